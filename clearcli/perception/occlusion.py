"""Stage 3c (ours, not in the thesis): join the pieces of an object that a nearer object
cuts in two.

LCCP joins only adjacent patches, so an object seen on both sides of a nearer one comes
out as two segments (mOSD's "occluded objects" frames). Two segments are joined when
- they do not touch, they reach the same height above the table, and each has a supervoxel on one common plane with the other's
  (parallel normals, each centroid on the other's plane; a box's top face in two
  pieces), the closest such pair at most ``occlusion_max_gap_m`` apart,
- and the camera cannot see the gap: along the straight line between those two patches
  the measured depth is in front of the line (something hides it) at most pixels that
  have depth, and almost never behind it (which would mean we see through the gap),
- and what hides it stands in front of it by ``occlusion_min_depth_ratio`` of the gap:
  a solid object cutting another in two, not a flat package lying across a bin's clutter.
Needs an organized frame (the depth image); the camera's intrinsics are estimated from
the frame itself (pixel coordinates against x/z, y/z).
"""

from __future__ import annotations

import numpy as np

from clearcli.perception.context import RefineContext
from clearcli.perception.filters import finite_mask

# patch normals within this angle count as the same surface
_MAX_ANGLE_DEG = 15.0
# depth margin (m) for "in front of" / "behind" the gap line, plus a share of the range
_DEPTH_TOL_M = 0.015
_MIN_HIDDEN = 0.7
_TOP_TOL_M = 0.015
_MAX_SEEN_THROUGH = 0.05
_LINES = 3  # gap lines judged per pair of segments: the closest coplanar patch pairs'


def estimate_intrinsics(points: np.ndarray, shape: tuple[int, int]) -> tuple[float, float, float, float] | None:
    """(fx, fy, cx, cy) from an organized cloud, or None when it is not a pinhole image."""
    h, w = shape
    idx = np.flatnonzero(finite_mask(points))[::7]
    if idx.size < 100:
        return None
    p = np.take(points, idx, axis=0).astype(np.float64)  # rows by index: take is faster than a[idx]
    ok = p[:, 2] > 1e-3
    if not ok.all():  # (most frames: every finite point lies in front; no copies then, issue 39)
        p, idx = np.compress(ok, p, axis=0), idx[ok]  # rows by a mask: compress is several times faster
    if idx.size < 100:
        return None
    row, col = np.divmod(idx, w)
    out = []
    for coord, pix in ((p[:, 0] / p[:, 2], col), (p[:, 1] / p[:, 2], row)):
        a = np.empty((coord.size, 2))  # what np.stack([coord, ones]) built, without its copies
        a[:, 0] = coord
        a[:, 1] = 1.0
        sol, *_ = np.linalg.lstsq(a, pix.astype(np.float64), rcond=None)
        resid = pix - a @ sol
        if np.sqrt(np.mean(resid**2)) > 2.0:  # pixels: not a pinhole projection
            return None
        out.append(sol)
    return float(out[0][0]), float(out[1][0]), float(out[0][1]), float(out[1][1])


def _hidden_line(
    pa: np.ndarray,
    pb: np.ndarray,
    gap: float,
    depth: np.ndarray,
    intr: tuple[float, float, float, float],
    voxel_m: float,
    min_depth_ratio: float = 0.0,
) -> bool:
    """Does the camera not see the straight line from ``pa`` to ``pb`` (the gap between
    two patches): in front of it at most pixels with depth, almost never behind it, and
    what hides it stands in front of it by at least ``min_depth_ratio`` of the gap (the
    median over the hidden pixels: a solid object, not a flat sheet lying over)?"""
    fx, fy, cx, cy = intr
    h, w = depth.shape
    n_s = max(3, int(gap / (0.5 * voxel_m)))
    t = np.linspace(0.0, 1.0, n_s + 2)[1:-1]
    t = t[(t * gap > 0.01) & ((1 - t) * gap > 0.01)]  # the ends are the patches' own
    if t.size < 3:
        return False
    line = pa + t[:, None] * (pb - pa)
    if np.any(line[:, 2] <= 1e-3):
        return False
    col = np.round(fx * line[:, 0] / line[:, 2] + cx).astype(np.int64)
    row = np.round(fy * line[:, 1] / line[:, 2] + cy).astype(np.int64)
    if not ((col >= 0) & (col < w) & (row >= 0) & (row < h)).all():
        return False
    z_meas = depth[row, col]
    tol_z = _DEPTH_TOL_M + 0.01 * line[:, 2]
    hidden = np.isfinite(z_meas) & (z_meas < line[:, 2] - tol_z)
    seen_through = np.isfinite(z_meas) & (z_meas > line[:, 2] + tol_z)
    # missing depth (the sensor's shadow beside a nearer edge) says nothing; judge by
    # the pixels that have depth, and want most of them
    measured = np.isfinite(z_meas)
    n_meas = int(measured.sum())
    if not (
        n_meas >= 0.5 * measured.size
        and hidden.sum() >= _MIN_HIDDEN * n_meas
        and seen_through.sum() <= _MAX_SEEN_THROUGH * n_meas
    ):
        return False
    # hidden.sum() >= 0.7 * n_meas >= 0.35 * t.size > 0 here
    return bool(np.median((line[:, 2] - z_meas)[hidden]) >= min_depth_ratio * gap)


def merge_occluded(seg_of_sv: np.ndarray, ctx: RefineContext) -> np.ndarray:
    """The stage (supervoxel level, organized frames): segment index per supervoxel
    after joining occluded pieces (renumbered).

    Segments of at least the smallest object (`SegmentSize.min_object_voxels`) that do
    not touch and reach the same height (within ``_TOP_TOL_M``), as the two sides of one
    object cut by a nearer one do: the closest pair of their supervoxels that lie on one
    plane (parallel normals, each centroid on the other's plane) gives the gap line; the
    pair is joined when the camera cannot see that line.

    It runs on the pixel grid only, where `SegmentSize` is never fitted to density: its
    voxel and smallest object are the settings' own.
    """
    sv, frame_points, shape = ctx.sv, ctx.frame.points, ctx.frame.shape
    assert shape is not None  # a stage on the pixel grid: refine() runs it on organized frames only
    sv_centroids, sv_normals, sv_edges, sv_height = sv.centroids, sv.normals, sv.edges, ctx.sv_height
    max_gap_m, voxel_m = ctx.settings.occlusion_max_gap_m, ctx.size.voxel_m
    min_depth_ratio = ctx.settings.occlusion_min_depth_ratio
    n_seg = int(seg_of_sv.max()) + 1 if seg_of_sv.size else 0
    if n_seg < 2:
        return seg_of_sv
    h, w = shape
    depth = frame_points[:, 2].reshape(h, w)
    seg_voxels = np.bincount(seg_of_sv, weights=sv.n_voxels, minlength=n_seg)
    cand = np.flatnonzero(seg_voxels >= ctx.size.min_object_voxels)
    if cand.size < 2:
        return seg_of_sv
    a_seg, b_seg = seg_of_sv[sv_edges[:, 0]], seg_of_sv[sv_edges[:, 1]]
    # the touching pairs (lower, higher), distinct in NumPy before the set: a few hundred,
    # not one tuple per adjacency
    cross = a_seg != b_seg
    t_lo, t_hi = np.minimum(a_seg, b_seg)[cross], np.maximum(a_seg, b_seg)[cross]
    t_key = np.unique(t_lo * n_seg + t_hi)
    touching = set(zip((t_key // n_seg).tolist(), (t_key % n_seg).tolist()))
    order = np.argsort(seg_of_sv, kind="stable")
    bounds = np.searchsorted(seg_of_sv[order], np.arange(n_seg + 1))
    members = {int(s): order[bounds[s] : bounds[s + 1]] for s in cand}
    # the candidates' boxes, all at once: minima and maxima are exact in any order, so
    # each is what sv_centroids[members].min(axis=0) gives (reduceat over the non-empty
    # segments' starts: each run ends where the next starts)
    sorted_centroids = sv_centroids[order]
    filled = np.flatnonzero(bounds[1:] > bounds[:-1])
    at = np.searchsorted(filled, cand)
    lo_c = np.minimum.reduceat(sorted_centroids, bounds[filled], axis=0)[at]
    hi_c = np.maximum.reduceat(sorted_centroids, bounds[filled], axis=0)[at]
    cos_max = np.cos(np.radians(_MAX_ANGLE_DEG))
    parent = np.arange(n_seg)

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    # the pairs the loop below could join, found for all at once: the gap between their
    # boxes within max_gap_m (with a margin: the loop's own test decides, this only drops
    # pairs far past it) and their tops within _TOP_TOL_M (the segments' highest supervoxels: exact)
    gap_c = np.maximum(0.0, np.maximum(lo_c[:, None, :] - hi_c[None, :, :], lo_c[None, :, :] - hi_c[:, None, :]))
    top = np.full(n_seg, -np.inf)
    np.maximum.at(top, seg_of_sv, sv_height)
    top_c = top[cand]
    maybe = (np.sqrt((gap_c**2).sum(axis=2)) <= max_gap_m * (1 + 1e-6) + 1e-9) & (
        np.abs(top_c[:, None] - top_c[None, :]) <= _TOP_TOL_M
    )
    cand_list = cand.tolist()
    # the camera's intrinsics are read from the frame only for a pair that gets as far as
    # a gap line (most frames' pairs end at the tests before); None: nothing is joined
    intr: tuple[float, float, float, float] | None = None
    for ia, a in enumerate(cand_list):
        for ib in np.flatnonzero(maybe[ia, ia + 1 :]).tolist():
            jb = ia + 1 + ib
            b = cand_list[jb]
            if (a, b) in touching or root(a) == root(b):
                continue
            # (their tops within _TOP_TOL_M: ``maybe`` tested it on the very maxima)
            gap_box = np.maximum(0.0, np.maximum(lo_c[ia] - hi_c[jb], lo_c[jb] - hi_c[ia]))
            if np.linalg.norm(gap_box) > max_gap_m:
                continue
            xa, na = sv_centroids[members[a]], sv_normals[members[a]]
            xb, nb = sv_centroids[members[b]], sv_normals[members[b]]
            diff = xb[None, :, :] - xa[:, None, :]  # (A, B, 3)
            dist = np.linalg.norm(diff, axis=2)
            parallel = np.abs(na @ nb.T) >= cos_max
            off_a = np.abs(np.einsum("ik,ijk->ij", na, diff))
            off_b = np.abs(np.einsum("jk,ijk->ij", nb, diff))
            tol = np.maximum(0.01, 0.05 * dist)
            ok = parallel & (off_a <= tol) & (off_b <= tol) & (dist <= max_gap_m)
            if not ok.any():
                continue
            # the closest few such pairs each give a line; one the camera cannot see
            # through is enough (the closest alone turned on which of two nearly
            # coplanar patches won by a fraction of a millimetre)
            if intr is None:
                intr = estimate_intrinsics(frame_points, shape)
                if intr is None:
                    return seg_of_sv  # not a pinhole image: as before any join
            flat_ok = np.flatnonzero(ok.ravel())
            closest = flat_ok[np.argsort(dist.ravel()[flat_ok], kind="stable")[:_LINES]]
            if any(
                _hidden_line(xa[i], xb[j], float(dist[i, j]), depth, intr, voxel_m, min_depth_ratio)
                for i, j in zip(*np.unravel_index(closest, dist.shape))
            ):
                parent[root(b)] = root(a)
    final = np.array([root(s) for s in range(n_seg)])[seg_of_sv]
    _, out = np.unique(final, return_inverse=True)
    return out.astype(np.int64)
