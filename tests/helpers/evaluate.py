"""Helpers that several test modules share (from the tests of evaluate)."""

from __future__ import annotations

import numpy as np


def _labels(*runs: tuple[int, int]) -> np.ndarray:
    """Concatenate (label, count) runs."""
    return np.concatenate([np.full(n, lab, dtype=np.int64) for lab, n in runs])
