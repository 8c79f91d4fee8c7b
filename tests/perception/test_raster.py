"""clearcli/perception/raster.py: 8-connected labels, their boxes and square dilation,
the same arrays scipy.ndimage's public functions give (which it replaces: issue 39)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from clearcli.perception import raster

_SQUARE = np.ones((3, 3), dtype=bool)


def _grids() -> list[np.ndarray]:
    rng = np.random.default_rng(3)
    grids = [rng.random((h, w)) < p for h, w, p in ((1, 1, 1.0), (7, 5, 0.4), (48, 64, 0.3), (120, 90, 0.55))]
    grids.append(np.zeros((6, 4), dtype=bool))
    grids.append(np.ones((5, 8), dtype=bool))
    grids.append((rng.random((60, 80)) < 0.4)[::2, 1::3])  # a strided view
    return grids


def test_label_8_by_hand() -> None:
    grid = np.array(
        [
            [1, 0, 0, 1],
            [0, 1, 0, 1],
            [0, 0, 0, 0],
            [1, 1, 0, 1],
        ],
        dtype=bool,
    )
    labels, n = raster.label_8(grid)
    # (0,0)-(1,1) touch at a corner: one piece; raster order of first cells: 1 at (0,0),
    # 2 at (0,3), 3 at (3,0), 4 at (3,3)
    assert n == 4 and labels.dtype == np.int32
    assert labels.tolist() == [[1, 0, 0, 2], [0, 1, 0, 2], [0, 0, 0, 0], [3, 3, 0, 4]]
    assert raster.boxes(labels, n) == [
        (slice(0, 2), slice(0, 2)),
        (slice(0, 2), slice(3, 4)),
        (slice(3, 4), slice(0, 2)),
        (slice(3, 4), slice(3, 4)),
    ]


@pytest.mark.parametrize("c_functions", [True, False])
def test_labels_and_boxes_are_ndimages(c_functions: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    if not c_functions:  # a SciPy that moved them: the public functions
        monkeypatch.setattr(raster, "_ndimage_c", lambda: None)
    for grid in _grids():
        labels, n = raster.label_8(grid)
        want, n_want = ndimage.label(grid, structure=_SQUARE)
        assert n == n_want and isinstance(n, int)
        assert labels.dtype == want.dtype and np.array_equal(labels, want)
        assert raster.boxes(labels, n) == ndimage.find_objects(want)
        assert raster.boxes(labels, 0) == ndimage.find_objects(want, 0)  # 0: up to the array's maximum


def test_a_missing_label_has_no_box() -> None:
    labels = np.array([[0, 3], [1, 0]], dtype=np.int32)
    assert raster.boxes(labels, 3) == [(slice(1, 2), slice(0, 1)), None, (slice(0, 1), slice(1, 2))]


def test_dilate_square_is_binary_dilation_and_maximum_filters() -> None:
    for grid in _grids():
        for steps in (0, 1, 3, 8):
            got = raster.dilate_square(grid, steps)
            if steps:
                assert np.array_equal(got, ndimage.binary_dilation(grid, _SQUARE, iterations=steps))
            else:
                assert np.array_equal(got, grid)
            # what clearcli/perception/exclude.py did: a running maximum down, then across
            size = 2 * steps + 1
            grown = ndimage.maximum_filter1d(
                ndimage.maximum_filter1d(grid.astype(np.uint8), size, axis=0), size, axis=1
            )
            assert np.array_equal(got, grown > 0)


def test_dilate_square_by_hand() -> None:
    mask = np.zeros((5, 6), dtype=bool)
    mask[0, 0] = True
    mask[4, 5] = True
    got = raster.dilate_square(mask, 1)
    want = np.zeros((5, 6), dtype=bool)
    want[0:2, 0:2] = True  # the corner's 3x3 square, cut by the edge
    want[3:5, 4:6] = True
    assert np.array_equal(got, want)
    # 4 steps: rows 0-4 of columns 0-4 from one corner, of columns 1-5 from the other
    assert raster.dilate_square(mask, 4).all() and raster.dilate_square(mask, 2).sum() == 9 + 9


def test_dilate_square_on_thin_and_small_rasters_and_long_reaches() -> None:
    # the doubling reach on rasters thinner than the steps (a row, a column, one cell,
    # none) and reaches that are no power of two, against maximum filters along both axes
    rng = np.random.default_rng(7)
    shapes = [(1, 1), (1, 9), (9, 1), (2, 3), (0, 4), (4, 0), (7, 13), (31, 17), (64, 5)]
    for shape in shapes:
        for share in (0.02, 0.2):
            grid = rng.random(shape) < share
            for steps in (1, 2, 3, 5, 6, 7, 12, 25, 40):
                got = raster.dilate_square(grid, steps)
                assert got.shape == grid.shape and got.dtype == bool
                if grid.size == 0:
                    continue
                size = 2 * steps + 1
                grown = ndimage.maximum_filter1d(
                    ndimage.maximum_filter1d(grid.astype(np.uint8), size, axis=0, mode="constant"),
                    size,
                    axis=1,
                    mode="constant",
                )
                assert np.array_equal(got, grown > 0), (shape, share, steps)


def test_dilate_square_reaches_exactly_steps_cells() -> None:
    # one cell in the middle of a 1 x 41 row: 5 steps set columns 15-25, no more
    row = np.zeros((1, 41), dtype=bool)
    row[0, 20] = True
    got = raster.dilate_square(row, 5)
    assert np.flatnonzero(got[0]).tolist() == list(range(15, 26))
    # and the input is left alone
    assert int(row.sum()) == 1


def test_flat_step_of_each_offset_by_hand() -> None:
    """On a raster 5 columns wide: right is 1 on (wrapping from column 4), down 5 (never
    wraps), down-right 6 (wrapping from column 4), down-left 4 (wrapping from column 0)."""
    from clearcli.perception.raster import flat_step

    assert flat_step((0, 1), 5) == (1, 4)
    assert flat_step((1, 0), 5) == (5, -1)
    assert flat_step((1, 1), 5) == (6, 4)
    assert flat_step((1, -1), 5) == (4, 0)
    # what wraps really lands in another row: pixel 4 (row 0, column 4) a step right is
    # pixel 5 (row 1, column 0); pixel 5 (row 1, column 0) down-left is pixel 9 (row 1)
    assert divmod(4 + flat_step((0, 1), 5)[0], 5) == (1, 0)
    assert divmod(5 + flat_step((1, -1), 5)[0], 5) == (1, 4)
