"""Tests of clearcli/io/read.py."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers import shared_path
from helpers.io import _header

from clearcli.errors import SceneError
from clearcli.io.read import read_frame, require_finite


def test_all_nan_reads_but_require_finite_refuses(tmp_path: Path) -> None:
    path = tmp_path / "nan.pcd"
    path.write_bytes(_header(w=2, h=2) + np.full(12, np.nan, dtype="<f4").tobytes())
    frame = read_frame(path)
    assert frame.shape == (2, 2) and frame.finite_mask.sum() == 0
    with pytest.raises(SceneError, match="0 finite points of 4"):
        require_finite(frame)
    ok = read_frame(shared_path("mosd/test/test57.pcd"))
    assert require_finite(ok, min_points=1000) is ok
