"""Stage 3d'' (ours, not in the thesis): an open container rebuilt from its rim, taking
back its wall from what stands in it and what leans on it.

A bowl with a can standing in it is cut by the can into the walls left and right of it,
the wall behind it goes to the can (they continue each other in depth), and an object
lying against the rim (a drill) joins the wall it touches there (`rims.py` sees two
segments touching only at their tops). No pairwise join undoes that: the pieces are
mixed. What stays plain is the container's shape: a surface of revolution about the
table's normal, whose rim is one circle at one height, and whose wall at each height
lies at one distance from the axis. What stands inside lies nearer the axis than the
wall at its height; what leans on it from outside lies beyond the rim's circle.

For every group of segments whose tops lie within ``rim_tolerance_m`` of each other:
1. their rim bands (voxels within ``rim_tolerance_m`` of their segment's top, on wall
   supervoxels) and the circle most of them lie on (RANSAC on the bands, then least
   squares on its inliers; radius between ``_MIN_RADIUS_M`` and ``ring_max_radius_m``);
   kept when its inliers go at least ``_MIN_COVER_DEG`` round the centre, no top face
   fills the circle at the rim's height, and some of the walls inside it face its centre
   (an opening: a can's or a box's walls all face away from any centre; two boxes whose
   edges lie on one circle fill it with their tops); when the group gives no circle,
   once more without the other member holding the most band voxels (a drill's top
   beside a bowl, more voxels than its rim, draws RANSAC to an arc that is no rim);
2. the wall's distance from the axis per 1 cm of height (the largest distances within
   the rim's circle at that height: the wall is the outermost thing inside it), made
   to widen upwards (bowls, cups and mugs do; a vase that narrows is not a container
   anything is put in);
3. the container is every voxel from the rim's height down to the lowest voxel of the
   segments holding the rim (not what the container stands on), within ``_OUT_M``
   outside the rim's circle and within ``_WALL_IN`` of the radius (or ``_WALL_IN_M``)
   inside the wall at its height; with the frame's colour, the voxels between
   ``_SURE_WALL`` and ``_SURE_INSIDE`` of the radius inside it (and the floor's) go to
   the wall or to what stands inside by their colour;
4. what is left of each segment: its connected pieces (what is left of the segments
   holding the rim, the container's own, is one piece wherever it is connected: their
   boundary may run through a handle); a piece of at least an object's
   area is an object of its own when, inside the rim's circle, it rises above the rim
   (the can standing in the bowl); inside it and below the rim, what stands on the
   floor is (`_standing_inside`: a can in a wide bowl, issue 37's large bowl); outside
   the circle, a piece that stands on the table is (the drill leaning on the rim); any
   other (a mug's handle, a strip of wall the circle did not
   cover, the floor, the surface a stereo camera spans across a mug's opening) goes
   with the container.
Applied only when the container takes an object's area of voxels from two or more
segments: one segment already holding its whole wall is left as it is. A container's
rim segments are not looked at again; the others of its group may hold another rim (two
bowls side by side).
"""

from __future__ import annotations

import numpy as np

from clearcli.perception.context import RefineContext
from clearcli.perception.graph import components, dense_labels
from clearcli.perception.rings import cover_deg, facing_cos, fit_circle_rows, kasa_rows

_MIN_RADIUS_M = 0.02
# a rim wider than ``ring_max_radius_m`` (found by the wider search up to
# ``vessel_max_radius_m``) holds _WIDE_MIN_ON of its segments' band voxels on its
# circle: the sides of a rectangle that wide (the walls of a bin whose floor is the
# support, 37 x 42 cm) meet a circle in arcs that cover 200 degrees with 38-45 % of their
# band on it; large_bowl's rims (18-21 cm) hold 96-100 %. Narrower rims keep the tests
# they had: a mug's band, its handle and noise in it, holds 45-100 % on mOSD and the
# foreign frames, and a small open box taken for a container is one
_WIDE_MIN_ON = 0.8
_RANSAC_ROUNDS = 200
_SCORE_SAMPLES = 500
_REFITS = 20  # at most this many least-squares refits of the circle (they settle in a few)
# a rim point within this share of the radius (or _INLIER_M) of the circle is on it
_INLIER = 0.06
_INLIER_M = 0.004
_MIN_COVER_DEG = 200.0
# the share of the walls within the rim that must face the centre (cos >= 0.5), and
# their least number: the inner wall seen over the near rim
_MIN_FACING_SHARE = 0.2
_MIN_FACING_SV = 3
# the container's wall: up to _OUT_M beyond the rim's circle (a rim is a few mm thick
# and the depth noise a few more), and inside the wall's distance at its height by
# _WALL_IN of the radius, at least _WALL_IN_M (the wall's thickness and the noise)
_OUT_M = 0.006
_WALL_IN = 0.15
_WALL_IN_M = 0.01
_BIN_M = 0.01  # the wall's distance from the axis is read per this much height
# the opening: within _OPEN of the radius, top faces at the rim's height may cover at
# most _MAX_FILLED of it (a container's inside is empty there; a box's top is not)
_OPEN = 0.8
_MAX_FILLED = 0.25
# inside the rim, below it: a thing standing on the container's floor keeps its top this
# far below the rim's height (a surface at the rim's height, or a strip of wall reaching
# it, is the container's), and the floor is a piece's top-facing voxels within
# _FLOOR_BAND_M of its lowest (a floor's depth noise is a few millimetres)
_BELOW_RIM_M = 0.005
_FLOOR_BAND_M = 0.01
# ... or, reaching the rim's height, it stands clear of the wall: this share of its
# voxels lies beyond _SURE_INSIDE of the radius inside the wall (a can as tall as the
# rim: 0.98 on large_bowl(4); a surface spanning the opening reaches the wall, about
# 0.7 of a disc's area lying that far in; a strip of wall, none)
_CLEAR_SHARE = 0.9
# with colour: within _SURE_WALL of the radius inside the wall a voxel is the wall for
# certain, beyond _SURE_INSIDE it is what stands inside; between, where a can's side
# and the bowl's lower wall both lie, each voxel goes to the one whose colour it is
# nearer (its _K nearest of the sure ones, CIELAB)
_SURE_WALL = 0.15
_SURE_INSIDE = 0.3
_K = 7
_MAX_SAMPLES = 2000


def _by_colour(
    lab: np.ndarray, wall: np.ndarray, inside: np.ndarray, unsure: np.ndarray, rng: np.random.Generator
) -> np.ndarray:
    """(len(unsure),) is each unsure voxel's colour nearer the wall's than the inside's
    (majority of its ``_K`` nearest among samples of both, CIELAB)?"""
    from scipy.spatial import cKDTree

    w = wall if wall.size <= _MAX_SAMPLES else rng.choice(wall, _MAX_SAMPLES, replace=False)
    i = inside if inside.size <= _MAX_SAMPLES else rng.choice(inside, _MAX_SAMPLES, replace=False)
    ref = np.vstack([lab[w], lab[i]])
    is_wall = np.concatenate([np.ones(w.size, bool), np.zeros(i.size, bool)])
    k = min(_K, ref.shape[0])
    _, nn = cKDTree(ref).query(lab[unsure], k=k)
    return is_wall[nn.reshape(unsure.size, k)].mean(axis=1) > 0.5


def _circles3(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centres (R, 2) and radii (R,) of the circles through each three points of ``p``
    (R, 3, 2); a radius of inf where the three are collinear."""
    # by coordinate columns: a sum or a norm over a row of two is one addition of the two
    # squares, the same arithmetic as (a**2).sum(1) and np.linalg.norm(..., axis=1)
    ax, ay, bx, by, cx, cy = p[:, 0, 0], p[:, 0, 1], p[:, 1, 0], p[:, 1, 1], p[:, 2, 0], p[:, 2, 1]
    d = 2.0 * (ax * (by - cy) + bx * (cy - ay) + cx * (ay - by))
    ok = np.abs(d) > 1e-12
    d = np.where(ok, d, 1.0)
    a2, b2, c2 = ax * ax + ay * ay, bx * bx + by * by, cx * cx + cy * cy
    ux = (a2 * (by - cy) + b2 * (cy - ay) + c2 * (ay - by)) / d
    uy = (a2 * (cx - bx) + b2 * (ax - cx) + c2 * (bx - ax)) / d
    centres = np.stack([ux, uy], axis=1)
    dx, dy = ax - ux, ay - uy
    radii = np.where(ok, np.sqrt(dx * dx + dy * dy), np.inf)
    return centres, radii


def find_rim(
    band_xy: np.ndarray, max_radius_m: float, rng: np.random.Generator
) -> tuple[np.ndarray, float, np.ndarray] | None:
    """(centre, radius, inlier mask) of the circle most of ``band_xy`` (N, 2) lie on,
    going at least ``_MIN_COVER_DEG`` round it, or None. RANSAC over circles through
    three band points, all rounds at once, then least squares on the inliers."""
    n = band_xy.shape[0]
    if n < 10:
        return None
    # a point picked twice makes no circle (radius inf); the rounds are scored on at
    # most _SCORE_SAMPLES of the band
    centres, radii = _circles3(np.take(band_xy, rng.integers(0, n, (_RANSAC_ROUNDS, 3)), axis=0))
    ok = (radii >= _MIN_RADIUS_M) & (radii <= max_radius_m)
    if not ok.any():
        return None
    centres, radii = centres[ok], radii[ok]
    sample = band_xy if n <= _SCORE_SAMPLES else band_xy[rng.choice(n, _SCORE_SAMPLES, replace=False)]
    # (R, n) distances, by coordinate: no (R, n, 2) array (what np.linalg.norm sums, in its order)
    # (in place: the same operations in the same order, no temporaries)
    dist = sample[None, :, 0] - centres[:, 0, None]
    dy = sample[None, :, 1] - centres[:, 1, None]
    dist *= dist
    dy *= dy
    dist += dy
    np.sqrt(dist, out=dist)
    dist -= radii[:, None]
    np.abs(dist, out=dist)
    score = np.count_nonzero(dist <= np.maximum(_INLIER * radii, _INLIER_M)[:, None], axis=1)
    best = int(np.argmax(score))
    centre, radius = centres[best], float(radii[best])
    bx, by = band_xy[:, 0], band_xy[:, 1]

    def on_circle(centre: np.ndarray, radius: float) -> np.ndarray:
        # np.linalg.norm(band_xy - centre, axis=1)'s arithmetic, by columns
        dx, dy = bx - centre[0], by - centre[1]
        return np.abs(np.sqrt(dx * dx + dy * dy) - radius) <= max(_INLIER * radius, _INLIER_M)

    inl = on_circle(centre, radius)
    if inl.sum() < 10:
        return None
    # least squares on the inliers until they no longer change: the circle is then a
    # fixed point of the refit, not of the draws (which voxel the random indices pick
    # changes with the band's size: one voxel more, other draws, another first circle)
    rows, sq = kasa_rows(band_xy)  # each refit's system: the inliers' rows of the band's
    for _ in range(_REFITS):
        # rows by a mask: compress is faster
        centre, radius = fit_circle_rows(np.compress(inl, rows, axis=0), np.compress(inl, sq))
        if not (_MIN_RADIUS_M <= radius <= max_radius_m):
            return None
        again = on_circle(centre, radius)
        if again.sum() < 10:
            return None
        settled = bool((again == inl).all())
        inl = again
        if settled:
            break
    if cover_deg(np.compress(inl, band_xy, axis=0), centre) < _MIN_COVER_DEG:
        return None
    return centre, radius, inl


def _rim_of(
    band_xy: np.ndarray, max_radius_m: float, wide_radius_m: float, seed: list[int]
) -> tuple[np.ndarray, float, np.ndarray] | None:
    """`find_rim` up to ``max_radius_m`` (``ring_max_radius_m``), and only when none is
    found there and the band spans more than that rim's diameter (an arc of more than 180
    degrees holds two opposite points), once more up to ``wide_radius_m``
    (``vessel_max_radius_m``), each search from a generator seeded by ``seed``: a narrow
    rim is found as it was before wide ones were sought (a box at 2.4 m, cut in two, is
    joined by a rim of 11 cm; a search up to 25 cm drew another circle and left it in
    two), and a group with no wide band pays for no second search."""
    found = find_rim(band_xy, max_radius_m, np.random.default_rng(seed))
    if found is not None or wide_radius_m <= max_radius_m or band_xy.shape[0] < 10:
        return found
    span = np.ptp(band_xy, axis=0)
    if float(np.hypot(span[0], span[1])) <= 2 * max_radius_m:
        return None
    return find_rim(band_xy, wide_radius_m, np.random.default_rng(seed))


def _wall_profile(d: np.ndarray, h: np.ndarray, rim_h: float, radius: float) -> np.ndarray:
    """(B,) the wall's distance from the axis per ``_BIN_M`` of height, 0..rim_h: the
    largest distance within the rim (its 95th percentile) at that height, widening
    upwards, the rim's radius at the top."""
    n_bins = int(np.ceil(max(rim_h, _BIN_M) / _BIN_M)) + 1
    b = np.clip((h / _BIN_M).astype(np.int64), 0, n_bins - 1)
    prof = np.full(n_bins, np.nan)
    # the 95th percentile of every bin of at least 3 at once: each bin's distances sorted
    # (one lexsort), then np.percentile's linear rule on its order statistics, the same
    # arithmetic: index v = (m - 1) 0.95, below it p = floor(v), weight g = v - p, and
    # lo + (hi - lo) g, or hi - (hi - lo) (1 - g) from g = 0.5 on
    counts = np.bincount(b, minlength=n_bins)
    full = counts >= 3
    if full.any():
        sorted_d = d[np.lexsort((d, b))]
        first = np.cumsum(counts) - counts
        v = (counts[full] - 1) * 0.95
        below = np.floor(v)
        g = v - below
        at = first[full] + below.astype(np.int64)
        lo, hi = sorted_d[at], sorted_d[at + 1]
        step = hi - lo
        prof[full] = np.where(g >= 0.5, hi - step * (1 - g), lo + step * g)
    prof[-1] = radius if np.isnan(prof[-1]) else max(prof[-1], radius)
    # bins with nothing seen take the next one up; then widening upwards: each bin at
    # most the one above it
    for k in range(n_bins - 2, -1, -1):
        if np.isnan(prof[k]) or prof[k] > prof[k + 1]:
            prof[k] = prof[k + 1] if np.isnan(prof[k]) else min(prof[k], prof[k + 1])
    return prof


def _standing_inside(
    piece: np.ndarray,
    voxel_height: np.ndarray,
    wall_vox: np.ndarray,
    voxel_edges: np.ndarray,
    rim_h: float,
    standing_max_m: float,
    min_voxels: int,
    depth_in: np.ndarray,
    clear_m: float,
) -> list[np.ndarray]:
    """The objects standing on a container's floor below its rim within ``piece`` (voxel
    indices, inside the rim's circle): the piece without its floor (its top-facing voxels
    within ``_FLOOR_BAND_M`` of its lowest: LCCP may leave the floor and a can standing on
    it in one segment), in connected pieces; each one of at least ``min_voxels`` that
    rises ``standing_max_m`` or more and keeps its top ``_BELOW_RIM_M`` or more below the
    rim is an object (a can in a wide bowl). A flat floor leaves nothing that rises. A
    part reaching the rim's height is one only when ``_CLEAR_SHARE`` of it stands clear
    of the wall (``depth_in``, each voxel's distance inside the wall at its height, at
    least ``clear_m``): a can as tall as the rim is; the surface
    a stereo camera spans across an opening, or a strip of wall the circle missed, both
    reaching the wall, are the container's."""
    if piece.size < min_voxels:
        return []
    h = voxel_height[piece]
    body = piece[wall_vox[piece] | (h > h.min() + _FLOOR_BAND_M)]
    if body.size < min_voxels:
        return []
    local = np.full(voxel_height.size, -1, dtype=np.int64)
    local[body] = np.arange(body.size)
    a, b = local[voxel_edges[:, 0]], local[voxel_edges[:, 1]]
    inner = (a >= 0) & (b >= 0)
    comp = components(body.size, np.column_stack([a[inner], b[inner]]))
    parts = []
    for c in np.unique(comp):
        part = body[comp == c]
        hp = voxel_height[part]
        below_rim = hp.max() < rim_h - _BELOW_RIM_M or float(np.mean(depth_in[part] >= clear_m)) >= _CLEAR_SHARE
        if part.size >= min_voxels and below_rim and hp.max() - hp.min() >= standing_max_m:
            parts.append(part)
    return parts


def rebuild_vessels(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
    """The stage: (V,) segment per voxel, 0..G-1, with each open container rebuilt from
    its rim (module docstring). The voxels and supervoxels in the table plane and above
    it, their adjacency, the walls (`RefineContext.sv_is_wall`) and the voxels' colour
    (CIELAB, when the frame's is usable) come from ``ctx``; a piece is an object of its
    own from the smallest object's voxels (`SegmentSize.min_object_voxels`)."""
    settings = ctx.settings
    voxel_xy, voxel_height, voxel_edges, voxel_label = ctx.voxel_xy, ctx.voxel_height, ctx.vox.edges, ctx.sv.voxel_label
    sv_normals_xy, sv_xy, sv_is_wall, voxel_lab = ctx.sv_normals_xy, ctx.sv_xy, ctx.sv_is_wall, ctx.voxel_lab
    tolerance_m, max_radius_m = settings.rim_tolerance_m, settings.ring_max_radius_m
    wide_radius_m = settings.vessel_max_radius_m
    standing_max_m = settings.standing_max_m
    min_voxels, voxel_m = ctx.size.min_object_voxels, ctx.size.voxel_m

    seg = np.asarray(seg_of_voxel, dtype=np.int64).copy()
    if seg.size == 0:
        return seg
    n_seg = int(seg.max()) + 1
    sizes = np.bincount(seg, minlength=n_seg)
    top = np.full(n_seg, -np.inf)
    np.maximum.at(top, seg, voxel_height)
    wall_vox = sv_is_wall[voxel_label]
    in_band = wall_vox & (voxel_height >= top[seg] - tolerance_m)
    cand = [s for s in range(n_seg) if sizes[s] >= min_voxels]
    # segments by their tops, highest first: a group is every candidate whose top lies
    # within the tolerance of the first one's, near it in the plane
    done: set[int] = set()
    next_label = n_seg
    mid = np.stack(
        [np.bincount(seg, weights=voxel_xy[:, k], minlength=n_seg) for k in range(2)], axis=1, dtype=np.float64
    )
    mid /= np.maximum(sizes, 1)[:, None]
    # each candidate's band voxels in index order (what a mask over all voxels gave),
    # from one stable sort of the band's voxels by segment, not a pass over all a segment
    band_vox = np.flatnonzero(in_band)
    band_vox = band_vox[np.argsort(seg[band_vox], kind="stable")]
    band_bounds = np.searchsorted(seg[band_vox], np.arange(n_seg + 1))
    band_of = {s: band_vox[band_bounds[s] : band_bounds[s + 1]] for s in cand}
    # which candidates may share a group, all pairs at once: tops within the tolerance
    # (exact) and middles within a diameter (with a margin; each is tested again below)
    cand_arr = np.asarray(cand, dtype=np.int64)
    mid_c = mid[cand_arr]
    d_mid = np.sqrt((mid_c[:, None, 0] - mid_c[None, :, 0]) ** 2 + (mid_c[:, None, 1] - mid_c[None, :, 1]) ** 2)
    may_group = (np.abs(top[cand_arr][:, None] - top[cand_arr][None, :]) <= tolerance_m) & (
        d_mid <= 2 * max_radius_m * (1 + 1e-6) + 1e-9
    )
    row_of = {k: i for i, k in enumerate(cand)}
    # a group's circle is drawn from a generator seeded by its own segments (integers:
    # the same under a micrometre's move), not one shared in order: a group met again
    # (each of its segments starts it in turn) has the same circle, and fails again the
    # same way while no segment has changed since (``n_changes``)
    rims_of: dict[tuple[int, ...], tuple[np.ndarray, float, np.ndarray] | None] = {}
    failed_at: dict[tuple[int, ...], int] = {}
    n_changes = 0
    for s in sorted(cand, key=lambda k: -top[k]):
        if s in done:
            continue
        group = [
            k
            for k in cand_arr[may_group[row_of[s]]].tolist()
            if k not in done
            and abs(top[k] - top[s]) <= tolerance_m
            and np.linalg.norm(mid[k] - mid[s]) <= 2 * max_radius_m
        ]
        key = tuple(group)
        if failed_at.get(key, -1) == n_changes:
            continue
        failed_at[key] = n_changes  # until it gets as far as changing segments below
        band = np.concatenate([band_of[k] for k in group])
        if key not in rims_of:
            rims_of[key] = _rim_of(voxel_xy[band], max_radius_m, wide_radius_m, [0, *group])
        found = rims_of[key]
        if found is None and len(group) >= 2:
            # another object's top at the rim's height (a drill beside a bowl) may hold
            # more of the band than the rim does and outvote it: once more without the
            # other member holding the most band voxels (a group of its own: its own
            # generator, its circle kept like any group's)
            drop = max((k for k in group if k != s), key=lambda k: band_of[k].size)
            group = [k for k in group if k != drop]
            band = np.concatenate([band_of[k] for k in group])
            key = tuple(group)
            if key not in rims_of:
                rims_of[key] = _rim_of(voxel_xy[band], max_radius_m, wide_radius_m, [0, *group])
            found = rims_of[key]
        if found is None:
            continue
        centre, radius, on_rim = found
        rim_h = float(np.median(voxel_height[band][on_rim]))
        # every voxel's distance from the axis, by columns: np.linalg.norm(voxel_xy -
        # centre, axis=1)'s arithmetic (`_circles3`), without its (V, 2) temporaries
        dx, dy = voxel_xy[:, 0] - centre[0], voxel_xy[:, 1] - centre[1]
        d = np.sqrt(dx * dx + dy * dy)
        inside_rim = d <= radius + _OUT_M
        # the container reaches down as far as the segments holding its rim do within
        # the circle: what it stands on (a box under a bowl) lies lower
        holders = np.unique(seg[band[on_rim]])
        if radius > max_radius_m and float(on_rim[np.isin(seg[band], holders)].mean()) < _WIDE_MIN_ON:
            continue  # a wide rectangle's sides (a bin's walls) met by a circle in arcs
        holders_inside = inside_rim & np.isin(seg, holders)
        if not holders_inside.any():  # a wide rim's inliers may all lie just beyond _OUT_M
            continue
        base = float(voxel_height[holders_inside].min())
        near = inside_rim & (voxel_height <= rim_h + tolerance_m) & (voxel_height >= base)
        # an opening: no top face filling the circle at the rim's height (two boxes'
        # edges can lie on a circle; their tops then fill it) ...
        filled = ~wall_vox & (d <= _OPEN * radius) & (voxel_height >= rim_h - tolerance_m)
        if filled.sum() * voxel_m**2 >= _MAX_FILLED * np.pi * (_OPEN * radius) ** 2:
            continue
        # ... and walls inside the rim facing its centre
        svs = np.unique(voxel_label[near & wall_vox])
        if svs.size == 0:
            continue
        facing = facing_cos(sv_normals_xy[svs], sv_xy[svs], centre) >= 0.5
        if facing.sum() < _MIN_FACING_SV or facing.mean() < _MIN_FACING_SHARE:
            continue
        prof = _wall_profile(d[near], voxel_height[near], rim_h, radius)
        b = np.clip((voxel_height / _BIN_M).astype(np.int64), 0, prof.size - 1)
        depth_in = prof[b] - d  # how far inside the wall at its height
        shell = near & (depth_in <= max(_WALL_IN * radius, _WALL_IN_M))
        if voxel_lab is not None:
            # the floor lies inside the wall too: below standing_max_m nothing is
            # inside for certain, colour decides there
            wall_like = near & (depth_in <= _SURE_WALL * radius)
            inside = near & (depth_in >= _SURE_INSIDE * radius) & (voxel_height > standing_max_m)
            sure_wall, sure_in = np.flatnonzero(wall_like), np.flatnonzero(inside)
            unsure = np.flatnonzero(near & ~wall_like & ~inside)
            if sure_wall.size >= _K and sure_in.size >= _K and unsure.size:
                shell[sure_wall] = True
                shell[sure_in] = False
                shell[unsure] = _by_colour(voxel_lab, sure_wall, sure_in, unsure, np.random.default_rng([1, *group]))
        share = np.bincount(seg[shell])
        touched = np.flatnonzero(share >= 3)
        # the rim's own segments are this container's whatever follows (a second
        # container near it is found from its own segments); the others of the group
        # may hold another container's rim
        done.update(holders.tolist())
        if int((share >= min_voxels).sum()) < 2:
            continue  # one segment holds the whole wall already
        vessel = next_label
        next_label += 1
        n_changes += 1
        # what is left of the touched segments, in connected pieces; the segments holding
        # the rim are the container's own, and what is left of them is judged as one
        # piece wherever it is connected: LCCP's boundary between two of them may run
        # through a handle, and where it runs moves with a rounding-sized change of the
        # points (uois_image_0000's mug: its handle's two parts were judged apart, one
        # taken as leaning on the mug and one as the mug's, and 69 of its 300 points went
        # from one to the other under +-1 micrometre, issue 37). Another segment's
        # pieces stay its own.
        owner = seg.copy()
        of_touched = np.isin(seg, touched)
        rest = of_touched & ~shell
        seg[of_touched & shell] = vessel
        done.update(touched.tolist())
        idx = np.flatnonzero(rest)
        if idx.size == 0:
            continue
        own_rim = np.isin(owner, holders)
        # adjacencies within what is left: within one segment, or between two rim holders
        ea, eb = voxel_edges[:, 0], voxel_edges[:, 1]
        keep = rest[ea] & rest[eb] & ((owner[ea] == owner[eb]) | (own_rim[ea] & own_rim[eb]))
        comp = components(seg.size, np.compress(keep, voxel_edges, axis=0))[idx]  # faster than [keep]
        pieces = [idx[comp == c] for c in np.unique(comp)]
        # in the order they were met segment by segment (numbers as before where no
        # two holders' pieces join): by the segment of each piece's first voxel
        for piece in sorted(pieces, key=lambda p: (int(owner[p[0]]), int(p[0]))):
            if np.median(d[piece]) <= radius:
                # inside the rim: what stands in it rises above the rim (the whole piece),
                # or stands on the floor below the rim (`_standing_inside`); the rest is
                # the container's (its floor; the surface a stereo camera spans across a
                # narrow opening it cannot see into)
                if voxel_height[piece].max() > rim_h + tolerance_m:
                    parts = [piece] if piece.size >= min_voxels else []
                else:
                    parts = _standing_inside(
                        piece,
                        voxel_height,
                        wall_vox,
                        voxel_edges,
                        rim_h,
                        standing_max_m,
                        min_voxels,
                        depth_in,
                        _SURE_INSIDE * radius,  # clear of the wall: beyond the sure wall and the unsure band
                    )
            else:
                # outside: what leans on it stands on the table; a handle does not
                own = voxel_height[piece].min() <= standing_max_m
                parts = [piece] if piece.size >= min_voxels and own else []
            seg[piece] = vessel
            for part in parts:
                seg[part] = next_label
                next_label += 1
    return dense_labels(seg)
