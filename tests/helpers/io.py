"""Helpers that several test modules share (from the tests of io)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from clearcli.errors import ClearError, InputError
from clearcli.io.frames import Frame
from clearcli.io.read import read_frame


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and bool(np.array_equal(a, b, equal_nan=True))


def _small_frame(n_rows: int = 4, n_cols: int = 5, nan_rows: tuple[int, ...] = (2,)) -> Frame:
    """An organized frame with hand-chosen values, NaN pixels, colours and labels."""
    n = n_rows * n_cols
    idx = np.arange(n, dtype=np.float32)
    points = np.stack([idx * 0.01, -idx * 0.02, 0.5 + idx * 0.001], axis=1).astype(np.float32)
    for r in nan_rows:
        points[r] = np.nan
    colors = np.stack([idx % 256, (idx * 7) % 256, 255 - idx % 256], axis=1).astype(np.uint8)
    labels = (np.arange(n) % 3 * 10).astype(np.uint32)
    return Frame(
        points=points,
        colors=colors,
        shape=(n_rows, n_cols),
        fields={"label": labels},
        stamp_s=12.25,
        frame_id="cam",
        source="small",
    )


_HEADER = (
    "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n"
    "TYPE F F F\nCOUNT 1 1 1\nWIDTH {w}\nHEIGHT {h}\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {d}\n"
)


def _header(w: int = 3, h: int = 1, n: int | None = None, d: str = "binary") -> bytes:
    return _HEADER.format(w=w, h=h, n=w * h if n is None else n, d=d).encode()


def _one_line_error(path: Path, match: str, kind: type[ClearError] = InputError) -> str:
    with pytest.raises(kind, match=match) as info:
        read_frame(path)
    message = str(info.value)
    assert "\n" not in message and str(path) in message
    return message
