"""2D bool rasters (an organized frame's pixels): their 8-connected pieces, the pieces'
boxes, and dilation by a square, as scipy.ndimage gives them, without importing
scipy.ndimage's package (issue 39).

Importing scipy.ndimage runs its array-API layer (a wrapper per function for CuPy and
JAX) and all of its modules: ~15 ms of a cold `clear plan` on a loaded machine, for two
C functions clear calls on NumPy arrays. `label_8` and `boxes` call those C functions
(scipy.ndimage._ni_label, ._nd_image, with what scipy.ndimage.label and find_objects do
around them); clearcli/startup.py defers scipy.ndimage's package code
(DEFERRED_PACKAGES), so importing them runs none of it. A SciPy that moved them gets
the public functions. `dilate_square` is NumPy's: ORs of shifted copies, the same
cells as binary_dilation by a 3x3 square (or maximum_filter1d along both axes) to any
depth.
"""

from __future__ import annotations

from typing import Any

import numpy as np

_SQUARE = np.ones((3, 3), dtype=bool)  # 8-connectivity


def flat_step(offset: tuple[int, int], width: int) -> tuple[int, int]:
    """A pixel offset (rows down >= 0, columns right) as one step along a raster's flat
    pixels of ``width`` columns, and the column whose pixels that step carries to the
    wrong row (-1: none): a step right wraps from the last column to the next row's
    first, a step down-left from the first column to the row's own last. A pass over
    the flat image pairs every pixel with the one a step on, in one contiguous run;
    the pairs from that column are struck out, or let through (filters.py, edges.py,
    table.py `beyond_the_edge`)."""
    rows, cols = offset
    return rows * width + cols, (width - 1 if cols > 0 else 0 if cols < 0 else -1)


def _ndimage_c() -> tuple[Any, Any] | None:
    """(scipy.ndimage._ni_label, scipy.ndimage._nd_image), or None if SciPy moved them.
    `import a.b.c` binds the submodule itself: no attribute of the deferred package is
    asked for (a `from scipy.ndimage import _ni_label` would run its code)."""
    try:
        import scipy.ndimage._nd_image
        import scipy.ndimage._ni_label
    except ImportError:
        return None
    ni_label = scipy.ndimage._ni_label
    nd_image = scipy.ndimage._nd_image
    if not hasattr(ni_label, "_label") or not hasattr(nd_image, "find_objects"):
        return None
    return ni_label, nd_image


def label_8(grid: np.ndarray) -> tuple[np.ndarray, int]:
    """8-connected pieces of the 2D bool ``grid``: (labels (H, W) int32, n), 0 off the
    grid's cells, 1..n in raster order of each piece's first cell: scipy.ndimage.label
    with a 3x3 square structure, what it does for a 2D array of fewer than 2^31 cells."""
    c = _ndimage_c()
    if c is None or grid.ndim != 2 or grid.size >= 2**31 - 2:
        from scipy import ndimage

        labels, n = ndimage.label(grid, structure=_SQUARE)
        return labels, int(n)
    out = np.empty(grid.shape, dtype=np.int32)
    if grid.size == 0:
        return out, 0
    return out, int(c[0]._label(np.asarray(grid), _SQUARE, out))


def boxes(labels: np.ndarray, n: int) -> list[tuple[slice, ...] | None]:
    """Per label 1..``n`` of ``labels`` (`label_8`'s), the slices of its bounding box, None
    for a label with no cell: scipy.ndimage.find_objects(labels, n)."""
    c = _ndimage_c()
    if c is None:
        from scipy import ndimage

        found: list[tuple[slice, ...] | None] = ndimage.find_objects(labels, n)
        return found
    if n < 1:  # find_objects takes the array's maximum then: none of label_8's
        n = int(labels.max()) if labels.size else 0
    found = c[1].find_objects(np.asarray(labels), n)
    return found


def dilate_square(mask: np.ndarray, steps: int) -> np.ndarray:
    """The 2D bool ``mask`` dilated ``steps`` times by a 3x3 square (binary_dilation's
    ``iterations``, nothing beyond the raster's edge), i.e. every cell within Chebyshev
    distance ``steps`` of a set cell: along each axis in turn, a cell is set when one
    within ``steps`` of it is. Each axis by ORs of shifted bool copies, the reach
    doubling each time (a handful of byte-wide passes; the box sum by int32 cumulative
    sums it replaced cost 2-25 times more, issue 39)."""
    out = np.asarray(mask, dtype=bool)
    if steps <= 0:
        return out.copy()
    for axis in (0, 1):
        n = out.shape[axis]
        # ahead: each cell ORed with the (up to) `steps` cells after it along the axis
        ahead = _reach_ahead(out, min(steps, max(n - 1, 0)), axis)
        # a cell within `steps` of a set cell: ahead of itself, or ahead of the cell
        # `steps` before it (the first cell's, for the cells nearer the start than that)
        r = min(steps, n)
        out = ahead.copy()
        if axis == 0:
            if n > r:
                out[r:] |= ahead[:-r]
            out[1:r] |= ahead[:1]
        else:
            if n > r:
                out[:, r:] |= ahead[:, :-r]
            out[:, 1:r] |= ahead[:, :1]
    return out


def _reach_ahead(mask: np.ndarray, steps: int, axis: int) -> np.ndarray:
    """``mask`` (2D bool) with each cell ORed with the ``steps`` cells after it along
    ``axis`` (fewer at the raster's end): a reach of 1, 2, 4, ... cells in turn, the
    last step only what is left."""
    out = mask.copy()
    covered = 1  # cells each entry holds the OR of
    while covered < steps + 1:
        shift = min(covered, steps + 1 - covered)
        if axis == 0:
            out[:-shift] |= out[shift:]  # overlapping in place: NumPy reads a copy first
        else:
            out[:, :-shift] |= out[:, shift:]
        covered += shift
    return out
