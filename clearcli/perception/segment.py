"""The `segment` stage: Frame -> Segmentation (thesis 4.1).

1. finite points, outlier removal (filters.py; range-scaled radius by default)
2. the table: RANSAC planes, the support surface among them, its 2D convex hull, the
   polygonal prism of points above it (table.py)
3. supervoxels (VCCS, supervoxels.py) after cutting the voxel adjacency at depth
   discontinuities (edges.py, organized frames), and LCCP merging (lccp.py; a small
   segment standing on the table with a top of its own is kept); then the refinements
   of refine.STAGES, one signature each: an object standing on another's top split off
   (stacks.py), planar cuts through rising seams (cuts.py, after CPC), pieces of one
   object cut apart by a nearer one (occlusion.py, organized frames), two tops at two
   heights (steps.py), a container's inner and outer walls joined where they touch at
   the rim (rims.py) or form one rim from above (rings.py), and strips of a face seen
   edge-on joined to their object (fragments.py)
4. minimum-size filter (visible area in voxels, and a point count); objects lying flat,
   by colour (flat.py); the rims of open containers and the seen table edges (openings.py)

`segment` runs `STEPS`, a list of named steps, each a function of the frame's `_Work`,
timed by one `Clock` under its name; the sizes every step counts in are the frame's
`SegmentSize` (size.py), worked out once.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from clearcli.errors import SceneError
from clearcli.io.frames import Frame
from clearcli.perception.clock import Clock
from clearcli.perception.context import RefineContext, by_label
from clearcli.perception.edges import cut_depth_edges
from clearcli.perception.exclude import (
    AROUND_LEVEL_M,
    DEEP_INSIDE_M,
    at_cloud_border,
    at_image_border,
    beyond_outline,
    near_the_objects,
    not_standing,
    reach_beyond,
    row_mean,
    support_around,
)
from clearcli.perception.filters import clean_mask
from clearcli.perception.flat import differing_shares, flat_objects, support_colour, within_reach
from clearcli.perception.gaps import behind_the_gap, gap_behind
from clearcli.perception.lccp import lccp_segments
from clearcli.perception.openings import RIM_MAX_POINTS, Opening, TableEdge, rim_of, seen_edges
from clearcli.perception.orientation import Orientation, axes_turn, cloud_turn, quarter_turns_for
from clearcli.perception.refine import STAGES, refine
from clearcli.perception.resolution import WorkingGrid, pixel_pitch, stride_of_pitch
from clearcli.perception.size import SegmentSize
from clearcli.perception.supervoxels import Supervoxels, VoxelCloud, compute_supervoxels, voxelize
from clearcli.perception.table import (
    Lift,
    TableFit,
    beyond_the_edge,
    convex_hull_2d,
    find_table,
    hull_vertices,
    lift,
    polygon_area,
    project,
    squared_range,
    table_and_prism,
    unique_cells,
)
from clearcli.perception.types import Excluded, Segmentation, SegmentedObject, TablePlane
from clearcli.settings.segment import SegmentSettings
from clearcli.transforms import cross3

# colour_state(): a frame is "all black" or "all saturated" when this share of its points
# are (every channel at most _BLACK, or at least _SATURATED); "one flat value" when no
# channel varies by more than _FLAT_COLOR
_BAD_SHARE = 0.98
_BLACK = 8
_SATURATED = 250
_FLAT_COLOR = 2
# an unorganized cloud's points this near its footprint's edge are at its border, at
# least (exclude.at_cloud_border; as the image's border, `exclude._BORDER_PX` pixels)
_CLOUD_BORDER_M = 0.01


def in_plane_axes(table: TablePlane) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors (u, v) spanning ``table``'s plane, (u, v, normal) right-handed."""
    n = table.normal
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = cross3(helper, n)
    u /= np.linalg.norm(u)
    return u, cross3(n, u)


def table_aligned_box(
    points: np.ndarray,
    table: TablePlane,
    rests_below_m: float,
    uv: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Oriented bounding box with one axis on the table normal: (center, axes rows, extents).

    In-plane: the minimum-area rectangle of the projected points (rotating calipers over
    the 2D hull's edges), longer side first. Along the normal: from the lowest to the
    highest point, except that an object whose lowest point is within ``rests_below_m``
    of the table reaches down to the table (the prism cuts its bottom, and it stands on
    the table). ``uv``: `in_plane_axes` of ``table``, when the caller has them (the same
    for every object of a frame).
    """
    from scipy.spatial import QhullError

    n = table.normal
    u, v = in_plane_axes(table) if uv is None else uv
    xy = np.stack([points @ u, points @ v], axis=1)  # matvecs: fast for (N, 3)
    h = table.height_of(points)
    try:
        hull = xy[hull_vertices(xy)]
    except (QhullError, ValueError):
        hull = xy
    edges = np.concatenate([hull[1:], hull[:1]]) - hull  # np.roll(hull, -1, axis=0), without its overhead
    lens = np.linalg.norm(edges, axis=1)
    dirs = edges[lens > 1e-12] / lens[lens > 1e-12, None]
    if dirs.shape[0] == 0:
        dirs = np.array([[1.0, 0.0]])
    perp = np.stack([-dirs[:, 1], dirs[:, 0]], axis=1)  # +90 deg in (u, v), i.e. n x dir
    pa = hull @ dirs.T  # (K, D)
    pb = hull @ perp.T
    areas = (pa.max(0) - pa.min(0)) * (pb.max(0) - pb.min(0))
    best = int(np.argmin(areas))
    a1_2d = dirs[best]
    if np.ptp(pb[:, best]) > np.ptp(pa[:, best]):  # longer side first
        a1_2d = perp[best]
    a2_2d = np.array([-a1_2d[1], a1_2d[0]])
    c1, c2 = hull @ a1_2d, hull @ a2_2d
    ext = np.array([np.ptp(c1), np.ptp(c2)])
    mid = np.array([(c1.max() + c1.min()) / 2, (c2.max() + c2.min()) / 2])
    a1 = a1_2d[0] * u + a1_2d[1] * v
    a2 = a2_2d[0] * u + a2_2d[1] * v  # = n x a1
    centre_2d = mid[0] * a1 + mid[1] * a2
    lo = float(h.min())
    hi = float(h.max())
    if lo <= rests_below_m:
        lo = 0.0
    # a1, a2 are in-plane, so centre_2d has no normal component: the point of the plane
    # below it is centre_2d - offset * n
    center = centre_2d - table.offset * n + (lo + hi) / 2 * n
    axes = np.stack([a1, a2, n])
    extents = np.array([ext[0], ext[1], hi - lo])
    return center, axes, extents


def make_object(
    frame_indices: np.ndarray, points: np.ndarray, table: TablePlane, rests_below_m: float
) -> SegmentedObject:
    return make_objects([(frame_indices, points, rests_below_m)], table)[0]


def _scatter(c: np.ndarray) -> np.ndarray:
    """``c.T @ c`` of the centred points ``c``."""
    return c.T @ c


def make_objects(found: list[tuple[np.ndarray, np.ndarray, float]], table: TablePlane) -> list[SegmentedObject]:
    """`make_object` of each of ``found`` ((frame indices, points, rests_below_m) each), the
    same objects: the plane's axes worked out once, and the principal axes' (3, 3) scatter
    matrices decomposed in one call (NumPy's eigh runs LAPACK on each matrix of a stack in
    turn, the same vectors as a call of its own; the calls' overhead was a third of the
    time per object)."""
    uv = in_plane_axes(table)
    boxes = [table_aligned_box(p, table, rests, uv) for _, p, rests in found]
    centroids = [row_mean(p) for _, p, _ in found]
    many = [k for k, (_, p, _) in enumerate(found) if p.shape[0] >= 2]
    vecs_each: dict[int, np.ndarray] = {}
    if many:
        # c.T @ c of one array c (unit PCA axes, largest variance first, right-handed):
        # NumPy computes that product as a symmetric one (syrk), whose last bits differ
        # from a product of two arrays
        scatter = [_scatter(found[k][1] - centroids[k]) for k in many]
        vecs_each = dict(zip(many, np.linalg.eigh(np.stack(scatter))[1], strict=True))
    out = []
    for k, (idx, _, _) in enumerate(found):
        axes = np.eye(3)
        if k in vecs_each:
            axes = vecs_each[k][:, ::-1].T.copy()
            axes[2] = cross3(axes[0], axes[1])
        center, box_axes, extents = boxes[k]
        out.append(
            SegmentedObject(
                indices=idx.astype(np.int64),
                centroid=centroids[k],
                obb_center=center,
                obb_axes=box_axes,
                obb_extents=extents,
                principal_axes=axes,
            )
        )
    return out


def _without_what_lies_beyond(
    frame: Frame,
    idx: np.ndarray,
    pts: np.ndarray,
    fit: TableFit,
    table_mask: np.ndarray,
    prism_mask: np.ndarray,
    settings: SegmentSettings,
    lifted: Lift,
) -> tuple[TableFit, np.ndarray, np.ndarray, float]:
    """The table without the pieces of its plane seen beyond its own edge (table.py,
    `beyond_the_edge`): its hull drawn again round the rest, and the prism with it, so
    that a chair's back standing over a seat in the table's plane is no object (the
    same plane: ``lifted``, the points' `lift`, serves the new hull too).
    Returns (fit, table mask, prism mask, area of the plane dropped in m^2)."""
    assert frame.shape is not None  # an organized frame's only
    on_table = np.flatnonzero(table_mask)
    drop, solid = beyond_the_edge(
        frame.points, frame.shape, idx[on_table], fit.plane, settings, np.take(lifted.heights, on_table)
    )
    if not drop.any():
        return fit, table_mask, prism_mask, 0.0
    kept = np.take(pts, on_table[solid], axis=0)  # rows by index: take is faster than a[idx]
    kept = kept[fit.inside(kept)]  # the new hull lies within the old one
    if kept.shape[0] < 3:
        return fit, table_mask, prism_mask, 0.0
    before = polygon_area(fit.polygon_2d)
    fit = dataclasses.replace(fit, polygon_2d=convex_hull_2d(fit.to_2d(kept)))
    table_mask, prism_mask, _ = table_and_prism(pts, fit, settings, lifted=lifted)
    table_mask[on_table[drop]] = False
    return fit, table_mask, prism_mask, max(0.0, before - polygon_area(fit.polygon_2d))


def color_state(frame: Frame, organized: bool, settings: SegmentSettings) -> tuple[bool, str]:
    """(colour used, why or what for): segmentation runs on geometry alone, and says so,
    when the frame has no colour, when it is all black or all saturated (a camera whose
    exposure failed, a colour topic that never came), or when no stage would read it."""
    readers = [
        name
        for name, on in (
            ("supervoxels", settings.color_importance > 0),
            ("colour splits", settings.color_split),
            ("flat objects", settings.flat_objects and organized),
            ("containers' walls", settings.vessel_rebuild),
        )
        if on
    ]
    if frame.colors is None:
        return False, frame.color_note or "the frame has no colour: geometry alone"
    if frame.colors.shape != (frame.n_points, 3):
        return False, f"the colour has {frame.colors.shape[0]} rows for {frame.n_points} points: geometry alone"
    step = max(1, frame.n_points // 20000)  # a sample judges the whole image
    # column by column: the same tests as over the (N, 3) rows (all finite, max, min,
    # ptp), whose reductions along a row cost 4-5x more (1.4-1.9 -> 0.3 ms a 640x480
    # frame, timed in the supervoxels step: issue 39)
    points = frame.points[::step]
    finite = np.isfinite(points[:, 0])
    finite &= np.isfinite(points[:, 1])
    finite &= np.isfinite(points[:, 2])
    sample = frame.colors[::step]
    rgb = [np.compress(finite, sample[:, j]) for j in range(3)]
    if rgb[0].size == 0:
        return False, "no finite points"
    if np.mean(np.maximum(np.maximum(rgb[0], rgb[1]), rgb[2]) <= _BLACK) >= _BAD_SHARE:
        return False, "the colour is all black: geometry alone"
    if np.mean(np.minimum(np.minimum(rgb[0], rgb[1]), rgb[2]) >= _SATURATED) >= _BAD_SHARE:
        return False, "the colour is all saturated (white): geometry alone"
    channels = [c.astype(np.int16) for c in rgb]
    if max(int(c.max()) - int(c.min()) for c in channels) <= _FLAT_COLOR:
        return False, "the colour is one flat value: geometry alone"
    if not readers:
        return (
            False,
            "no stage reads colour with these settings (color_importance 0, color_split, flat_objects and vessel_rebuild off)",
        )
    return True, "read by: " + ", ".join(readers)


def _flat_objects(
    frame: Frame,
    table_idx: np.ndarray,
    obj_idx: np.ndarray,
    objects: list[SegmentedObject],
    fit: TableFit,
    settings: SegmentSettings,
    size: SegmentSize,
    support: tuple[np.ndarray, float] | None = None,
    below: np.ndarray | None = None,
) -> tuple[np.ndarray, list[SegmentedObject], list[tuple[SegmentedObject, np.ndarray]]]:
    """(table indices without the flat objects' points, the flat objects, the feet of
    ``objects``: (object, the foot's pixels) each): flat.py; ``support``:
    `support_colour` of ``table_idx`` when the caller has it; ``below``: the points
    under the prism's floor (`_below_prism`), looked at with the loose ones."""
    assert frame.colors is not None and frame.shape is not None  # an organized frame's, with usable colour
    # the points above the table that no object kept: np.setdiff1d(obj_idx, the objects'
    # indices, assume_unique=True) (obj_idx's own order), by a mask of the frame's pixels
    # instead of a sort of both (issue 39: 0.59 -> 0.18 ms on a cluttered table's 95k)
    taken = np.concatenate([o.indices for o in objects]) if objects else np.zeros(0, dtype=np.int64)
    is_taken = np.zeros(frame.n_points, dtype=bool)
    is_taken[taken] = True
    loose = np.compress(~np.take(is_taken, obj_idx), obj_idx)
    if below is not None and below.size:
        loose = np.concatenate([loose, below])
    cell = size.voxel_m

    def area(pixels: np.ndarray) -> float:
        xy = project(frame.points[pixels].astype(np.float64), fit.basis)
        return float(unique_cells(np.floor(xy / cell).astype(np.int64)).shape[0]) * cell * cell

    finds = flat_objects(
        frame.points,
        frame.colors,
        frame.shape,
        table_idx,
        loose,
        taken,
        lambda p: fit.plane.height_of(p.astype(np.float64)),
        area,
        settings.flat_min_color_delta,
        settings.flat_min_relief_m,
        settings.min_object_area_m2,
        settings.flat_max_area_m2,
        settings.flat_grow_min_m,
        support,
        [o.indices.size for o in objects] if settings.flat_feet else (),
    )
    found = finds.objects
    feet = [(objects[j], foot) for j, foot in finds.feet.items()]
    if not found:
        return table_idx, [], feet
    pixels = np.concatenate(found)
    table_idx = np.setdiff1d(table_idx, pixels, assume_unique=True)
    # lying on the table: the box reaches down to it
    made = [make_object(f, frame.points[f].astype(np.float64), fit.plane, np.inf) for f in found]
    return table_idx, made, feet


# an object whose foot (its pixels of its colour under the prism's floor, flat.py 5.)
# holds at least this share of its own points, and whose points lie low (`_lies_flat`),
# is a thing lying flat, most of it under the floor: its whole foot joins it, not only
# the points under its outline. On the support families' choose seeds (the four
# sensors) the feet of objects standing up hold 0.05-0.40 of their object's points
# (mOSD: at most 0.15), and those of things lying flat whose top the prism kept up to
# 0.42; of those it kept a speckle of, 0.69-46: 0.5 lies between, near the geometric
# mean of 0.42 and 0.69
_WHOLE_FOOT_RATIO = 0.5
# ... and lying low: its points' median height at most this far (m) above the prism's
# floor at their range. The things lying flat on those seeds: 0.5-3.6 mm; a bowl 4.6
# cm tall with a foot as large as itself (uois_image_0000, where the foot was a dark
# grain of the table's wood beside it, which a whole foot took): 16.4 mm. 8 mm lies
# between, near their geometric mean (7.7)
_FLAT_TOP_M = 0.008


def _lies_flat(obj_pts: np.ndarray, fit: TableFit, settings: SegmentSettings) -> bool:
    """Does the object of points ``obj_pts`` (camera frame, float64) lie low, its
    points' median height at most `_FLAT_TOP_M` above the prism's floor at their median
    range (the floor `table.lift` draws)?"""
    floor_m = settings.prism_min_height_m
    if fit.camera_is_origin:
        floor_m += settings.prism_noise_per_m2 * float(np.median(squared_range(obj_pts)))
    return float(np.median(fit.plane.height_of(obj_pts))) - floor_m <= _FLAT_TOP_M


def _with_feet(w: _Work) -> None:
    """5. the feet `_flat` found joined to their objects, if these were kept (flat.py,
    5.): after `_exclude`, which judges each object as the prism cut it. The grown objects'
    boxes in one `make_objects` and the table's indices cut once (issue 39: per object,
    a sort of the table's indices and a box of its own cost 3-4 ms a frame)."""
    fit = w.fit
    if not w.feet or fit is None:
        return
    feet = {id(obj): foot for obj, foot in w.feet}
    grown_at: list[int] = []
    found: list[tuple[np.ndarray, np.ndarray, float]] = []
    taken: list[np.ndarray] = []
    for k, obj in enumerate(w.objects):
        foot = feet.get(id(obj))
        if foot is None:
            continue
        # np.setdiff1d(foot, obj.indices): the same sorted unique pixels, the object's own
        # looked up in a table of its pixel range instead of sorted with the foot's (the
        # sort of a large object's every index was a third of the step, issue 39)
        foot = np.unique(foot)
        foot = foot[np.isin(foot, obj.indices, invert=True, kind="table")]
        # the points gathered once, by take (several times faster than a[idx]): the
        # grown object's are the object's and the foot's kept ones, in that order
        obj_pts = np.take(w.frame.points, obj.indices, axis=0).astype(np.float64)
        foot_pts = np.take(w.frame.points, foot, axis=0).astype(np.float64)
        if foot.size >= _WHOLE_FOOT_RATIO * obj.indices.size and _lies_flat(obj_pts, fit, w.settings):
            # a thing lying flat, most of it under the prism's floor: the prism kept a
            # speckle of its top's highest points, no outline of it; the foot is the thing
            inside = np.ones(foot.size, dtype=bool)
        else:
            # held to the object's own outline: a foot's mixed points beyond it widened the box
            inside = within_reach(
                project(obj_pts, fit.basis), project(foot_pts, fit.basis), w.settings.flat_foot_reach_m
            )
        foot = np.compress(inside, foot)
        if not foot.size:
            continue
        taken.append(foot)
        grown = np.concatenate([obj.indices, foot])
        # its foot stands on the table: the box reaches down to it
        grown_at.append(k)
        found.append((grown, np.concatenate([obj_pts, np.compress(inside, foot_pts, axis=0)]), np.inf))
    if not found:
        return
    # one cut by all the feet: the same indices in the same order as a cut per foot
    w.table_idx = np.setdiff1d(w.table_idx, np.unique(np.concatenate(taken)), assume_unique=True)
    for k, obj in zip(grown_at, make_objects(found, fit.plane), strict=True):
        w.objects[k] = obj


def _empty() -> np.ndarray:
    return np.zeros(0, dtype=np.int64)


@dataclass
class _Work:
    """One frame on its way through `STEPS`: what each step leaves for the next."""

    frame: Frame
    settings: SegmentSettings
    organized: bool  # the frame's pixel grid is usable
    clock: Clock
    may_roll: bool = False  # the table step may find the image rolled (`_Rolled`)
    idx: np.ndarray = field(default_factory=_empty)  # (K,) frame index of the points kept (finite, not outliers)
    pts: np.ndarray = field(default_factory=_empty)  # (K, 3) their coordinates
    fit: TableFit | None = None
    table_mask: np.ndarray = field(default_factory=_empty)  # (K,) on the table
    prism_mask: np.ndarray = field(default_factory=_empty)  # (K,) above it, inside its hull
    heights: np.ndarray = field(default_factory=_empty)  # (K,) height above the table's plane
    range2: np.ndarray | None = None  # (K,) squared range from the sensor (a camera frame's only)
    lifted: Lift | None = None  # the table's plane against the kept points (table.lift)
    beyond_m2: float = 0.0
    obj_idx: np.ndarray = field(default_factory=_empty)  # (M,) frame index of the points above the table
    obj_pts: np.ndarray = field(default_factory=_empty)  # (M, 3)
    color_used: bool = False
    color_note: str = ""
    size: SegmentSize | None = None
    vox: VoxelCloud | None = None  # None: too few points above the table to segment
    sv: Supervoxels | None = None
    seg_of_voxel: np.ndarray = field(default_factory=_empty)
    ctx: RefineContext | None = None  # what LCCP and the refinements read (`_lccp` makes it)
    objects: list[SegmentedObject] = field(default_factory=list)
    table_idx: np.ndarray = field(default_factory=_empty)
    openings: tuple[Opening, ...] = ()
    table_edges: tuple[TableEdge, ...] = ()
    excluded: list[Excluded] = field(default_factory=list)
    # flat.py's feet of the objects: (object, the foot's pixels), joined after _exclude
    feet: list[tuple[SegmentedObject, np.ndarray]] = field(default_factory=list)
    # flat.support_colour of the table's pixels: (those pixels, CIELAB centre, threshold)
    support_rgb: tuple[np.ndarray, np.ndarray, float] | None = None


# A depth sensor's points lie within some 10 m of it, a table scene's within a few: a
# frame whose points lie a median this far from its origin is in another unit (in
# millimetres a table scene lies 300 to 3000 units away), five times over either way.
_FAR_MEDIAN_M = 50.0


def _unit_hint(points: np.ndarray) -> str:
    """A clause for a "no table" message when ``points`` lie so far from the origin that
    they are likely millimetres (`_FAR_MEDIAN_M`); "" otherwise."""
    sample = np.asarray(points[:: max(1, points.shape[0] // 10000)], dtype=np.float64)
    sample = sample[np.isfinite(sample).all(axis=1)]
    if sample.shape[0] == 0:
        return ""
    median = float(np.median(np.linalg.norm(sample, axis=1)))
    if median <= _FAR_MEDIAN_M:
        return ""
    return (
        f"; its points lie a median {median:.0f} m from the origin, beyond any depth sensor's reach: "
        "if they are millimetres, scale them to metres (x 0.001)"
    )


def _filter(w: _Work) -> None:
    """1. finite points, outliers (filters.py)."""
    where = f"{w.frame.source}: " if w.frame.source else ""
    points = w.frame.points
    keep = clean_mask(points, w.frame.shape if w.organized else None, w.settings)
    w.idx = np.flatnonzero(keep)
    if w.idx.size == 0:
        if not np.isfinite(points).all(axis=1).any():
            raise SceneError(f"{where}the frame has no finite points (all NaN)")
        raise SceneError(f"{where}no table: no points are left after outlier removal{_unit_hint(points)}")
    w.pts = np.take(points, w.idx, axis=0).astype(np.float64)  # rows by index: take is faster than a[idx]


def _table(w: _Work) -> None:
    """2. the table, its hull, the prism above it (table.py)."""
    frame = w.frame

    def pinhole() -> bool:
        # a pinhole's grid about the origin: a camera image in its optical frame (resolution.py)
        return w.organized and frame.shape is not None and pixel_pitch(frame.points, frame.shape) is not None

    try:
        fit = find_table(
            w.pts,
            w.settings,
            w.organized,
            frame.source,
            pinhole,
            upright_check=not w.may_roll,
            # only a camera image may be turned for its support (an unorganized cloud's turn
            # is cloud_turn's, told by its view)
            needs_turn=(lambda normal: quarter_turns_for(normal) != 0) if w.may_roll and w.organized else None,
        )
    except SceneError as err:
        hint = _unit_hint(w.pts)
        if not hint:
            raise
        raise SceneError(f"{err}{hint}") from None
    if w.may_roll and fit.camera_is_origin:
        # a camera image the wrong way up, or an unorganized cloud in another axis convention
        # or rolled: turned and segmented again (orientation.py)
        turn = quarter_turns_for(fit.plane.normal) if w.organized else cloud_turn(w.pts, fit.plane.normal)
        if turn:
            raise _Rolled(turn)
    # heights and squared ranges of the kept points: the table's stage and _exclude read them
    w.range2 = squared_range(w.pts) if fit.camera_is_origin else None
    # the plane against the points once: a hull drawn anew and _exclude read it again
    w.lifted = lift(w.pts, fit, w.settings, w.range2)
    table_mask, prism_mask, w.heights = table_and_prism(w.pts, fit, w.settings, lifted=w.lifted)
    if w.organized and w.settings.beyond_edge_check:
        fit, table_mask, prism_mask, w.beyond_m2 = _without_what_lies_beyond(
            w.frame, w.idx, w.pts, fit, table_mask, prism_mask, w.settings, w.lifted
        )
    w.fit, w.table_mask, w.prism_mask = fit, table_mask, prism_mask


def _voxels(w: _Work) -> None:
    """3. the points above the table, whether their colour is usable, the frame's sizes
    (fitted to an unorganized cloud's density), the voxel grid."""
    w.obj_idx = w.idx[w.prism_mask]
    w.color_used, w.color_note = color_state(w.frame, w.organized, w.settings)
    w.obj_pts = np.compress(w.prism_mask, w.pts, axis=0)  # rows by a mask: compress is several times faster
    w.size = SegmentSize.of(w.settings, None if w.organized else w.obj_pts)
    if w.obj_pts.shape[0] < 4:
        return
    # the supervoxels read colour only where it is usable (not all black, saturated or flat)
    colors = w.frame.colors if (w.color_used and w.settings.color_importance > 0) else None
    colors = np.take(colors, w.obj_idx, axis=0) if colors is not None else None  # take: several times faster
    # the points' scatter per voxel only for the normals that read it (normal_stencil)
    w.vox = voxelize(w.obj_pts, w.size.voxel_m, colors, scatter=w.settings.normal_stencil)


def _depth_edges(w: _Work) -> None:
    """3a'. the voxel adjacency cut at depth discontinuities (edges.py, organized)."""
    if w.organized and w.settings.depth_edges:
        vox, shape, size = w.vox, w.frame.shape, w.size
        assert vox is not None and shape is not None and size is not None  # above the table, organized, sized
        w.vox = cut_depth_edges(
            vox,
            w.frame.points,
            shape,
            w.obj_idx,
            w.settings.depth_edge_rel,
            size.min_edge_piece_voxels,
            xyz=w.obj_pts,  # the frame's points at obj_idx, in float64 (_filter, _voxels)
        )


def _supervoxels(w: _Work) -> None:
    """3a. supervoxels (supervoxels.py), seen from the camera, or from above the table's
    middle for a cloud in the table's frame."""
    fit, vox = w.fit, w.vox
    assert fit is not None and vox is not None  # the table's and the voxels' steps ran
    viewpoint = np.zeros(3) if fit.camera_is_origin else fit.polygon.mean(axis=0) + 1.0 * fit.plane.normal
    w.sv = compute_supervoxels(vox, viewpoint, w.settings, w.size)


def _lccp(w: _Work) -> None:
    """3b. LCCP (lccp.py): a small segment standing on the table with a top of its own
    is kept. The refinements' `RefineContext` is made here, before them: LCCP reads its
    voxel heights and supervoxel colours, the very numbers the refinements read again
    (the same plane and voxels; the same points, labels and `flat.group_lab` arithmetic),
    worked out once (issue 39)."""
    fit, vox, sv, size = w.fit, w.vox, w.sv, w.size
    assert fit is not None and vox is not None and sv is not None and size is not None  # the steps before ran
    plane = fit.plane
    ctx = w.ctx = RefineContext(w.frame, w.organized, vox, sv, plane, w.settings, size, w.obj_idx, w.color_used)
    voxel_h = ctx.voxel_height
    sv_low = np.full(sv.centroids.shape[0], np.inf)
    np.minimum.at(sv_low, sv.voxel_label, voxel_h)
    sv_high = np.full(sv.centroids.shape[0], -np.inf)
    np.maximum.at(sv_high, sv.voxel_label, voxel_h)
    # group_lab of the points by supervoxel, as ctx.sv_lab sums them (None without usable
    # colour): one pass over the points for LCCP, the colour splits and the voxels' colour
    sv_lab = ctx.sv_lab if w.settings.lccp_color_delta > 0 else None
    seg_of_sv = lccp_segments(sv, w.settings, sv_low, sv_high, plane.normal, size, sv_lab, vox, ctx.sv_edge_shape)
    w.seg_of_voxel = seg_of_sv[sv.voxel_label]


def _refine(w: _Work) -> None:
    """3c. the refinements after LCCP, each a stage of refine.STAGES timed by its name,
    on `_lccp`'s context."""
    assert w.ctx is not None  # LCCP's step ran
    w.seg_of_voxel = refine(w.seg_of_voxel, w.ctx, w.clock)


def _objects(w: _Work) -> None:
    """4. the size filter (visible area in voxels, and a point count), largest first,
    and each object's box."""
    settings, fit, vox, size = w.settings, w.fit, w.vox, w.size
    assert fit is not None and vox is not None and size is not None  # the steps before ran
    seg_of_voxel = w.seg_of_voxel
    seg_of_point = np.take(seg_of_voxel, vox.point_voxel)  # take: several times faster than a[idx]
    n_seg = int(seg_of_voxel.max()) + 1 if seg_of_voxel.size else 0
    seg_voxels = np.bincount(seg_of_voxel, minlength=n_seg)
    seg_points = np.bincount(seg_of_point, minlength=n_seg)
    ok = size.holds_object_area(seg_voxels) & (seg_points >= settings.min_object_points)
    kept = np.flatnonzero(ok)
    kept = kept[np.argsort(-seg_points[kept], kind="stable")]  # largest first
    order = by_label(seg_of_point, n_seg)  # a stable argsort (by radix: 100k points on a cluttered table)
    # where each segment's points start in ``order``: the counts' running sum (what a
    # binary search of the sorted labels gave, without gathering them: issue 39, 0.12 ms
    # of a cluttered table's 95k points)
    bounds = np.concatenate([[0], np.cumsum(seg_points)])
    rests = settings.prism_min_height_m + settings.plane_distance_m
    # the points' squared ranges from the table's step (einsum's sums are the same per row
    # on a part of the rows as on all of them)
    obj_range2 = w.range2[w.prism_mask] if w.range2 is not None else None
    found = []
    for s in kept.tolist():
        members = order[bounds[s] : bounds[s + 1]]
        p = np.take(w.obj_pts, members, axis=0)  # rows by index: take is several times faster than a[idx]
        # the prism's lower bound grew with range: so does "resting on the table"
        noise = 0.0
        if fit.camera_is_origin:
            r2 = np.take(obj_range2, members) if obj_range2 is not None else squared_range(p)
            noise = settings.prism_noise_per_m2 * float(np.min(r2))
        found.append((np.take(w.obj_idx, members), p, rests + noise))
    w.objects.extend(make_objects(found, fit.plane))


def _below_prism(w: _Work) -> np.ndarray:
    """The frame's indices of the points over the support, above its band
    (``plane_distance_m``) and under the prism's floor (``prism_min_height_m``, growing
    with range): neither table nor object. A notebook or a tablet lying flat (6-20 mm
    thick) has most of its top there, a Kinect or a RealSense a metre away scattering it
    over the band, this layer and the prism; the flat objects' step reads them with the
    table's and the loose points, so that such a thing is found whole (flat.py)."""
    fit, settings, lifted = w.fit, w.settings, w.lifted
    assert fit is not None and lifted is not None  # the table's step ran
    h = w.heights
    # above the band (so no table point) and in no prism's band (so no object point)
    # up to its top: under its floor, which lift drew (not drawn again here)
    layer = h > settings.plane_distance_m
    layer &= ~lifted.band
    layer &= h <= settings.prism_max_height_m
    rows, xy = _in_plane(w, layer)
    return np.take(w.idx, np.compress(fit.inside_2d(xy, settings.hull_margin_m), rows))


def _flat(w: _Work) -> None:
    """4'. objects lying flat, found by colour (flat.py; organized frames)."""
    w.table_idx = w.idx[w.table_mask]
    if w.color_used and w.settings.flat_objects and w.organized:
        assert w.fit is not None and w.size is not None  # the table's and the voxels' steps ran
        assert w.frame.colors is not None and w.frame.shape is not None  # colour used on a pixel grid
        support = None
        if w.table_idx.size >= 100:  # flat_objects's and _off_colour's own condition
            # worked out once: _off_colour reads it again when no flat object changed the table
            support = support_colour(w.frame.colors, w.frame.shape, w.table_idx, w.settings.flat_min_color_delta)
            w.support_rgb = (w.table_idx, *support)
        w.table_idx, found, w.feet = _flat_objects(
            w.frame, w.table_idx, w.obj_idx, w.objects, w.fit, w.settings, w.size, support, _below_prism(w)
        )
        w.objects.extend(found)


def _exclude(w: _Work) -> None:
    """4''. only what stands on the support is an object (exclude.py): what reaches in
    from beyond its outline, hangs above it, or stands on such a thing is set aside; so
    is what stands beyond a gap across the support with a step at it (gaps.py)."""
    fit, settings = w.fit, w.settings
    assert fit is not None  # the table's step ran
    if not settings.exclude_not_standing or not w.objects:
        return
    pts = w.pts
    h = w.heights  # fit.plane.height_of(pts): the hull changed after the table's stage, not the plane
    rng2 = w.range2 if w.range2 is not None else np.zeros(pts.shape[0])
    low = settings.prism_min_height_m + settings.prism_noise_per_m2 * rng2
    above, above_xy = _in_plane(w, ~w.prism_mask & ~w.table_mask & (h > low) & (h <= settings.prism_max_height_m))
    out = ~fit.inside_2d(above_xy, settings.hull_margin_m)
    out_sel = np.compress(out, above)
    outside = np.take(pts, out_sel, axis=0)
    # how far what lies outside reaches beyond the outline, along the pixel grid
    reach = reach_beyond(
        outside,
        w.idx[out_sel] if w.organized else None,
        w.frame.shape[1] if w.organized and w.frame.shape is not None else 0,
        beyond_outline(np.compress(out, above_xy, axis=0), fit.polygon_2d),
    )
    # every object's points gathered at once (take: faster than a[idx]), split back: the
    # same rows per object, without a gather and a cast of its own each
    sizes = [o.indices.size for o in w.objects]
    every = np.take(w.frame.points, np.concatenate([o.indices for o in w.objects]), axis=0).astype(np.float64)
    below = np.flatnonzero(~w.table_mask & (h < -low))
    below_pts = np.take(pts, below, axis=0)
    # beyond the outline: tested only on those not_standing reads (near the objects), as
    # a part of them all (the same test, raster or exact, as theirs)
    near_pts = near_the_objects(below_pts, every)
    outside_below = np.compress(
        ~fit.inside(near_pts, settings.hull_margin_m, of_n=below_pts.shape[0]), near_pts, axis=0
    )  # rows by a mask
    # an even sample of the table's points: no copy of every one first
    support_rows, support_xy = _in_plane(w, w.table_mask, max(1, int(np.count_nonzero(w.table_mask)) // 50000))
    rests = settings.prism_min_height_m + settings.plane_distance_m

    def rests_m(p: np.ndarray) -> float:
        if not fit.camera_is_origin:
            return rests
        return rests + settings.prism_noise_per_m2 * float(np.min(np.einsum("ij,ij->i", p, p)))

    verdicts = not_standing(
        np.split(every, np.cumsum(sizes)[:-1]),
        outside,
        outside_below,
        support_xy,
        fit.plane.height_of,
        fit.to_2d,
        lambda xy: fit.inside_2d(xy, settings.hull_margin_m - 0.02),
        rests_m,
        reach,
        at_image_border([o.indices for o in w.objects], w.frame.shape)
        if w.organized
        else _at_cloud_border(w, every, sizes)
        if settings.exclude_cloud_border
        else None,
        _support_around(w) if w.organized else None,
        lambda xy: fit.inside_2d(xy, -DEEP_INSIDE_M),
        below=below_pts,
        off_colour=_off_colour(w),
        border_edge="the image's border" if w.organized else "the cloud's edge",
    )
    gone = {v.index: v.reason for v in verdicts}
    # a desk or a table behind at nearly the support's level is one plane with it: a gap
    # across the support with a step at it tells them apart (gaps.py)
    if fit.camera_is_origin and len(gone) < len(w.objects):
        gap = gap_behind(support_xy, np.take(h, support_rows), fit.to_2d(np.zeros((1, 3)))[0], fit.polygon_2d)
        if gap is not None:
            objects_xy = np.split(fit.to_2d(every), np.cumsum(sizes)[:-1])
            for k in behind_the_gap(gap, objects_xy):
                gone.setdefault(k, gap.why())
    if not gone:
        return
    w.excluded = [Excluded(o.indices, o.centroid, gone[k]) for k, o in enumerate(w.objects) if k in gone]
    w.objects = [o for k, o in enumerate(w.objects) if k not in gone]


def _at_cloud_border(w: _Work, every: np.ndarray, sizes: list[int]) -> list[np.ndarray]:
    """`exclude.at_cloud_border` of the objects (``every``: their points, ``sizes`` each)
    in an unorganized cloud: within twice the voxel's side (the voxel fitted to the
    cloud's density), at least `_CLOUD_BORDER_M`, of its footprint's edge."""
    fit, size = w.fit, w.size
    assert fit is not None and size is not None  # the table's and the voxels' steps ran
    border_m = max(_CLOUD_BORDER_M, 2.0 * size.voxel_m)
    return at_cloud_border(np.split(fit.to_2d(every), np.cumsum(sizes)[:-1]), fit.to_2d(w.pts), border_m)


def _in_plane(w: _Work, mask: np.ndarray, step: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """(the kept points in ``mask`` (every ``step``-th), their (N, 2) ``fit.to_2d``): read
    from the table step's `Lift` when they are all among its candidates (what lies above
    the support, its own points: the same bits), projected otherwise."""
    fit, lifted = w.fit, w.lifted
    assert fit is not None  # the table's step ran
    if lifted is not None and lifted.serves(fit):
        on_cand = np.take(mask, lifted.cand)
        if np.count_nonzero(on_cand) == np.count_nonzero(mask):
            at = np.flatnonzero(on_cand)[::step]
            return np.take(lifted.cand, at), np.stack([np.take(lifted.x, at), np.take(lifted.y, at)], axis=1)
    rows = np.flatnonzero(mask)[::step]
    return rows, fit.to_2d(np.take(w.pts, rows, axis=0))  # rows by index: take is faster than a[idx]


def _off_colour(w: _Work) -> list[float] | None:
    """Per object, the share of its pixels whose colour differs from the support's
    (flat.py's test; exclude.py's fringes); None without usable colour on a pixel grid."""
    colors, shape = w.frame.colors, w.frame.shape
    if not (w.color_used and w.organized) or colors is None or shape is None or w.table_idx.size < 100:
        return None
    if w.support_rgb is not None and w.support_rgb[0] is w.table_idx:  # _flat's, of these very pixels
        centre, threshold = w.support_rgb[1], w.support_rgb[2]
    else:
        centre, threshold = support_colour(colors, shape, w.table_idx, w.settings.flat_min_color_delta)
    return differing_shares(colors, [o.indices for o in w.objects], centre, threshold)


def _support_around(w: _Work) -> list[tuple[int, int]]:
    """exclude.support_around on the frame's pixel grid: a pixel counts when its point was
    kept by the filter, lies outside the prism and within `AROUND_LEVEL_M` of the support's
    level (where the support would be seen if it went on there); the support's are the
    table's points."""
    fit, shape = w.fit, w.frame.shape
    assert fit is not None and shape is not None  # the table's step ran; organized

    def state(pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # each pixel's kept point (-1: none) from a map of the frame's pixels: the rings'
        # pixels come in no order, and binary searches of them in w.idx cost several
        # times more than writing the map
        kept_at = np.full(w.frame.n_points, -1, dtype=np.int32)  # int32: a frame's pixels fit, half the writes
        kept_at[w.idx] = np.arange(w.idx.size, dtype=np.int32)
        j = np.take(kept_at, pixels)
        kept = j >= 0
        jk = j[kept]
        counts, support = np.zeros(pixels.size, dtype=bool), np.zeros(pixels.size, dtype=bool)
        # gathers by take: several times faster than a[idx]; the heights the table's step
        # took (the same plane: a row's product does not depend on the rows around it)
        counts[kept] = ~np.take(w.prism_mask, jk) & (np.abs(np.take(w.heights, jk)) <= AROUND_LEVEL_M)
        support[kept] = np.take(w.table_mask, jk)
        return counts, support

    return support_around([o.indices for o in w.objects], shape, state)


def _openings(w: _Work) -> None:
    """What the grasps beyond the pinch need: rims of open containers, seen table edges
    (openings.py)."""
    fit = w.fit
    assert fit is not None  # the table's step ran
    # rim_of looks at an even sample of a large object's points: only those are gathered
    # (the same rows as its own sampling takes)
    w.openings = tuple(
        rim_of(np.take(w.frame.points, o.indices[:: max(1, -(-o.indices.size // RIM_MAX_POINTS))], axis=0), fit.plane)
        for o in w.objects
    )
    w.table_edges = seen_edges(w.frame.points, w.frame.shape, fit.plane, fit.polygon)


@dataclass(frozen=True)
class Step:
    name: str | None  # its key in the timings (steps of one name add up); None: it times its own parts
    run: Callable[[_Work], None]
    above_table: bool = False  # needs points above the table: skipped (0 s) without them


STEPS: tuple[Step, ...] = (
    Step("filter", _filter),
    Step("table", _table),
    Step("supervoxels", _voxels),
    Step("edges", _depth_edges, above_table=True),
    Step("supervoxels", _supervoxels, above_table=True),
    Step("lccp", _lccp, above_table=True),
    Step(None, _refine, above_table=True),  # each stage of refine.STAGES by its name
    Step("objects", _objects, above_table=True),
    Step("flat", _flat),
    Step("exclude", _exclude),
    Step("flat", _with_feet),
    Step("openings", _openings),
)
STAGE_NAMES = tuple(st.name for st in STAGES)
# "merge": every refinement but the planar cuts, together (each is also timed apart)
MERGED = tuple(name for name in STAGE_NAMES if name != "cuts")
# the timings' keys, in the order the JSON reports them
TIMINGS = (
    "filter",
    "table",
    "supervoxels",
    "lccp",
    "merge",
    "edges",
    *STAGE_NAMES,
    "flat",
    "objects",
    "exclude",
    "openings",
    "total",
)


def segment(frame: Frame, settings: SegmentSettings, stride: int | None = None) -> Segmentation:
    """Segment the objects on the table of ``frame``: the steps of `STEPS` in order,
    each timed by its name (`Segmentation.timings_s`, keys `TIMINGS`).

    An organized frame far denser than the voxel grid (a RealSense at 1280x720) is
    segmented on its every k-th row and column and the labels carried back to every
    pixel (resolution.py; ``stride`` forces k, 1 every pixel); 640x480 frames keep k = 1.

    Raises SceneError when there is no usable table (no finite points, no plane, a table
    seen from below). A table with nothing on it is a result with zero objects.
    """
    # an image in another axis convention, moved or rolled, is segmented as the upright
    # optical image it is turned into, and the results turned back (orientation.py). An
    # organized frame whose pixel pitch reads (a pinhole's grid in its optical frame: what
    # almost every camera writes) needs no turn, and that pitch gives the working grid's
    # stride, read once (issue 39: 1.8 ms a 640x480 frame)
    shape = frame.grid
    pitch = pixel_pitch(frame.points, shape) if shape is not None else None
    turn = None if pitch is not None else axes_turn(frame)
    for may_roll in (True, False):
        work = frame if turn is None else turn.frame(frame)
        k = stride
        if k is None and turn is None:
            k = stride_of_pitch(pitch, settings)  # choose_stride's, from the pitch read above
        grid = WorkingGrid.of(work, settings, k)
        try:
            seg = grid.to_full_nominal(_segment(grid.frame, settings, may_roll), settings)
        except _Rolled as rolled:
            if isinstance(rolled.turn, Orientation):
                turn = rolled.turn  # an unorganized cloud: no turn before this one
            else:
                turn = (turn or Orientation()).rolled(rolled.turn)
            continue
        return seg if turn is None or turn.identity else turn.segmentation_back(seg, frame)
    raise AssertionError("unreachable: the second pass may not roll")  # pragma: no cover


class _Rolled(Exception):
    """The table step's finding that the image is rolled (orientation.quarter_turns_for:
    how many quarter turns), or that an unorganized cloud is to be turned (cloud_turn: the
    turn): `segment` turns it and starts again."""

    def __init__(self, turn: int | Orientation) -> None:
        super().__init__(turn)
        self.turn = turn


def _segment(frame: Frame, settings: SegmentSettings, may_roll: bool = False) -> Segmentation:
    """`segment` on the frame as given (the working grid); ``may_roll``: the table step
    raises `_Rolled` when the image is rolled, rather than reading it as it is."""
    clock = Clock(TIMINGS[:-1])
    points = frame.points
    if points.ndim != 2 or points.shape[1] != 3 or points.shape[0] == 0:
        where = f"{frame.source}: " if frame.source else ""
        raise SceneError(f"{where}the frame holds no points")
    w = _Work(frame, settings, frame.grid is not None, clock, may_roll=may_roll)
    for step in STEPS:
        if step.above_table and w.vox is None:
            continue
        if step.name is None:
            step.run(w)
        else:
            with clock(step.name):
                step.run(w)
    clock.total("merge", MERGED)
    clock.timings["total"] = clock.elapsed()
    fit = w.fit
    assert fit is not None  # the table's step ran (or raised)
    return Segmentation(
        n_points=frame.n_points,
        table=fit.plane,
        table_polygon=fit.polygon,
        table_indices=w.table_idx,
        objects=tuple(w.objects),
        timings_s=clock.timings,
        support=fit.planes,
        beyond_edge_m2=w.beyond_m2,
        color_used=w.color_used,
        color_note=w.color_note,
        openings=w.openings,
        table_edges=w.table_edges,
        excluded=tuple(w.excluded),
        source=frame.source,
        frame_id=frame.frame_id,
        stamp_s=frame.stamp_s,
    )
