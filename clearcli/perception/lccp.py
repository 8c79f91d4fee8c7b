"""Stage 3b: Locally Convex Connected Patches (Stein et al., CVPR 2014), vectorised.

Every supervoxel adjacency is classified convex or concave from the two patches'
centroids and normals; segments are the connected components over the convex ones;
segments of fewer than ``min_segment_supervoxels`` supervoxels then join their largest
neighbouring segment (edges where normals are smoothed over are the usual source).

Convexity of a connection (x1, n1) - (x2, n2), d = x1 - x2, alpha = angle(n1, n2):
- convex when angle(d, n1) - angle(d, n2) <= 0 (the surfaces open away from each other),
  else accepted only when alpha is under the concavity tolerance;
- sanity criterion: rejected when the line joining the centroids is nearly parallel to
  n1 x n2 (within 60 deg / (1 + exp(-0.25 (alpha - 25 deg)))): convexity is undefined
  for such a pair (a step, or two patches side by side);
- smoothness check: rejected when the patches are offset along their normals by more
  than |n1 x n2| * seed + smoothness_threshold * voxel (a step between parallel faces).
  With the voxels at hand, a pair whose offset lies within smoothness_threshold * voxel
  of that allowance is decided at its boundary instead (`boundary_steps_m`): one voxel
  joining or leaving a supervoxel of a few dozen moves its centroid and turns its normal
  enough to move the centroids' offset by a few tenths of a millimetre (0.33 mm on a
  pair of gqcnn_primesense_4 whose margin was 0.02 mm: a micrometre's move of the points
  split it), while the step between the voxels that touch across the boundary, a median
  over the pairs, moves by a few hundredths (issue 37).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clearcli.perception.graph import components, dense_labels
from clearcli.perception.size import SegmentSize
from clearcli.perception.supervoxels import Supervoxels, VoxelCloud
from clearcli.settings.segment import SegmentSettings


def _angle_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise angle between vectors, degrees (0 for a zero vector)."""
    na = np.linalg.norm(a, axis=1)
    nb = np.linalg.norm(b, axis=1)
    cos = np.einsum("ij,ij->i", a, b) / np.maximum(na * nb, 1e-12)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def boundary_steps_m(sv: Supervoxels, vox: VoxelCloud, rows: np.ndarray) -> np.ndarray:
    """(len(rows),) for the supervoxel adjacencies ``sv.edges[rows]``: the step between
    the two patches where they touch, metres. Over the voxel pairs adjacent across the
    boundary (``vox.edges`` joining a voxel of one to a voxel of the other), each pair's
    offset along the patches' mean normal less what the normals' tilt explains over the
    pair's distance (|n1 x n2| |c_u - c_v|); the median of those (NaN: no such pair)."""
    out = np.full(rows.size, np.nan)
    if rows.size == 0 or vox.edges.shape[0] == 0:
        return out
    e = sv.edges[rows]
    n_sv = np.int64(sv.centroids.shape[0])
    label = sv.voxel_label
    a, b = label[vox.edges[:, 0]], label[vox.edges[:, 1]]
    key_v = np.minimum(a, b).astype(np.int64) * n_sv + np.maximum(a, b)
    key_e = np.minimum(e[:, 0], e[:, 1]).astype(np.int64) * n_sv + np.maximum(e[:, 0], e[:, 1])
    order = np.argsort(key_e, kind="stable")
    sorted_keys = key_e[order]
    pos = np.minimum(np.searchsorted(sorted_keys, key_v), sorted_keys.size - 1)
    hit = (sorted_keys[pos] == key_v) & (a != b)
    if not hit.any():
        return out
    which = order[pos[hit]]  # the row of ``rows`` each crossing pair belongs to
    pairs = vox.edges[hit]
    n1, n2 = sv.normals[e[:, 0]], sv.normals[e[:, 1]]
    mean_n = n1 + n2
    norm = np.linalg.norm(mean_n, axis=1)
    # opposite normals have no mean: n1 alone (such a pair is concave anyway)
    mean_n = np.where(norm[:, None] > 1e-9, mean_n / np.maximum(norm, 1e-9)[:, None], n1)
    tilt = np.linalg.norm(np.cross(n1, n2), axis=1)
    diff = vox.centroids[pairs[:, 0]] - vox.centroids[pairs[:, 1]]
    step = np.abs(np.einsum("ij,ij->i", diff, mean_n[which])) - tilt[which] * np.linalg.norm(diff, axis=1)
    # the median per row: the steps sorted within each row (one lexsort), the middle one
    # (the mean of the middle two for an even count), as np.median takes it
    srt = np.lexsort((step, which))
    step, which = step[srt], which[srt]
    count = np.bincount(which, minlength=rows.size)
    first = np.cumsum(count) - count
    has = count > 0
    lo = step[first[has] + (count[has] - 1) // 2]
    hi = step[first[has] + count[has] // 2]
    out[has] = 0.5 * (lo + hi)
    return out


@dataclass(frozen=True, eq=False)
class EdgeShape:
    """What `convex_edges` reads of each supervoxel adjacency's two patches before the
    colour cue and the boundaries, for one ``sv``, ``settings`` and ``size``
    (`edge_shape`): `RefineContext.sv_edge_shape` works it out once a frame for LCCP,
    the planar cuts and the colour splits, which judge the same adjacencies (issue 39)."""

    normal_angle: np.ndarray  # (A,) degrees between the two normals
    convex: np.ndarray  # (A,) bool: angle(d, n1) - angle(d, n2) <= 0
    offset_m: np.ndarray | None  # (A,) the smoothness check's offset less its allowance; None: the check is off
    insane: np.ndarray | None  # (A,) bool: fails the sanity criterion; None: the criterion is off


def edge_shape(sv: Supervoxels, settings: SegmentSettings, size: SegmentSize | None = None) -> EdgeShape:
    """`EdgeShape` of ``sv.edges`` (``size``: as for `convex_edges`)."""
    e = sv.edges
    size = size if size is not None else SegmentSize.of(settings)
    x1, x2 = sv.centroids[e[:, 0]], sv.centroids[e[:, 1]]
    n1, n2 = sv.normals[e[:, 0]], sv.normals[e[:, 1]]
    d = x1 - x2  # target -> source, the reference direction
    normal_angle = _angle_deg(n1, n2)
    ncross = np.cross(n1, n2)
    offset_m = None
    if settings.smoothness_check:
        expected = np.linalg.norm(ncross, axis=1) * size.seed_m
        p1 = np.abs(np.einsum("ij,ij->i", d, n1))
        p2 = np.abs(np.einsum("ij,ij->i", -d, n2))
        offset_m = np.minimum(p1, p2) - expected  # against the allowance: <= tolerance_m passes
    convex = _angle_deg(d, n1) - _angle_deg(d, n2) <= 0
    insane = None
    if settings.sanity_criterion:
        inter = _angle_deg(ncross, d)
        min_inter = np.minimum(inter, 180.0 - inter)
        thresh = 60.0 / (1.0 + np.exp(-0.25 * (normal_angle - 25.0)))
        insane = min_inter < thresh
    return EdgeShape(normal_angle, convex, offset_m, insane)


def convex_edges(
    sv: Supervoxels,
    settings: SegmentSettings,
    size: SegmentSize | None = None,
    sv_lab: np.ndarray | None = None,
    vox: VoxelCloud | None = None,
    shape: EdgeShape | None = None,
) -> np.ndarray:
    """(A,) bool: which supervoxel adjacencies are convex (may be merged). ``size``: the
    frame's seed and voxel (`SegmentSize.of(settings)` when None); ``sv_lab`` (S, 3):
    each supervoxel's CIELAB colour, when the frame's colour is usable; ``vox``: the
    voxels ``sv`` was grown on, when at hand: the smoothness check of a pair near its
    allowance is then decided at the pair's boundary (module docstring); ``shape``:
    `edge_shape` of these ``sv``, ``settings`` and ``size``, when the caller has it."""
    e = sv.edges
    if e.shape[0] == 0:
        return np.zeros(0, dtype=bool)
    size = size if size is not None else SegmentSize.of(settings)
    shape = shape if shape is not None else edge_shape(sv, settings, size)
    ok = np.ones(e.shape[0], dtype=bool)
    if shape.offset_m is not None:
        offset_m = shape.offset_m
        tolerance_m = settings.smoothness_threshold * size.voxel_m
        smooth = offset_m <= tolerance_m
        if vox is not None and tolerance_m > 0:
            # near the allowance the centroids' offset is as much the supervoxels' make-up
            # as the surface: the step where the two touch decides (the same tolerance)
            near = np.flatnonzero(np.abs(offset_m - tolerance_m) <= tolerance_m)
            step_m = boundary_steps_m(sv, vox, near)
            seen = ~np.isnan(step_m)
            smooth[near[seen]] = step_m[seen] <= tolerance_m
        ok &= smooth
    tolerance_deg = np.full(e.shape[0], settings.concavity_tolerance_deg)
    if sv_lab is not None and settings.lccp_color_delta > 0:
        # two touching objects of different colours often meet in a shallow concave
        # seam the tolerance accepts (a tin against a box); one object's concave
        # patches (a mug's inside, a bowl) are mostly of one colour, and a print on a
        # flat face is neither concave nor convex, so only a small tolerance there
        differ = np.linalg.norm(sv_lab[e[:, 0]] - sv_lab[e[:, 1]], axis=1) >= settings.lccp_color_delta
        tolerance_deg[differ] = min(settings.lccp_color_tolerance_deg, settings.concavity_tolerance_deg)
    is_convex = shape.convex | (shape.normal_angle < tolerance_deg)
    if shape.insane is not None:
        is_convex &= ~shape.insane
    return ok & is_convex


def lccp_segments(
    sv: Supervoxels,
    settings: SegmentSettings,
    sv_low_m: np.ndarray | None = None,
    sv_high_m: np.ndarray | None = None,
    up: np.ndarray | None = None,
    size: SegmentSize | None = None,
    sv_lab: np.ndarray | None = None,
    vox: VoxelCloud | None = None,
    shape: EdgeShape | None = None,
) -> np.ndarray:
    """(S,) segment index of every supervoxel, 0..G-1; ``size``: the frame's sizes
    (`SegmentSize.of(settings)` when None); ``sv_lab``, ``vox``, ``shape``: as for
    `convex_edges`.

    With ``sv_low_m`` and ``sv_high_m`` (S,), the heights above the table of each
    supervoxel's lowest and highest voxel, and ``up``, the table's normal: a small
    segment that stands on the table (reaches within ``standing_max_m`` of it), has a
    top face of its own (a supervoxel within ``step_max_tilt_deg`` of level) and a top
    at another height than every segment it touches (by ``step_min_m``: a piece of a
    box's top and front cut off by an object standing on the box is at the box's
    height) is a whole small object, not a piece of a larger one, and keeps its own
    segment when it holds at least ``min_object_area_m2`` of surface."""
    n_sv = sv.centroids.shape[0]
    if n_sv == 0:
        return np.zeros(0, dtype=np.int64)
    size = size if size is not None else SegmentSize.of(settings)
    convex = convex_edges(sv, settings, size, sv_lab, vox, shape)
    e = np.compress(convex, sv.edges, axis=0)  # rows by a mask: compress is several times faster
    seg = components(n_sv, e)
    # "small" also by area: the connectivity step of the supervoxels can leave a small
    # patch in several pieces, which would count as several supervoxels
    keep: np.ndarray | None = None
    if sv_low_m is not None and sv_high_m is not None and up is not None and settings.keep_standing_small:
        n_seg = int(seg.max()) + 1
        top = np.abs(sv.normals @ (up / np.linalg.norm(up))) >= np.cos(np.radians(settings.step_max_tilt_deg))
        low = np.full(n_seg, np.inf)
        np.minimum.at(low, seg, sv_low_m)
        high = np.full(n_seg, -np.inf)
        np.maximum.at(high, seg, sv_high_m)
        has_top = np.bincount(seg, weights=top.astype(np.float64), minlength=n_seg) > 0
        big = size.holds_object_area(np.bincount(seg, weights=sv.n_voxels, minlength=n_seg))
        keep = (low <= settings.standing_max_m) & has_top & big
        a, b = seg[sv.edges[:, 0]], seg[sv.edges[:, 1]]
        level = (a != b) & (np.abs(high[a] - high[b]) < settings.step_min_m)
        keep[a[level]] = False
        keep[b[level]] = False
    return merge_small_segments(seg, sv.edges, size.min_segment_supervoxels, sv.n_voxels, size.min_segment_voxels, keep)


def join_pairs(seg: np.ndarray, pairs: list[tuple[int, int]] | np.ndarray, n_seg: int) -> np.ndarray:
    """``seg`` (labels 0..n_seg-1) with every pair of segments in ``pairs`` joined (and
    what they chain to), renumbered 0..G-1 in order of first label."""
    p = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    comp = components(n_seg, p)
    return dense_labels(comp[seg])


def rejoin_pieces(
    seg: np.ndarray,
    edges: np.ndarray,
    min_size: int,
    sizes: np.ndarray | None = None,
    min_voxels: int = 0,
) -> np.ndarray:
    """After a cut: every segment of ``seg`` split into its connected pieces over
    ``edges``, and small pieces joined to their largest neighbour (`merge_small_segments`)."""
    keep = seg[edges[:, 0]] == seg[edges[:, 1]]
    # rows by a mask: np.compress, several times faster than boolean indexing of rows
    pieces = components(seg.size, np.compress(keep, edges, axis=0)).astype(np.int64)
    return merge_small_segments(pieces, edges, min_size, sizes, min_voxels)


def merge_small_segments(
    seg: np.ndarray,
    sv_edges: np.ndarray,
    min_size: int,
    sv_voxels: np.ndarray | None = None,
    min_voxels: int = 0,
    keep: np.ndarray | None = None,
) -> np.ndarray:
    """Segments with fewer than ``min_size`` supervoxels (or fewer than ``min_voxels``
    voxels) join their largest adjacent segment (PCL's rule), smallest first; isolated
    small segments stay, and so do those flagged in ``keep`` (G,)."""
    seg = seg.copy()
    if (min_size <= 1 and min_voxels <= 0) or sv_edges.shape[0] == 0:
        return dense_labels(seg)
    n_seg = int(seg.max()) + 1
    # Python lists, not arrays: the loop below reads and writes them one element at a
    # time (NumPy's scalar indexing cost most of a call); same values, same arithmetic
    parent = list(range(n_seg))
    size = np.bincount(seg, minlength=n_seg).tolist()
    vox = (
        np.bincount(seg, weights=sv_voxels, minlength=n_seg) if sv_voxels is not None else np.asarray(size, dtype=float)
    ).tolist()
    kept = keep.tolist() if keep is not None else [False] * n_seg

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    # segment adjacency (loops below run over segments, a few hundred at most); the
    # pairs packed into one integer key: the same sorted pairs as unique rows, no row sort
    a, b = seg[sv_edges[:, 0]], seg[sv_edges[:, 1]]
    cross = a != b
    key = np.unique(np.minimum(a[cross], b[cross]) * n_seg + np.maximum(a[cross], b[cross]))
    neighbours: dict[int, set[int]] = {}
    for s, t in zip((key // n_seg).tolist(), (key % n_seg).tolist(), strict=True):
        neighbours.setdefault(s, set()).add(t)
        neighbours.setdefault(t, set()).add(s)
    for s in np.argsort(np.asarray(size), kind="stable").tolist():
        if (size[s] >= min_size and vox[s] >= min_voxels) or root(s) != s or kept[s]:
            continue
        roots = {root(t) for t in neighbours.get(s, ())} - {s}
        if not roots:
            continue
        target = max(roots, key=lambda r: (size[r], -r))
        parent[s] = target
        size[target] += size[s]
        vox[target] += vox[s]
        for t in neighbours.get(s, ()):
            neighbours.setdefault(target, set()).add(t)
    final = np.array([root(s) for s in range(n_seg)])[seg]
    return dense_labels(final)
