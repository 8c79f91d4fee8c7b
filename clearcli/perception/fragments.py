"""Stage 3e (ours, not in the thesis): join the fragments of a face seen edge-on.

A face seen within a few degrees of edge-on steps centimetres in range from pixel to
pixel; the outlier filter (which wants neighbours within a range-scaled radius) keeps
only scattered strips of it, and each strip comes out as a small segment of its own,
touching nothing, a few millimetres from the object it belongs to. Such a FRAGMENT is a
segment smaller than LCCP's smallest segment (``min_segment_supervoxels`` seeds) with
no top face (no supervoxel within ``step_max_tilt_deg`` of level: a small object
standing apart has one) and no voxel adjacency to another segment. It joins the segment
of the nearest voxel outside it when that is within ``fragment_join_m``; farther away
it is left alone (the size filter drops it if it is tiny).
"""

from __future__ import annotations

import numpy as np

from clearcli.perception.context import RefineContext
from clearcli.perception.graph import dense_labels


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
    )


def join_fragments(
    seg_of_voxel: np.ndarray,
    voxel_centroids: np.ndarray,
    voxel_edges: np.ndarray,
    voxel_is_top: np.ndarray,
    max_fragment_voxels: int,
    max_gap_m: float,
) -> np.ndarray:
    """(V,) segment per voxel after joining fragments to their nearest segment."""
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
    joined = target >= 0
    out[joined[seg]] = target[seg[joined[seg]]]
    return dense_labels(out)


def _near_cells(centroids: np.ndarray, seeds: np.ndarray, reach_m: float) -> np.ndarray:
    """(V,) bool: voxels in the cell of one of the ``seeds`` (voxel indices), or in one
    of its 26 neighbours, on a grid of cells a little wider than ``reach_m``: every voxel
    within ``reach_m`` of a seed is among them."""
    cell = np.floor(centroids / (1.01 * reach_m)).astype(np.int64)  # 1 %: floor's rounding
    cell -= cell.min(axis=0) - 1  # one empty layer around so offsets never wrap
    dims = cell.max(axis=0) + 2
    packed = (cell[:, 0] * dims[1] + cell[:, 1]) * dims[2] + cell[:, 2]
    step = np.array([(dx * dims[1] + dy) * dims[2] + dz for dx in (-1, 0, 1) for dy in (-1, 0, 1) for dz in (-1, 0, 1)])
    near = np.unique(np.unique(packed[seeds])[:, None] + step[None, :])
    return np.isin(packed, near)
