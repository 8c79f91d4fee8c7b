"""Rounding of the numbers in JSON documents: one rule for every schema.

Coordinates, poses and lengths are rounded to 6 decimals (a micrometre: far below any
sensor's noise, and short documents); per-stage timings to 4 (0.1 ms). NumPy's rounding
(round half to even on the scaled value) is used throughout so that a value rounds the
same way in every document that carries it.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

DIGITS = 6
TIMING_DIGITS = 4


def rounded(a: Any, digits: int = DIGITS) -> Any:
    """A number, vector or matrix (anything NumPy reads as floats) as rounded plain
    Python floats in nested lists."""
    return np.round(np.asarray(a, dtype=float), digits).tolist()


def timings(t: Mapping[str, float], digits: int = TIMING_DIGITS) -> dict[str, float]:
    return {k: round(float(v), digits) for k, v in t.items()}
