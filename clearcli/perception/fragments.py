"""Stage 3e (ours, not in the thesis): join the fragments of a face seen edge-on.

A face seen within a few degrees of edge-on steps centimetres in range from pixel to
pixel; the outlier filter (which wants neighbours within a range-scaled radius) keeps
only scattered strips of it, and each strip comes out as a small segment of its own,
touching nothing, a few millimetres from the object it belongs to. Such a FRAGMENT is a
segment smaller than LCCP's smallest segment (``min_segment_supervoxels`` seeds) with
no top face (no supervoxel within ``step_max_tilt_deg`` of level: a small object
standing apart has one) and no voxel adjacency to another segment. It joins the segment
of the nearest voxel outside it when that is within ``fragment_join_m``; farther away
it is left alone (the size filter drops it if it is tiny). A strip of one face is
flat (its voxels within ``fragment_max_thickness_m`` RMS of a plane) or has the colour
of the object beside it (within ``color_split_delta`` of the target's voxels near it):
a small object apart from the rest, with no level top (a ball, a deodorant lying in a
bin), is thicker than a strip and of its own colour, and is left alone. Without colour
a thick fragment joins as before.
"""

from __future__ import annotations

import numpy as np

from clearcli.perception.context import RefineContext
from clearcli.perception.graph import dense_labels

# _near_cells' grid as a dense array up to this many cells (1 MB of flags); a wider
# cloud's cells are looked up by np.isin instead
_MAX_GRID_CELLS = 1_000_000


def rejoin_fragments(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
    """The stage: `join_fragments` on the frame's voxels; a fragment is smaller than
    LCCP's smallest segment in voxels."""
    return join_fragments(
        seg_of_voxel,
        ctx.vox.centroids,
        ctx.vox.edges,
        ctx.voxel_is_top,
        ctx.size.min_segment_voxels,
        ctx.settings.fragment_join_m,
        ctx.settings.fragment_max_thickness_m,
        ctx.voxel_lab,
        ctx.settings.color_split_delta,
    )


def join_fragments(
    seg_of_voxel: np.ndarray,
    voxel_centroids: np.ndarray,
    voxel_edges: np.ndarray,
    voxel_is_top: np.ndarray,
    max_fragment_voxels: int,
    max_gap_m: float,
    max_thickness_m: float = np.inf,
    voxel_lab: np.ndarray | None = None,
    max_color_delta: float = np.inf,
) -> np.ndarray:
    """(V,) segment per voxel after joining fragments to their nearest segment. With
    ``voxel_lab`` (V, 3), a fragment more than ``max_thickness_m`` thick (`thickness`)
    whose mean colour is ``max_color_delta`` or more (CIE76) from its target's voxels
    within twice ``max_gap_m`` of it stays apart."""
    from scipy.spatial import cKDTree

    seg = np.asarray(seg_of_voxel, dtype=np.int64)
    n_seg = int(seg.max()) + 1 if seg.size else 0
    if n_seg < 2:
        return seg
    size = np.bincount(seg, minlength=n_seg)
    has_top = np.bincount(seg, weights=voxel_is_top.astype(np.float64), minlength=n_seg) > 0
    a, b = seg[voxel_edges[:, 0]], seg[voxel_edges[:, 1]]
    touches = np.zeros(n_seg, dtype=bool)
    touches[a[a != b]] = True
    touches[b[a != b]] = True
    fragment = (size < max_fragment_voxels) & ~has_top & ~touches
    if not fragment.any() or fragment.all():
        return seg
    is_frag = fragment[seg]
    frag_vox = np.flatnonzero(is_frag)
    # the tree holds only the other voxels that can lie within max_gap_m of a fragment:
    # those in the fragments' cells of the grid of cells a little wider than max_gap_m,
    # or in a neighbouring cell (a few hundred, not the whole table's voxels)
    rest = ~is_frag & _near_cells(voxel_centroids, frag_vox, max_gap_m)
    out = seg.copy()
    if not rest.any():
        return dense_labels(out)
    tree = cKDTree(np.compress(rest, voxel_centroids, axis=0))  # rows by a mask: compress is faster
    rest_seg = seg[rest]
    dist, nearest = tree.query(voxel_centroids[frag_vox], distance_upper_bound=max_gap_m)
    found = np.isfinite(dist)
    # each fragment to the segment of its voxel nearest to any other segment
    target = np.full(n_seg, -1, dtype=np.int64)
    best = np.full(n_seg, np.inf)
    for v, d, k in zip(frag_vox[found].tolist(), dist[found].tolist(), nearest[found].tolist()):
        f = seg[v]
        if d < best[f]:
            best[f], target[f] = d, rest_seg[k]
    if voxel_lab is not None and np.isfinite(max_thickness_m):
        target = _apart_by_colour(seg, voxel_centroids, voxel_lab, target, max_thickness_m, max_color_delta, max_gap_m)
    joined = target >= 0
    out[joined[seg]] = target[seg[joined[seg]]]
    return dense_labels(out)


def _apart_by_colour(
    seg: np.ndarray,
    centroids: np.ndarray,
    voxel_lab: np.ndarray,
    target: np.ndarray,
    max_thickness_m: float,
    max_color_delta: float,
    max_gap_m: float,
) -> np.ndarray:
    """``target`` with -1 for each joining fragment thicker than ``max_thickness_m``
    whose mean colour differs by ``max_color_delta`` or more from that of its target's
    voxels within 2 ``max_gap_m`` of it (the object's side it would join: a printed
    box's other faces say nothing)."""
    from scipy.spatial import cKDTree

    n_seg = target.size
    thick = (target >= 0) & (thickness(seg, centroids, n_seg, target >= 0) > max_thickness_m)
    out = target.copy()
    for f in np.flatnonzero(thick).tolist():
        mine = seg == f
        theirs = np.flatnonzero(seg == target[f])
        d, _ = cKDTree(centroids[mine]).query(centroids[theirs], distance_upper_bound=2 * max_gap_m)
        near = theirs[np.isfinite(d)]
        if near.size == 0:
            continue
        delta = float(np.linalg.norm(voxel_lab[mine].mean(axis=0) - voxel_lab[near].mean(axis=0)))
        if delta >= max_color_delta:
            out[f] = -1
    return out


def thickness(seg: np.ndarray, centroids: np.ndarray, n_seg: int, which: np.ndarray) -> np.ndarray:
    """(n_seg,) RMS distance (m) of each segment's voxels from their best-fitting plane
    (the square root of their covariance's smallest eigenvalue), for the segments
    ``which`` flags; the others 0."""
    out = np.zeros(n_seg)
    picked = which[seg]
    s = seg[picked]
    p = centroids[picked]
    count = np.bincount(s, minlength=n_seg).astype(np.float64)
    rows = np.flatnonzero(which & (count > 0))
    if rows.size == 0:
        return out
    mean = np.zeros((n_seg, 3))
    for k in range(3):
        mean[:, k] = np.bincount(s, weights=p[:, k], minlength=n_seg)
    mean[rows] /= count[rows, None]
    c = p - mean[s]  # about each segment's own mean: no cancellation far from the camera
    cov = np.zeros((n_seg, 3, 3))
    for i in range(3):
        for j in range(i, 3):
            cov[:, i, j] = cov[:, j, i] = np.bincount(s, weights=c[:, i] * c[:, j], minlength=n_seg)
    cov[rows] /= count[rows, None, None]
    out[rows] = np.sqrt(np.maximum(np.linalg.eigvalsh(cov[rows])[:, 0], 0.0))
    return out


def _near_cells(centroids: np.ndarray, seeds: np.ndarray, reach_m: float) -> np.ndarray:
    """(V,) bool: voxels in the cell of one of the ``seeds`` (voxel indices), or in one
    of its 26 neighbours, on a grid of cells a little wider than ``reach_m``: every voxel
    within ``reach_m`` of a seed is among them."""
    # the cells (1 % wider than the reach: floor's rounding) one coordinate at a time:
    # reductions over axis 0 of a (V, 3) array are several times slower than over a
    # column (the same numbers)
    cols = [np.floor(centroids[:, k] / (1.01 * reach_m)).astype(np.int64) for k in range(3)]
    cols = [c - (int(c.min()) - 1) for c in cols]  # one empty layer around so offsets never wrap
    dims = [int(c.max()) + 2 for c in cols]
    packed = (cols[0] * dims[1] + cols[1]) * dims[2] + cols[2]
    step = np.array([(dx * dims[1] + dy) * dims[2] + dz for dx in (-1, 0, 1) for dy in (-1, 0, 1) for dz in (-1, 0, 1)])
    near = np.unique(packed[seeds])[:, None] + step[None, :]
    n_cells = dims[0] * dims[1] * dims[2]
    if n_cells <= _MAX_GRID_CELLS:
        # a table's grid is small: the near cells marked in a dense grid and read by
        # index, not np.isin's sort of every voxel's cell
        marked = np.zeros(n_cells, dtype=bool)
        marked[near.ravel()] = True
        return marked[packed]
    return np.isin(packed, np.unique(near))
