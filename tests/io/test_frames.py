"""The Frame value's derived properties (clearcli/io/frames.py)."""

from __future__ import annotations

import numpy as np
import pytest

from clearcli.io.frames import Frame


@pytest.mark.parametrize(
    "shape, n, grid",
    [
        ((2, 3), 6, (2, 3)),  # one point per pixel, in row order: a pixel grid
        ((1, 6), 6, None),  # a single row: PCL's layout of an unorganized cloud
        ((2, 3), 5, None),  # a shape that does not hold the points
        (None, 6, None),  # unorganized
    ],
)
def test_the_pixel_grid_is_the_shape_only_when_it_holds_the_points(
    shape: tuple[int, int] | None, n: int, grid: tuple[int, int] | None
) -> None:
    frame = Frame(np.zeros((n, 3), dtype=np.float32), shape=shape)
    assert frame.grid == grid
    assert frame.is_organized == (shape is not None and shape[0] > 1)
