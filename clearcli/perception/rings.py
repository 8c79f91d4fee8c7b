"""Stage 3d' (ours, not in the thesis): join a container's inner and outer walls that do
not touch.

Seen from a Kinect at the usual 30-50 degrees above the table, an open container (a
bowl, a mug, a pot) shows its near OUTER wall and, over the near rim, its far INNER
wall. LCCP keeps them apart (the inner wall is concave), and `rims.py` joins them only
where the two come within a couple of centimetres of each other near their tops. They
often do not: the rim's ends, seen edge-on, are the pixels the outlier filter and the
depth edges drop, and the near rim is far (a container's diameter) from the inner wall
seen above it. What stays plain is their shape from above: the top bands of the two
walls are two arcs of ONE circle (the rim), and the inner wall faces that circle's
centre while the outer wall faces away from it.

For two segments whose tops lie within ``rim_tolerance_m`` of each other:
1. each segment's rim band: its voxels within ``rim_tolerance_m`` of its top, in the
   table plane;
2. one circle fitted to both bands (algebraic least squares); kept when its radius is
   between ``_MIN_RADIUS_M`` and ``ring_max_radius_m``, every band point lies within
   ``ring_max_residual`` of the radius on average (RMS, as a share of it: a filled top
   of a can or a box fits a circle badly), and the two bands together go at least
   ``ring_min_cover_deg`` round the centre (two arcs of one rim, not one arc);
3. joined when one segment's surface faces the centre (its supervoxel normals, in the
   table plane, point towards it on average: an inner wall) and the other's faces away
   (an outer wall). Two cans side by side both face away from any centre between them.
"""

from __future__ import annotations

import numpy as np

from clearcli.perception.context import RefineContext, by_label
from clearcli.perception.lccp import join_pairs

_MIN_RADIUS_M = 0.015
# average facing (cosine between a wall's in-plane normal and the direction to the
# centre) an inner wall must reach, and an outer wall go below the negative of
_MIN_FACING = 0.3
_ANGLE_BINS = 36
# rim points farther than this many times the allowed RMS from the circle are not rim
# (a handle, a knob)
_TRIM = 2.0


def fit_circle(xy: np.ndarray) -> tuple[np.ndarray, float]:
    """(centre (2,), radius) of the least-squares circle through ``xy`` (N, 2) (Kasa's
    algebraic fit: linear in the centre and r^2 - |c|^2)."""
    return fit_circle_rows(*kasa_rows(xy))


def kasa_rows(xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Kasa's linear system for the points ``xy`` (N, 2): the rows (2x, 2y, 1) (N, 3) and
    the right-hand sides x^2 + y^2 (N,). A fit to a subset is `fit_circle_rows` of the
    subset's rows: a refit loop builds them once, not once a refit."""
    a = np.empty((xy.shape[0], 3))  # the columns 2x, 2y, 1 (what column_stack built, without its copies)
    np.multiply(xy, 2.0, out=a[:, :2])
    a[:, 2] = 1.0
    # (xy**2).sum(axis=1)'s arithmetic by columns (a sum over a row of two is one
    # addition of the two squares), without the (N, 2) temporary
    x, y = xy[:, 0], xy[:, 1]
    return a, x * x + y * y


def fit_circle_rows(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, float]:
    """`fit_circle` of the points whose `kasa_rows` are ``a`` (N, 3) and ``b`` (N,)."""
    sol, *_ = np.linalg.lstsq(a, b, rcond=None)
    centre = sol[:2]
    r2 = float(sol[2] + centre @ centre)
    return centre, float(np.sqrt(max(r2, 0.0)))


def fit_rim(
    xy: np.ndarray, max_radius_m: float, max_residual: float, max_off_share: float = 0.2
) -> tuple[np.ndarray, float, np.ndarray] | None:
    """(centre, radius, inlier mask) of the rim circle through ``xy`` (N, 2), or None.

    A mug's handle and a lid's knob reach into a rim band (their tops are within the
    band's tolerance of the rim's) and pull a plain least-squares circle off the rim:
    the PCL tutorial's mug fits at 0.13 of its radius with its handle, 0.07 without.
    So the circle is fitted again to the points within ``_TRIM`` x ``max_residual`` of
    the radius (twice), and kept when at most ``max_off_share`` of the band lie off it and
    those fit within ``max_residual`` (RMS, as a share of the radius). A filled top (a
    can's, a box's) has most of its points far inside any circle through its edge: it
    fails the share, as it failed the plain residual before.
    """
    if xy.shape[0] < 3:
        return None
    rows, sq = kasa_rows(xy)  # every fit below is to a subset of these rows
    centre, radius = fit_circle_rows(rows, sq)
    inlier = np.ones(xy.shape[0], dtype=bool)
    x, y = xy[:, 0], xy[:, 1]

    def from_centre(centre: np.ndarray) -> np.ndarray:
        # np.linalg.norm(xy - centre, axis=1)'s arithmetic (one sum of two squares a
        # row), by columns: no (N, 2) temporaries
        dx, dy = x - centre[0], y - centre[1]
        return np.sqrt(dx * dx + dy * dy)

    for _ in range(2):
        resid = np.abs(from_centre(centre) - radius)
        inlier = resid <= _TRIM * max_residual * radius
        if inlier.sum() < 3:
            return None
        centre, radius = fit_circle_rows(np.compress(inlier, rows, axis=0), np.compress(inlier, sq))
    resid = from_centre(centre) - radius
    inlier = np.abs(resid) <= _TRIM * max_residual * radius
    if not (_MIN_RADIUS_M <= radius <= max_radius_m) or inlier.mean() < 1.0 - max_off_share:
        return None
    if np.sqrt(np.mean(resid[inlier] ** 2)) > max_residual * radius:
        return None
    return centre, radius, inlier


def cover_deg(xy: np.ndarray, centre: np.ndarray) -> float:
    """How far round ``centre`` the points ``xy`` (N, 2) go, in degrees (10° bins)."""
    ang = np.arctan2(xy[:, 1] - centre[1], xy[:, 0] - centre[0])
    bins = np.floor((ang + np.pi) / (2 * np.pi) * _ANGLE_BINS).astype(np.int64) % _ANGLE_BINS
    # the bins hit, counted on 36 counters: what np.unique(bins).size gives, without its sort
    return int(np.count_nonzero(np.bincount(bins, minlength=_ANGLE_BINS))) * 360.0 / _ANGLE_BINS


def facing_cos(normals: np.ndarray, points: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """(K,) cosine between each in-plane normal (K, 2) and the direction from its point
    (K, 2) to ``centre``: near 1 for an inner wall, near -1 for an outer one."""
    to_centre = centre - points
    to_centre = to_centre / np.maximum(np.linalg.norm(to_centre, axis=1, keepdims=True), 1e-9)
    n = normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-9)
    return np.einsum("ij,ij->i", n, to_centre)


def ring_pair(
    band_a: np.ndarray,
    band_b: np.ndarray,
    normals_a: np.ndarray,
    points_a: np.ndarray,
    normals_b: np.ndarray,
    points_b: np.ndarray,
    max_radius_m: float,
    max_residual: float,
    min_cover_deg: float,
    max_off_share: float = 0.2,
) -> bool:
    """Are two segments the inner and outer walls of one container? ``band_*`` (N, 2):
    their rim bands in the table plane; ``normals_*`` / ``points_*`` (K, 2): their
    supervoxels' in-plane normals and centroids."""
    if band_a.shape[0] < 3 or band_b.shape[0] < 3:
        return False
    both = np.vstack([band_a, band_b])
    fitted = fit_rim(both, max_radius_m, max_residual, max_off_share)
    if fitted is None:
        return False
    centre, radius, inlier = fitted
    if cover_deg(both[inlier], centre) < min_cover_deg:
        return False
    fa = float(np.mean(facing_cos(normals_a, points_a, centre)))
    fb = float(np.mean(facing_cos(normals_b, points_b, centre)))
    return (fa >= _MIN_FACING and fb <= -_MIN_FACING) or (fb >= _MIN_FACING and fa <= -_MIN_FACING)


def merge_rings(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
    """The stage: (V,) segment per voxel after joining inner and outer walls of
    containers.

    The voxels and the supervoxels in the table plane and their heights above it come
    from ``ctx``; only supervoxels that are not a top face (`RefineContext.sv_is_wall`)
    count for facing. Segments of fewer than the smallest object's voxels
    (`SegmentSize.min_object_voxels`) are left alone."""
    settings = ctx.settings
    voxel_xy, voxel_height, voxel_label = ctx.voxel_xy, ctx.voxel_height, ctx.sv.voxel_label
    sv_normals_xy, sv_xy, sv_is_wall = ctx.sv_normals_xy, ctx.sv_xy, ctx.sv_is_wall
    tolerance_m, max_radius_m = settings.rim_tolerance_m, settings.ring_max_radius_m
    min_voxels = ctx.size.min_object_voxels

    n_seg = int(seg_of_voxel.max()) + 1 if seg_of_voxel.size else 0
    if n_seg < 2:
        return seg_of_voxel
    sizes = np.bincount(seg_of_voxel, minlength=n_seg)
    top = np.full(n_seg, -np.inf)
    np.maximum.at(top, seg_of_voxel, voxel_height)
    # each segment's voxels in index order (what a mask over all voxels gives), from one
    # sort: no pass over every voxel per segment
    order = by_label(seg_of_voxel, n_seg)
    bounds = np.searchsorted(seg_of_voxel[order], np.arange(n_seg + 1))
    # the segments holding a wall supervoxel: a segment without one faces nowhere
    has_wall = np.bincount(seg_of_voxel, weights=sv_is_wall[voxel_label], minlength=n_seg) > 0
    cand = np.flatnonzero((sizes >= min_voxels) & has_wall)
    if cand.size < 2:
        return seg_of_voxel
    # the segments' boxes in the plane, all at once: minima and maxima are exact in any
    # order, so each is what xy.min(axis=0) over the segment's voxels gives
    # (reduceat over the non-empty segments' starts: each run ends where the next starts)
    xy_sorted = np.take(voxel_xy, order, axis=0)  # rows by index: take is several times faster than a[idx]
    filled = np.flatnonzero(sizes > 0)
    at = np.searchsorted(filled, cand)
    lo_all = np.minimum.reduceat(xy_sorted, bounds[filled], axis=0)[at]
    hi_all = np.maximum.reduceat(xy_sorted, bounds[filled], axis=0)[at]
    # the pairs (i < j, in the order the loop took them) whose tops lie within the
    # tolerance (exact) and whose boxes in the plane lie within a diameter (with a
    # margin here; each survivor is tested again below as before)
    top_c = top[cand]
    gap_c = np.maximum(
        0.0, np.maximum(lo_all[:, None, :] - hi_all[None, :, :], lo_all[None, :, :] - hi_all[:, None, :])
    )
    maybe = (np.abs(top_c[:, None] - top_c[None, :]) <= tolerance_m) & (
        np.sqrt((gap_c**2).sum(axis=2)) <= max_radius_m * (1 + 1e-6) + 1e-9
    )
    pair_i, pair_j = np.nonzero(np.triu(maybe, k=1))  # row-major: (a, b) as the loop went
    band: dict[int, np.ndarray] = {}
    walls: dict[int, np.ndarray] = {}

    def prepare(s: int) -> None:
        # a segment's rim band and wall supervoxels, once, when one of its pairs is tried
        if s in band:
            return
        members = order[bounds[s] : bounds[s + 1]]
        band[s] = voxel_xy[members[voxel_height[members] >= top[s] - tolerance_m]]
        svs = np.unique(voxel_label[members])
        walls[s] = svs[sv_is_wall[svs]]

    joined: list[tuple[int, int]] = []
    for i, j in zip(pair_i.tolist(), pair_j.tolist(), strict=True):
        a, b = int(cand[i]), int(cand[j])
        # the two must lie on one rim: their boxes in the plane within a diameter
        gap = np.maximum(0.0, np.maximum(lo_all[i] - hi_all[j], lo_all[j] - hi_all[i]))
        if float(np.linalg.norm(gap)) > max_radius_m:
            continue
        prepare(a)
        prepare(b)
        wa, wb = walls[a], walls[b]
        if ring_pair(
            band[a],
            band[b],
            sv_normals_xy[wa],
            sv_xy[wa],
            sv_normals_xy[wb],
            sv_xy[wb],
            max_radius_m,
            settings.ring_max_residual,
            settings.ring_min_cover_deg,
            settings.ring_max_off_share,
        ):
            joined.append((a, b))
    return join_pairs(seg_of_voxel, joined, n_seg)
