"""Stage 3d (ours, not in the thesis): join the inside and the outside of a container.

A bowl, mug or open can shows the camera its outer wall and, over the rim, its inner
wall. The inner wall is concave, so LCCP keeps the two apart. They touch only along the
rim, which is the top of both. So two touching segments are joined when nearly all of
their contact lies within ``rim_tolerance_m`` of the top of each:
- a box on a box touches the lower one at the lower one's top but the upper one's
  bottom: kept apart (unless the upper one is flatter than the tolerance);
- objects side by side touch down a vertical seam: kept apart;
- tall objects side by side, whose lower parts hide each other, touch along their top
  edges: a contact where either voxel lies on a top face (``voxel_is_top``: a
  horizontal patch) is not a rim, which is two walls meeting.
"""

from __future__ import annotations

import numpy as np

from clearcli.perception.context import RefineContext
from clearcli.perception.lccp import join_pairs

# share of the contact (voxel adjacencies) that must be near both tops
_MIN_SHARE_AT_TOP = 0.9
_MIN_CONTACTS = 5
# _near_another_segment's grid as a dense array up to this many cells (8 MB a grid of
# int64); a wider cloud's cells are searched for instead
_MAX_GRID_CELLS = 1_000_000


def join_rims(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
    """The stage: `merge_rims` on the frame's voxels, top faces from the supervoxels."""
    s = ctx.settings
    return merge_rims(
        seg_of_voxel,
        ctx.vox.centroids,
        ctx.voxel_height,
        s.rim_tolerance_m,
        s.rim_contact_m,
        voxel_is_top=ctx.voxel_is_top,
    )


def merge_rims(
    seg_of_voxel: np.ndarray,
    voxel_centroids: np.ndarray,
    voxel_height: np.ndarray,
    tolerance_m: float,
    contact_m: float,
    voxel_is_top: np.ndarray | None = None,
) -> np.ndarray:
    """(V,) segment per voxel after joining segments that touch only along their tops.

    "Touch": voxels of the two within ``contact_m`` (a thin wall seen edge-on at the
    sides of a container loses its depth, so the two walls need not be adjacent)."""
    from scipy.spatial import cKDTree

    n_seg = int(seg_of_voxel.max()) + 1 if seg_of_voxel.size else 0
    if n_seg < 2:
        return seg_of_voxel
    # only voxels with another segment in their cells' neighbourhood can touch one
    near = np.flatnonzero(_near_another_segment(seg_of_voxel, voxel_centroids, contact_m, n_seg))
    if near.size == 0:
        return seg_of_voxel
    # the pairs across segments, searched between each two segments' trees: nine in ten
    # pairs of one search over all near voxels lay within one segment. The same pairs
    # (both searches keep a distance <= contact_m); their order does not matter below
    # (counts per pair of segments)
    seg_near = seg_of_voxel[near]
    by_seg = near[np.argsort(seg_near, kind="stable")]
    bounds = np.searchsorted(seg_of_voxel[by_seg], np.arange(n_seg + 1))
    present = np.flatnonzero(bounds[1:] > bounds[:-1])
    pts = np.take(voxel_centroids, by_seg, axis=0)  # rows by index: take is several times faster than a[idx]
    lo_box = np.minimum.reduceat(pts, bounds[present], axis=0)
    hi_box = np.maximum.reduceat(pts, bounds[present], axis=0)
    # the two segments' boxes within contact_m (with a margin: the search decides)
    gap = np.maximum(0.0, np.maximum(lo_box[:, None, :] - hi_box[None, :, :], lo_box[None, :, :] - hi_box[:, None, :]))
    close = np.sqrt((gap**2).sum(axis=2)) <= contact_m * (1 + 1e-6) + 1e-9
    trees: dict[int, cKDTree] = {}
    found = []
    for i, j in zip(*np.nonzero(np.triu(close, k=1)), strict=True):
        sa, sb = int(present[i]), int(present[j])
        for s in (sa, sb):
            if s not in trees:
                # unbalanced, uncompacted (sliding midpoint splits): built a quarter
                # faster and searched a fifth faster here; the same pairs and distances
                # (each pair's distance is computed alike, whatever the tree)
                trees[s] = cKDTree(pts[bounds[s] : bounds[s + 1]], balanced_tree=False, compact_nodes=False)
        m = trees[sa].sparse_distance_matrix(trees[sb], contact_m, output_type="ndarray")
        if m.size:
            found.append(np.stack([by_seg[bounds[sa] + m["i"]], by_seg[bounds[sb] + m["j"]]], axis=1))
    if not found:
        return seg_of_voxel
    edges_cross = np.concatenate(found)
    ea, eb = seg_of_voxel[edges_cross[:, 0]], seg_of_voxel[edges_cross[:, 1]]
    top = np.full(n_seg, -np.inf)
    np.maximum.at(top, seg_of_voxel, voxel_height)
    ha, hb = voxel_height[edges_cross[:, 0]], voxel_height[edges_cross[:, 1]]
    h_contact = 0.5 * (ha + hb)
    lo, hi = np.minimum(ea, eb), np.maximum(ea, eb)
    at_top = (h_contact >= top[lo] - tolerance_m) & (h_contact >= top[hi] - tolerance_m)
    if voxel_is_top is not None:
        at_top &= ~(voxel_is_top[edges_cross[:, 0]] | voxel_is_top[edges_cross[:, 1]])
    key = lo * n_seg + hi
    uniq, inv = np.unique(key, return_inverse=True)
    n_contacts = np.bincount(inv)
    n_top = np.bincount(inv, weights=at_top.astype(np.float64))
    join = (n_contacts >= _MIN_CONTACTS) & (n_top >= _MIN_SHARE_AT_TOP * n_contacts)
    return join_pairs(seg_of_voxel, np.stack([uniq[join] // n_seg, uniq[join] % n_seg], axis=1), n_seg)


def _near_another_segment(
    seg_of_voxel: np.ndarray, voxel_centroids: np.ndarray, reach_m: float, n_seg: int
) -> np.ndarray:
    """(V,) bool: voxels whose cell, or one of its 26 neighbours, on a grid of cells a
    little wider than ``reach_m`` holds a voxel of another segment. Two voxels within
    ``reach_m`` lie in the same or neighbouring cells, so every pair of two segments'
    voxels within ``reach_m`` has both ends here: the pairs search needs only these
    (the same pairs across segments, a fraction of the voxels on a cluttered table)."""
    if not reach_m > 0.0:  # rim_contact_m = 0: no two voxels touch, and no grid of 0 m cells
        return np.zeros(seg_of_voxel.shape[0], dtype=bool)
    # the cells (1 % wider than the reach: floor's rounding) one coordinate at a time:
    # reductions over axis 0 of a (V, 3) array are several times slower than over a
    # column (the same numbers)
    cols = [np.floor(voxel_centroids[:, k] / (1.01 * reach_m)).astype(np.int64) for k in range(3)]
    cols = [c - (int(c.min()) - 1) for c in cols]  # one empty layer around so offsets never wrap
    dims = [int(c.max()) + 2 for c in cols]
    packed = (cols[0] * dims[1] + cols[1]) * dims[2] + cols[2]
    # ... over the cell and its 26 neighbours, all 27 offsets in one gather or search
    step = np.array([(dx * dims[1] + dy) * dims[2] + dz for dx in (-1, 0, 1) for dy in (-1, 0, 1) for dz in (-1, 0, 1)])
    n_cells = dims[0] * dims[1] * dims[2]
    if n_cells <= _MAX_GRID_CELLS:
        # a table's grid is small (tens of thousands of cells): each cell's lowest and
        # highest segment in a dense grid, filled by ufunc.at (minima and maxima: the
        # same in any order; no sort of the voxels), read at the 27 offsets by index
        # and back at each voxel's cell (empty cells hold none: n_seg and -1)
        lo_grid = np.full(n_cells, n_seg, dtype=np.int64)
        hi_grid = np.full(n_cells, -1, dtype=np.int64)
        np.minimum.at(lo_grid, packed, seg_of_voxel)
        np.maximum.at(hi_grid, packed, seg_of_voxel)
        occupied = np.flatnonzero(hi_grid >= 0)
        lo_near = lo_grid[occupied[None, :] + step[:, None]].min(axis=0)
        hi_near = hi_grid[occupied[None, :] + step[:, None]].max(axis=0)
        other = np.zeros(n_cells, dtype=bool)
        other[occupied] = lo_near != hi_near
        return other[packed]
    cell_seg = np.unique(packed * n_seg + seg_of_voxel)  # (cell, segment) pairs, sorted
    cell_of = cell_seg // n_seg  # sorted: each cell's first pair where it changes
    first = np.flatnonzero(np.r_[True, cell_of[1:] != cell_of[:-1]])
    cells = cell_of[first]
    seg = cell_seg % n_seg
    lo = seg[first]  # each cell's lowest and highest segment
    hi = seg[np.r_[first[1:], seg.size] - 1]
    # each row of targets is sorted, as the cells are; the cell itself is always found
    target = cells[None, :] + step[:, None]
    pos = np.minimum(np.searchsorted(cells, target), cells.size - 1)
    hit = cells[pos] == target
    lo_near = np.where(hit, lo[pos], n_seg).min(axis=0)
    hi_near = np.where(hit, hi[pos], -1).max(axis=0)
    return (lo_near != hi_near)[np.searchsorted(cells, packed)]
