"""Families of self-made scenes that test segmentation where it is hardest for clearing:
small objects (the 3-7 cm a gripper takes) on and against larger ones, equal-height
objects across narrow gaps, dense mixes, open containers, and objects too wide for the
gripper (bowls, mugs with handles, plates, flat boxes) among small ones.

Every family is a pure function ``family(seed) -> Scene``: sizes and poses drawn from
``seed``, the same seed giving the same scene. `FAMILIES` names them for the benchmark
and tests. Choose settings on seeds 0-99 (`CHOOSE_SEEDS`) and report on 1000-1099
(`REPORT_SEEDS`), which are not looked at while choosing.

Frames and conventions are those of `clearcli.sim.scene` (table frame: z up, +y away
from the camera).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from functools import partial

import numpy as np

from clearcli.io.frames import LABEL_NONE, LABEL_TABLE, Frame, object_label
from clearcli.settings.sim import DepthNoise, PinholeCamera
from clearcli.sim.camera import FLOOR_BELOW_TABLE_M, KINECT, render
from clearcli.sim.scene import (
    MAX_WIDTH_M,
    MIN_WIDTH_M,
    Box,
    Cylinder,
    Scene,
    SceneObject,
    Table,
    _in_region,
    _place_touching,
    _rows,
    camera_pose_T_camera_table,
    make_scene,
    objects_overlap,
)

CHOOSE_SEEDS = range(0, 100)
REPORT_SEEDS = range(1000, 1100)

# Gaps of the rows (m): 3 mm is about one depth step of the sensor at 0.9 m seen across
# the line of sight, 10 mm is two voxels.
GAPS_M = (0.003, 0.005, 0.010)


def _small(rng: np.random.Generator, object_id: int, max_height_m: float = 0.12) -> SceneObject:
    """A graspable object: a box or a cylinder 3-7 cm wide."""
    height = float(rng.uniform(0.04, max_height_m))
    yaw = float(rng.uniform(-math.pi / 2, math.pi / 2))
    if rng.random() < 0.4:
        radius = float(rng.uniform(MIN_WIDTH_M, MAX_WIDTH_M)) / 2
        return Cylinder(object_id, round(radius, 4), round(height, 4), 0.0, 0.0, round(yaw, 4))
    sx, sy = rng.uniform(MIN_WIDTH_M, MAX_WIDTH_M, size=2)
    return Box(object_id, round(float(sx), 4), round(float(sy), 4), round(height, 4), 0.0, 0.0, round(yaw, 4))


def _inside(inner: SceneObject, outer: Box, margin_m: float) -> bool:
    """Is the footprint of ``inner`` within the top of box ``outer`` (``margin_m`` in)?"""
    c, s = math.cos(outer.yaw_rad), math.sin(outer.yaw_rad)
    rel = inner.footprint() - np.array([outer.x_m, outer.y_m])
    local = rel @ np.array([[c, -s], [s, c]])  # rotate by -yaw
    return bool(
        (np.abs(local[:, 0]) <= outer.size_x_m / 2 - margin_m).all()
        and (np.abs(local[:, 1]) <= outer.size_y_m / 2 - margin_m).all()
    )


def _flat_box(rng: np.random.Generator, object_id: int) -> Box:
    """A large flat box (a tray, a board game): 16-26 x 12-18 x 3-5 cm."""
    return Box(
        object_id,
        round(float(rng.uniform(0.16, 0.26)), 4),
        round(float(rng.uniform(0.12, 0.18)), 4),
        round(float(rng.uniform(0.03, 0.05)), 4),
        round(float(rng.uniform(-0.08, 0.08)), 4),
        round(float(rng.uniform(-0.05, 0.05)), 4),
        round(float(rng.uniform(-0.5, 0.5)), 4),
    )


def _on_top(rng: np.random.Generator, small: SceneObject, lower: Box) -> SceneObject:
    """``small`` standing at a random place on the top of ``lower``, wholly on it."""
    c, s = math.cos(lower.yaw_rad), math.sin(lower.yaw_rad)
    for _ in range(200):
        lx = rng.uniform(-lower.size_x_m / 2, lower.size_x_m / 2)
        ly = rng.uniform(-lower.size_y_m / 2, lower.size_y_m / 2)
        cand = replace(
            small,
            x_m=round(float(lower.x_m + c * lx - s * ly), 4),
            y_m=round(float(lower.y_m + s * lx + c * ly), 4),
            base_z_m=lower.top_z_m,
        )
        if _inside(cand, lower, 0.005):
            return cand
    raise ValueError("no room on the lower object")  # pragma: no cover - sizes always fit


def small_on_large(seed: int) -> Scene:
    """One graspable object standing on a large flat box."""
    rng = np.random.default_rng(seed)
    lower = _flat_box(rng, 0)
    upper = _on_top(rng, _small(rng, 1, max_height_m=0.10), lower)
    return make_scene(f"small_on_large({seed})", [lower, upper])


def small_against_tall(seed: int) -> Scene:
    """A graspable object touching a taller, larger one, on the side the camera sees (in
    front or to a side, never hidden behind it)."""
    rng = np.random.default_rng(seed)
    tall_h = float(rng.uniform(0.15, 0.25))
    if rng.random() < 0.3:
        tall: SceneObject = Cylinder(0, round(float(rng.uniform(0.04, 0.06)), 4), round(tall_h, 4), 0.0, 0.05)
    else:
        tall = Box(
            0,
            round(float(rng.uniform(0.08, 0.16)), 4),
            round(float(rng.uniform(0.06, 0.10)), 4),
            round(tall_h, 4),
            0.0,
            0.05,
            round(float(rng.uniform(-0.4, 0.4)), 4),
        )
    small = _small(rng, 1, max_height_m=min(0.12, 0.7 * tall_h))
    # -y is towards the camera: in front is -90 degrees; keep within 75 degrees of it
    direction = -math.pi / 2 + float(rng.uniform(-1.3, 1.3))
    if isinstance(tall, Box) and isinstance(small, Box) and rng.random() < 0.5:
        small = replace(small, yaw_rad=tall.yaw_rad)  # face to face
    return make_scene(f"small_against_tall({seed})", [tall, _place_touching(small, tall, direction)])


def gap_row(seed: int, gap_m: float, away: bool) -> Scene:
    """Two or three boxes of equal height 5 cm wide across the gaps, ``gap_m`` apart.

    ``away``: the gaps run away from the camera (boxes side by side along x, the table
    seen through the gap); else across the line of sight (boxes one behind the other)."""
    rng = np.random.default_rng(seed)
    n = 2 + int(rng.random() < 0.3)
    height = round(float(rng.uniform(0.05, 0.12)), 4)
    width = 0.05
    yaw = float(rng.uniform(-0.08, 0.08))  # within 5 degrees of the named direction
    x0, y0 = float(rng.uniform(-0.08, 0.08)), float(rng.uniform(-0.05, 0.05))
    u = np.array([math.cos(yaw), math.sin(yaw)]) if away else np.array([-math.sin(yaw), math.cos(yaw)])
    objs: list[SceneObject] = []
    for k in range(n):
        length = round(float(rng.uniform(0.05, 0.10)), 4)
        offset = (k - (n - 1) / 2) * (width + gap_m)
        sx, sy = (width, length) if away else (length, width)
        objs.append(
            Box(k, sx, sy, height, round(float(x0 + offset * u[0]), 5), round(float(y0 + offset * u[1]), 5), yaw)
        )
    way = "away" if away else "across"
    return make_scene(f"gap_row({seed}, {gap_m * 1000:.0f} mm, {way})", objs)


def dense_mix(seed: int) -> Scene:
    """Up to 6-10 objects (one that finds no room after 300 tries is left out, its id
    unused): one or two large boxes (flat or tall), small objects on them, against them
    and against each other, the rest apart."""
    rng = np.random.default_rng(seed)
    placed: list[SceneObject] = []
    n_large = 1 + int(rng.random() < 0.5)
    n_total = int(rng.integers(6, 11))
    for object_id in range(n_total):
        obj: SceneObject
        if object_id < n_large:
            box = _flat_box(rng, object_id)
            if rng.random() < 0.4:  # a tall one instead (a cereal box)
                box = replace(
                    box,
                    size_x_m=round(box.size_x_m * 0.6, 4),
                    size_y_m=0.07,
                    size_z_m=round(float(rng.uniform(0.15, 0.25)), 4),
                )
            obj = box
        else:
            obj = _small(rng, object_id)
        for _attempt in range(300):
            roll = rng.random()
            flats = [p for p in placed if isinstance(p, Box) and p.size_z_m <= 0.05 and p.base_z_m == 0.0]
            if object_id >= n_large and flats and roll < 0.25:
                lower = flats[int(rng.integers(len(flats)))]
                small = replace(obj, size_z_m=min(obj.size_z_m, 0.08)) if isinstance(obj, Box) else obj
                try:
                    cand = _on_top(rng, small, lower)
                except ValueError:
                    continue
            elif placed and roll < 0.65:
                anchor = placed[int(rng.integers(len(placed)))]
                if anchor.base_z_m > 0:
                    continue
                cand = _place_touching(obj, anchor, float(rng.uniform(-math.pi, math.pi)))
            else:
                cand = replace(obj, x_m=float(rng.uniform(-0.2, 0.2)), y_m=float(rng.uniform(-0.13, 0.13)))
            if not _in_region(cand.footprint()):
                continue
            others = [p for p in placed if not (cand.base_z_m > 0 and p.top_z_m == cand.base_z_m)]
            clearance = 0.0 if roll < 0.65 else 0.015
            if any(objects_overlap(cand, p, clearance) for p in others if p is not cand):
                continue
            if cand.base_z_m > 0 and any(
                p.base_z_m == cand.base_z_m and objects_overlap(replace(cand, base_z_m=0.0), replace(p, base_z_m=0.0))
                for p in placed
            ):
                continue
            placed.append(cand)
            break
    return make_scene(f"dense_mix({seed})", placed)


def open_container(seed: int) -> Scene:
    """An open cylindrical container (a mug, a deep bowl, a tin): 7-12 cm across, 6-12 cm
    tall, walls 3-6 mm thick, alone near the middle of the table."""
    rng = np.random.default_rng(seed)
    cup = Cylinder(
        0,
        round(float(rng.uniform(0.035, 0.06)), 4),
        round(float(rng.uniform(0.06, 0.12)), 4),
        round(float(rng.uniform(-0.12, 0.12)), 4),
        round(float(rng.uniform(-0.08, 0.08)), 4),
        wall_m=round(float(rng.uniform(0.003, 0.006)), 4),
    )
    return make_scene(f"open_container({seed})", [cup])


# wide_objects: footprints keep this far in from the table's border, at least one wide
# object comes this close to it (near enough to be slid over the edge and pinched), and
# objects keep this gap between them (beyond the sensor's noise: segmentable).
WIDE_TABLE_MARGIN_M = 0.03
WIDE_NEAR_EDGE_M = 0.12
WIDE_MIN_GAP_M = 0.01


def _wide(rng: np.random.Generator, object_id: int) -> SceneObject:
    """An object no parallel gripper closes across: an open bowl, a mug with a handle, a
    plate, or a flat box wider than every profile's opening (the widest is 8.5 cm)."""
    kind = int(rng.integers(4))
    yaw = round(float(rng.uniform(-math.pi, math.pi)), 4)  # the mug's handle direction
    if kind == 0:  # bowl
        return Cylinder(
            object_id,
            round(float(rng.uniform(0.06, 0.09)), 4),
            round(float(rng.uniform(0.05, 0.08)), 4),
            0.0,
            0.0,
            yaw,
            wall_m=round(float(rng.uniform(0.003, 0.006)), 4),
        )
    if kind == 1:  # mug
        return Cylinder(
            object_id,
            round(float(rng.uniform(0.04, 0.045)), 4),
            round(float(rng.uniform(0.09, 0.10)), 4),
            0.0,
            0.0,
            yaw,
            wall_m=round(float(rng.uniform(0.003, 0.005)), 4),
            handle_m=round(float(rng.uniform(0.02, 0.025)), 4),
        )
    if kind == 2:  # plate: closed and low
        return Cylinder(
            object_id,
            round(float(rng.uniform(0.09, 0.12)), 4),
            round(float(rng.uniform(0.015, 0.025)), 4),
            0.0,
            0.0,
            yaw,
        )
    return Box(  # flat box
        object_id,
        round(float(rng.uniform(0.15, 0.22)), 4),
        round(float(rng.uniform(0.10, 0.16)), 4),
        round(float(rng.uniform(0.02, 0.04)), 4),
        0.0,
        0.0,
        yaw,
    )


def _edge_gap(poly: np.ndarray, table: Table) -> float:
    """Shortest distance from a footprint (on the table) to the table's border."""
    hx, hy = table.size_x_m / 2, table.size_y_m / 2
    return float(min(hx - poly[:, 0].max(), hx + poly[:, 0].min(), hy - poly[:, 1].max(), hy + poly[:, 1].min()))


def wide_objects(seed: int) -> Scene:
    """1-3 wide objects (`_wide`: bowls, mugs with handles, plates, flat boxes) and 3-6
    small graspable ones (`_small`) anywhere on the table, ``WIDE_TABLE_MARGIN_M`` in from
    its border and ``WIDE_MIN_GAP_M`` apart; the first wide object within
    ``WIDE_NEAR_EDGE_M`` of a table edge. Wide objects get ids 0.., small ones follow."""
    rng = np.random.default_rng(seed)
    table = Table()
    n_wide = int(rng.integers(1, 4))
    n_small = int(rng.integers(3, 7))
    objs: list[SceneObject] = [_wide(rng, i) for i in range(n_wide)]
    objs += [_small(rng, n_wide + i) for i in range(n_small)]
    lim_x = table.size_x_m / 2 - WIDE_TABLE_MARGIN_M
    lim_y = table.size_y_m / 2 - WIDE_TABLE_MARGIN_M
    placed: list[SceneObject] = []
    for obj in objs:
        for _attempt in range(500):
            cand = replace(
                obj, x_m=round(float(rng.uniform(-lim_x, lim_x)), 4), y_m=round(float(rng.uniform(-lim_y, lim_y)), 4)
            )
            if not placed:
                # the first (wide) object: moved towards a random side until its footprint
                # is 3-10 cm (a drawn gap) from that edge, keeping its place along it
                side = int(rng.integers(4))
                axis, sign = side // 2, 1.0 if side % 2 else -1.0
                gap = float(rng.uniform(WIDE_TABLE_MARGIN_M, 0.10))
                poly = cand.footprint()
                half = (table.size_x_m, table.size_y_m)[axis] / 2
                reach = float((sign * poly[:, axis]).max())  # how far out it reaches now
                shift = sign * (half - gap - reach)
                centre = [cand.x_m, cand.y_m]
                centre[axis] = round(centre[axis] + shift, 4)
                cand = replace(cand, x_m=centre[0], y_m=centre[1])
            poly = cand.footprint()
            if (np.abs(poly[:, 0]) > lim_x).any() or (np.abs(poly[:, 1]) > lim_y).any():
                continue
            if any(objects_overlap(cand, p, WIDE_MIN_GAP_M) for p in placed):
                continue
            placed.append(cand)
            break
        else:
            raise ValueError(f"wide_objects({seed}): no room for object {obj.object_id}")  # pragma: no cover
    return make_scene(f"wide_objects({seed})", placed)


# suction_mix (issue 36): the share of its wide objects whose top is porous, and ribbed
# (no cup seals there), the share that are heavy, and the true masses drawn (kg).
SUCTION_POROUS_SHARE = 0.12
SUCTION_RIBBED_SHARE = 0.12
SUCTION_HEAVY_SHARE = 0.15
SUCTION_MASS_KG = (0.1, 1.5)
SUCTION_HEAVY_KG = (3.0, 5.0)
SUCTION_SMALL_KG = (0.05, 0.4)


def _suction_wide(rng: np.random.Generator, object_id: int) -> SceneObject:
    """An object a cup takes and no parallel gripper closes across: a box lying flat, each
    side 10-30 cm (wider than every profile's opening), 3-8 cm tall, or a lidded
    container (a closed cylinder 6-10 cm in radius, 4-14 cm tall); its top porous, ribbed
    or smooth, its true mass 0.1-1.5 kg or, for a few, 3-5 kg."""
    yaw = round(float(rng.uniform(-math.pi / 2, math.pi / 2)), 4)
    obj: SceneObject
    if rng.random() < 0.35:
        obj = Cylinder(
            object_id,
            round(float(rng.uniform(0.06, 0.10)), 4),
            round(float(rng.uniform(0.04, 0.14)), 4),
            0.0,
            0.0,
            yaw,
        )
    else:
        sx, sy = rng.uniform(0.10, 0.30, size=2)
        obj = Box(
            object_id, round(float(sx), 4), round(float(sy), 4), round(float(rng.uniform(0.03, 0.08)), 4), 0.0, 0.0, yaw
        )
    roll = rng.random()
    surface = (
        "porous"
        if roll < SUCTION_POROUS_SHARE
        else "ribbed"
        if roll < SUCTION_POROUS_SHARE + SUCTION_RIBBED_SHARE
        else "smooth"
    )
    heavy = rng.random() < SUCTION_HEAVY_SHARE
    mass = float(rng.uniform(*(SUCTION_HEAVY_KG if heavy else SUCTION_MASS_KG)))
    return replace(obj, mass_kg=round(mass, 3), surface=surface)


def suction_mix(seed: int) -> Scene:
    """2-4 wide objects a cup may take (`_suction_wide`: flat boxes and lidded containers,
    some tops porous or ribbed, some heavy) and 1-2 small graspable ones (`_small`, their
    true mass 0.05-0.4 kg), anywhere on the table ``WIDE_TABLE_MARGIN_M`` in from its
    border and ``WIDE_MIN_GAP_M`` apart; one that finds no room after 300 tries is left
    out (its id unused). Every true mass is drawn here (`Box.mass_kg`): the planner sees
    none of them, nor the surfaces."""
    rng = np.random.default_rng(seed)
    table = Table()
    n_wide = int(rng.integers(2, 5))
    n_small = int(rng.integers(1, 3))
    objs: list[SceneObject] = [_suction_wide(rng, i) for i in range(n_wide)]
    for i in range(n_small):
        small = _small(rng, n_wide + i)
        objs.append(replace(small, mass_kg=round(float(rng.uniform(*SUCTION_SMALL_KG)), 3)))
    lim_x = table.size_x_m / 2 - WIDE_TABLE_MARGIN_M
    lim_y = table.size_y_m / 2 - WIDE_TABLE_MARGIN_M
    placed: list[SceneObject] = []
    for obj in objs:
        for _attempt in range(300):
            cand = replace(
                obj, x_m=round(float(rng.uniform(-lim_x, lim_x)), 4), y_m=round(float(rng.uniform(-lim_y, lim_y)), 4)
            )
            poly = cand.footprint()
            if (np.abs(poly[:, 0]) > lim_x).any() or (np.abs(poly[:, 1]) > lim_y).any():
                continue
            if any(objects_overlap(cand, p, WIDE_MIN_GAP_M) for p in placed):
                continue
            placed.append(cand)
            break
    return make_scene(f"suction_mix({seed})", placed)


FAMILIES: dict[str, Callable[[int], Scene]] = {
    "small_on_large": small_on_large,
    "small_against_tall": small_against_tall,
    **{
        f"gap_{g * 1000:.0f}mm_{way}": partial(gap_row, gap_m=g, away=way == "away")
        for way in ("away", "across")
        for g in GAPS_M
    },
    "dense_mix": dense_mix,
    "open_container": open_container,
    "wide_objects": wide_objects,
    "suction_mix": suction_mix,
}


# --- support families (issue 37) -------------------------------------------------------
# Scenes where the support is not simply the largest plane, or where things that are no
# objects stand in the prism above it: a mat on the table, a robot arm reaching in from
# an edge, a second desk behind, objects on a small raised surface above a floor, a large
# bowl. What is no object ("furniture": the mat, the arm, the desk, the raised top's body,
# what stands on the floor or the desk) takes ids from FURNITURE_ID up; `support_frame`
# renders a scene and relabels it: the mat as table, the rest of the furniture as none.
# They are not in `FAMILIES` (the simulator would clear the furniture as objects).
FURNITURE_ID = 100


def _spread(
    rng: np.random.Generator,
    objs: list[SceneObject],
    half_x: float,
    half_y: float,
    base_z: float,
    cx: float = 0.0,
    cy: float = 0.0,
) -> list[SceneObject]:
    """``objs`` placed apart (1.5 cm) within +-half_x, +-half_y of (cx, cy), standing at base_z;
    one that finds no room after 300 tries is left out."""
    placed: list[SceneObject] = []
    for obj in objs:
        for _attempt in range(300):
            cand = replace(
                obj,
                x_m=round(float(cx + rng.uniform(-half_x, half_x)), 4),
                y_m=round(float(cy + rng.uniform(-half_y, half_y)), 4),
                base_z_m=base_z,
            )
            poly = cand.footprint()
            if (np.abs(poly[:, 0] - cx) > half_x).any() or (np.abs(poly[:, 1] - cy) > half_y).any():
                continue
            if any(objects_overlap(cand, p, 0.015) for p in placed):
                continue
            placed.append(cand)
            break
    return placed


def mat_on_table(seed: int) -> Scene:
    """3-5 graspable objects on a mat or board 10-16 mm thick (35-50 x 25-35 cm) lying on the table."""
    rng = np.random.default_rng(seed)
    thick = round(float(rng.uniform(0.010, 0.016)), 4)
    sx, sy = round(float(rng.uniform(0.35, 0.50)), 4), round(float(rng.uniform(0.25, 0.35)), 4)
    mat = Box(FURNITURE_ID, sx, sy, thick, 0.0, 0.0)
    objs = [_small(rng, i) for i in range(int(rng.integers(3, 6)))]
    return make_scene(f"mat_on_table({seed})", [mat, *_spread(rng, objs, sx / 2 - 0.02, sy / 2 - 0.02, thick)])


def arm_entering(seed: int) -> Scene:
    """3-5 objects on the table and a robot arm reaching in over its left or right edge: an
    upper arm 15-25 cm above the table from beyond the edge, a forearm down to 3-8 cm above
    the table (boxes 6-9 cm thick)."""
    rng = np.random.default_rng(seed)
    side = 1.0 if rng.random() < 0.5 else -1.0
    height = float(rng.uniform(0.15, 0.25))
    reach_to = float(rng.uniform(0.0, 0.15))  # where the forearm comes down (|x|)
    thick = float(rng.uniform(0.06, 0.09))
    y = float(rng.uniform(-0.12, 0.12))
    x_out = 0.75
    upper = Box(
        FURNITURE_ID,
        round(x_out - reach_to, 4),
        round(thick, 4),
        round(thick, 4),
        round(side * (x_out + reach_to) / 2, 4),
        round(y, 4),
        0.0,
        round(height, 4),
    )
    low = float(rng.uniform(0.03, 0.08))
    fore = Box(
        FURNITURE_ID + 1,
        round(thick, 4),
        round(thick, 4),
        round(height - low, 4),
        round(side * reach_to, 4),
        round(y, 4),
        0.0,
        round(low, 4),
    )
    objs = [_small(rng, i, max_height_m=0.08) for i in range(int(rng.integers(3, 6)))]
    placed: list[SceneObject] = []
    for obj in _spread(rng, objs * 3, 0.35, 0.25, 0.0):  # tries: keep the first that miss the arm
        if len(placed) < len(objs) and not any(p.object_id == obj.object_id for p in placed):
            if not objects_overlap(replace(obj, base_z_m=0.0), replace(fore, base_z_m=0.0), 0.02):
                placed.append(obj)
    return make_scene(f"arm_entering({seed})", [*placed, upper, fore])


def _desk_beyond(
    rng: np.random.Generator, table: Table, gap_m: float, rise_m: float, n_lo: int, n_hi: int
) -> tuple[Box, float, list[SceneObject]]:
    """A 1 m x 40 cm desk ``gap_m`` beyond the table's far edge, its top ``rise_m`` above
    the table's, its centre's y, and n_lo..n_hi-1 small things to stand on it (drawn from
    ``rng``; ids after FURNITURE_ID)."""
    depth_m = 0.40
    y0 = table.size_y_m / 2 + gap_m + depth_m / 2
    desk = Box(FURNITURE_ID, 1.0, depth_m, round(rise_m + 0.7, 4), 0.0, round(y0, 4), 0.0, -0.7)
    on_desk = [
        replace(_small(rng, FURNITURE_ID + 1 + i), object_id=FURNITURE_ID + 1 + i)
        for i in range(int(rng.integers(n_lo, n_hi)))
    ]
    return desk, y0, on_desk


def desk_behind(seed: int) -> Scene:
    """3-5 objects on the table and, beyond its far edge (1-5 cm gap), a second desk 8-20 cm
    higher with 2-3 things on it."""
    rng = np.random.default_rng(seed)
    table = Table()
    gap = float(rng.uniform(0.01, 0.05))
    rise = float(rng.uniform(0.08, 0.20))
    desk, y0, on_desk = _desk_beyond(rng, table, gap, rise, 2, 4)
    objs = [_small(rng, i) for i in range(int(rng.integers(3, 6)))]
    return make_scene(
        f"desk_behind({seed})",
        [*_spread(rng, objs, 0.33, 0.24, 0.0), desk, *_spread(rng, on_desk, 0.45, 0.15, round(rise, 4), 0.0, y0)],
    )


def raised_surface(seed: int) -> Scene:
    """2-4 objects on a small raised top (a stool, a chair's writing arm: 40-50 x 30-40 cm),
    the table of the scene, seen from 0.8-1 m above it; the floor 75 cm below (rendered by
    `support_frame`) holds the top's body and 2-3 boxes (a bag, a footrest: 15-35 cm tall)."""
    rng = np.random.default_rng(seed)
    top = Table(round(float(rng.uniform(0.40, 0.50)), 4), round(float(rng.uniform(0.30, 0.40)), 4))
    floor = -FLOOR_BELOW_TABLE_M
    body = Box(
        FURNITURE_ID,
        round(top.size_x_m - 0.02, 4),
        round(top.size_y_m - 0.02, 4),
        round(FLOOR_BELOW_TABLE_M - 0.02, 4),
        0.0,
        0.0,
        0.0,
        floor,
    )
    things: list[SceneObject] = [body]
    for k in range(int(rng.integers(2, 4))):
        ang = float(rng.uniform(-math.pi, math.pi))
        dist = float(rng.uniform(0.45, 0.7))
        things.append(
            Box(
                FURNITURE_ID + 1 + k,
                round(float(rng.uniform(0.2, 0.4)), 4),
                round(float(rng.uniform(0.2, 0.35)), 4),
                round(float(rng.uniform(0.15, 0.35)), 4),
                round(dist * math.cos(ang), 4),
                round(dist * math.sin(ang) * 0.8, 4),
                round(float(rng.uniform(-0.5, 0.5)), 4),
                floor,
            )
        )
    objs = [_small(rng, i, max_height_m=0.10) for i in range(int(rng.integers(2, 5)))]
    placed = _spread(rng, objs, top.size_x_m / 2 - 0.03, top.size_y_m / 2 - 0.03, 0.0)
    T = camera_pose_T_camera_table(float(rng.uniform(0.8, 1.0)), float(rng.uniform(50.0, 60.0)))
    return make_scene(f"raised_surface({seed})", [*placed, *things], top, T)


def large_bowl(seed: int) -> Scene:
    """A large open bowl (36-42 cm across, 6-9 cm tall, its floor 1.5-2.5 cm thick) with 2-3
    objects in it, and 1-2 objects on the table beside it."""
    rng = np.random.default_rng(seed)
    radius = float(rng.uniform(0.18, 0.21))
    bowl = Cylinder(
        0,
        round(radius, 4),
        round(float(rng.uniform(0.06, 0.09)), 4),
        round(float(rng.uniform(-0.05, 0.05)), 4),
        round(float(rng.uniform(-0.02, 0.04)), 4),
        wall_m=0.006,
        floor_m=round(float(rng.uniform(0.015, 0.025)), 4),
    )
    inside = [_small(rng, 1 + i, max_height_m=0.06) for i in range(int(rng.integers(2, 4)))]
    half = (radius - 0.02) / math.sqrt(2)
    placed = _spread(rng, inside, half, half, bowl.floor_m, bowl.x_m, bowl.y_m)
    beside: list[SceneObject] = []
    for k in range(int(rng.integers(1, 3))):
        obj = _small(rng, 10 + k)
        for _attempt in range(300):
            cand = replace(
                obj, x_m=round(float(rng.uniform(-0.35, 0.35)), 4), y_m=round(float(rng.uniform(-0.25, 0.25)), 4)
            )
            if not objects_overlap(cand, bowl, 0.02) and not any(objects_overlap(cand, p, 0.02) for p in beside):
                poly = cand.footprint()
                if (np.abs(poly[:, 0]) < 0.37).all() and (np.abs(poly[:, 1]) < 0.27).all():
                    beside.append(cand)
                    break
    return make_scene(f"large_bowl({seed})", [bowl, *placed, *beside])


def wall_at_edge(seed: int) -> Scene:
    """desk_behind(seed)'s objects on the table and, instead of the desk, a wall 2 cm thick
    and 1.5 m tall standing on the table 0-4 cm inside its far edge, as wide as the table
    less 2 cm (a partition; the cleargrasp frames' wall stands inside the table's outline)."""
    objs = [o for o in desk_behind(seed).objects if o.object_id < FURNITURE_ID]
    table = Table()
    gap = float(np.random.default_rng(seed).uniform(0.0, 0.04))
    y = table.size_y_m / 2 - gap - 0.01
    wall = Box(FURNITURE_ID, round(table.size_x_m - 0.02, 4), 0.02, 1.5, 0.0, round(y, 4), 0.0, 0.0)
    return make_scene(f"wall_at_edge({seed})", [*objs, wall], table)


def desk_level_behind(seed: int) -> Scene:
    """desk_behind(seed)'s objects on the table and, beyond its far edge (2-6 cm gap), a
    second desk at the table's own height (within 1 cm) with 3-5 things on it: the lab's
    bench behind, clutter on it, one plane with the table but for the gap."""
    rng = np.random.default_rng(seed + 7919)
    table = Table()
    objs = [o for o in desk_behind(seed).objects if o.object_id < FURNITURE_ID]
    gap = float(rng.uniform(0.02, 0.06))
    rise = float(rng.uniform(-0.01, 0.01))
    desk, y0, on_desk = _desk_beyond(rng, table, gap, rise, 3, 6)
    return make_scene(
        f"desk_level_behind({seed})",
        [*objs, desk, *_spread(rng, on_desk, 0.45, 0.15, round(rise, 4), 0.0, y0)],
        table,
    )


def shelf_above(seed: int) -> Scene:
    """3-5 objects on the table under and before a shelf board (2 cm thick, 20-25 cm deep,
    25-40 cm above the table) over its far part, held by two side boards standing on the
    floor 1-3 cm beyond the table's left and right ends (a shelf unit the table is pushed
    into), 1-3 things on the shelf."""
    rng = np.random.default_rng(seed + 104729)
    table = Table()
    rise = float(rng.uniform(0.25, 0.40))
    depth = float(rng.uniform(0.20, 0.25))
    y = table.size_y_m / 2 - depth / 2 - float(rng.uniform(0.0, 0.03))
    width = table.size_x_m + 2 * float(rng.uniform(0.01, 0.03)) + 0.04
    board = Box(FURNITURE_ID, round(width, 4), round(depth, 4), 0.02, 0.0, round(y, 4), 0.0, round(rise, 4))
    floor = -FLOOR_BELOW_TABLE_M
    sides = [
        Box(
            FURNITURE_ID + 1 + k,
            0.02,
            round(depth, 4),
            round(rise - floor, 4),
            round(sgn * (width / 2 - 0.01), 4),
            round(y, 4),
            0.0,
            floor,
        )
        for k, sgn in enumerate((-1.0, 1.0))
    ]
    on_shelf = [
        replace(_small(rng, FURNITURE_ID + 3 + i, max_height_m=0.10), object_id=FURNITURE_ID + 3 + i)
        for i in range(int(rng.integers(1, 4)))
    ]
    shelf_things = _spread(rng, on_shelf, width / 2 - 0.07, depth / 2 - 0.02, round(rise + 0.02, 4), 0.0, y)
    objs = [_small(rng, i, max_height_m=min(0.12, rise - 0.08)) for i in range(int(rng.integers(3, 6)))]
    return make_scene(
        f"shelf_above({seed})", [*_spread(rng, objs, 0.33, 0.24, 0.0), board, *sides, *shelf_things], table
    )


def overhanging(seed: int) -> Scene:
    """2-4 objects standing at the table's left, right or far edge with 20-40 % of their
    footprint's width beyond it (a box, a book, a tray pushed to the edge: objects all), and
    2-3 objects elsewhere on the table."""
    rng = np.random.default_rng(seed + 15485863)
    table = Table()
    placed: list[SceneObject] = []
    n_edge = int(rng.integers(2, 5))
    for k in range(n_edge + int(rng.integers(2, 4))):
        obj = _small(rng, k)
        if k < n_edge and rng.random() < 0.5:  # a wider flat thing (a book, a tray)
            obj = _flat_box(rng, k)
        for _attempt in range(300):
            if k < n_edge:
                side = int(rng.integers(3))  # 0 left, 1 right, 2 far
                poly = replace(obj, x_m=0.0, y_m=0.0).footprint()
                axis, sign = (0, -1.0) if side == 0 else (0, 1.0) if side == 1 else (1, 1.0)
                extent = float((sign * poly[:, axis]).max())
                width = float(poly[:, axis].max() - poly[:, axis].min())
                out = float(rng.uniform(0.2, 0.4)) * width
                half = (table.size_x_m, table.size_y_m)[axis] / 2
                centre = sign * (half + out - extent)
                along = float(rng.uniform(-0.7, 0.7)) * (table.size_y_m, table.size_x_m)[axis] / 2
                x, y = (centre, along) if axis == 0 else (along, centre)
            else:
                x, y = float(rng.uniform(-0.3, 0.3)), float(rng.uniform(-0.2, 0.2))
            cand = replace(obj, x_m=round(x, 4), y_m=round(y, 4))
            if any(objects_overlap(cand, p, 0.015) for p in placed):
                continue
            placed.append(cand)
            break
    return make_scene(f"overhanging({seed})", placed, table)


def thin_flat(seed: int) -> Scene:
    """3-6 thin things lying flat (a phone, a card, a notebook, a pen, a ruler: boxes 6-20 mm
    tall, 1.5-20 cm wide, 10-25 cm long) and 1-2 graspable objects on the table."""
    rng = np.random.default_rng(seed + 32452843)
    objs: list[SceneObject] = []
    for k in range(int(rng.integers(3, 7))):
        if rng.random() < 0.35:  # a pen, a marker, a ruler
            sx, sy = float(rng.uniform(0.012, 0.03)), float(rng.uniform(0.10, 0.16))
        else:  # a phone, a card box, a notebook
            sx, sy = float(rng.uniform(0.06, 0.20)), float(rng.uniform(0.10, 0.25))
        objs.append(
            Box(
                k,
                round(sx, 4),
                round(sy, 4),
                round(float(rng.uniform(0.006, 0.02)), 4),
                0.0,
                0.0,
                round(float(rng.uniform(-math.pi / 2, math.pi / 2)), 4),
            )
        )
    objs += [_small(rng, 10 + k) for k in range(int(rng.integers(1, 3)))]
    return make_scene(f"thin_flat({seed})", _spread(rng, objs, 0.36, 0.26, 0.0))


SUPPORT_FAMILIES: dict[str, Callable[[int], Scene]] = {
    "mat_on_table": mat_on_table,
    "arm_entering": arm_entering,
    "desk_behind": desk_behind,
    "raised_surface": raised_surface,
    "large_bowl": large_bowl,
    "wall_at_edge": wall_at_edge,
    "desk_level_behind": desk_level_behind,
    "shelf_above": shelf_above,
    "overhanging": overhanging,
    "thin_flat": thin_flat,
}
_WITH_FLOOR = ("raised_surface",)
# other sensors for the support families (`support_frame`): a RealSense at 1280x720 (its
# colour stream's intrinsics, as cleargrasp's D435 frames), and stereo-like depth noise
# (an active stereo pair's errors: about twice the Kinect's spread, finer disparity steps,
# more pixels lost behind depth edges)
REALSENSE_HD = PinholeCamera(width=1280, height=720, fx=920.0, fy=920.0, cx=639.5, cy=359.5)
STEREO_NOISE = DepthNoise(
    sigma_base_m=0.002, sigma_quadratic_per_m=0.004, disparity_step_px=0.08, dropout_probability=0.6
)


def support_frame(
    name: str,
    seed: int,
    *,
    view: tuple[float, float] | None = None,
    camera: PinholeCamera | None = None,
    noise: DepthNoise | None = None,
) -> Frame:
    """The render of ``SUPPORT_FAMILIES[name](seed)`` (noise drawn from ``seed``), its labels
    those of the truth: the mat is table; the rest of the furniture, and what stands on
    it, is none. ``view``: (camera height above the table (m), pitch below the horizontal
    (degrees)) instead of the scene's own; ``camera``, ``noise``: another sensor
    (`REALSENSE_HD`, `STEREO_NOISE`)."""
    scene = SUPPORT_FAMILIES[name](seed)
    if view is not None:
        scene = replace(scene, T_camera_table_rows=_rows(camera_pose_T_camera_table(*view)))
    frame = render(scene, seed=seed, floor=name in _WITH_FLOOR, camera=camera or KINECT, noise=noise)
    labels = np.asarray(frame.fields["label"]).copy()
    furniture = labels >= object_label(FURNITURE_ID)
    labels[furniture] = LABEL_TABLE if name == "mat_on_table" else LABEL_NONE
    return replace(frame, fields={**frame.fields, "label": labels})
