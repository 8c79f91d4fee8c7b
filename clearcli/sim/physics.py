"""The simulated world's own physics of a grasp and a push: what the fingers meet, what
a push moves and shoves, what slips, where a suction cup seals and what it holds; judged
on the scene itself, never on the planner's model of it (see `clearcli.sim.episode`)."""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence
from typing import Any

import numpy as np

from clearcli.predicates.grasps import kind
from clearcli.predicates.grasps import kinds as registered
from clearcli.settings.sim import WorldParams
from clearcli.settings.suction import SuctionSettings
from clearcli.sim.scene import (
    Box,
    Cylinder,
    Scene,
    SceneObject,
    convex_hull,
    make_scene,
    objects_overlap,
    polygons_overlap,
    with_object_pose,
    without_object,
)
from clearcli.transforms import rot2

# A neighbour that reaches less than this (m) into the space the open fingers take is
# nudged aside as they come down and close; more, and the grasp takes nothing.
GRASP_TOLERANCE_M = 0.003


def grasp_width_m(obj: SceneObject) -> float:
    """Width the gripper closes across: the narrower side (a cylinder's diameter)."""
    if isinstance(obj, Cylinder):
        return 2.0 * obj.radius_m
    return min(obj.size_x_m, obj.size_y_m)


def on_table(scene: Scene, obj: SceneObject) -> bool:
    """The object's centre is over the table top (else it falls)."""
    return abs(obj.x_m) <= scene.table.size_x_m / 2 and abs(obj.y_m) <= scene.table.size_y_m / 2


def truly_ungraspable(obj: SceneObject, opening_width_m: float, closing_width_m: float) -> bool:
    """The real gripper cannot hold the object whichever way it closes: its narrowest
    width is beyond the opening, or under the closing width (the fingers meet first)."""
    width = grasp_width_m(obj)
    return width > opening_width_m or width < closing_width_m


# An arm reaching over a table's edge to pinch what overhangs it comes down at some angle
# below the horizontal, about 45 deg by default and no lower than
# EDGE_PINCH_MIN_TILT_DEG (the world's figures: a level approach puts the wrist at the
# table's height, beyond the arms' reach): across the fingers a slab h thick then spans
# h / cos(angle), and the fingers keep 5 mm on either side.
EDGE_PINCH_TILT_DEG = 45.0
EDGE_PINCH_MIN_TILT_DEG = 20.0


def edge_pinch_span_m(opening_m: float, tilt_deg: float = EDGE_PINCH_TILT_DEG) -> float:
    """The thickest slab the gripper pinches at an edge coming down ``tilt_deg`` below
    the horizontal (m)."""
    return (opening_m - 0.01) * math.cos(math.radians(tilt_deg))


def approach_tilt_deg(T_table_gripper: np.ndarray) -> float:
    """How far below the horizontal a gripper pose's approach (its z axis) points (deg)."""
    z = np.asarray(T_table_gripper, dtype=float)[:3, 2]
    return math.degrees(math.asin(float(np.clip(-z[2] / max(float(np.linalg.norm(z)), 1e-12), -1.0, 1.0))))


def open_container(obj: SceneObject) -> bool:
    """An open cylinder: a bowl, a cup, a mug (what a rim grasp may take)."""
    return isinstance(obj, Cylinder) and obj.is_open


def truly_ungraspable_by(
    obj: SceneObject, gripper: Any, kinds: tuple[str, ...] | None = None, suction: SuctionSettings | None = None
) -> bool:
    """No grasp kind in ``kinds`` (clearcli/predicates/grasps; default the thesis's pinch
    alone) can take the object by the world's own rules, each kind's `world_holds` (with
    this module as its rules): the pinch when it is not `truly_ungraspable`, a rim grasp
    an open cylinder whose wall the fingers close on, a slide a box or a closed cylinder
    the gripper pinches at an edge, suction an object with a face the cup seals on and
    holds it by (`world_suction_holds`, with ``suction`` the robot's cup tool: default
    the [suction] defaults)."""
    rules: Any = sys.modules[__name__] if suction is None else _CupRules(suction)
    chosen = [kind(k) for k in kinds] if kinds is not None else [k for k in registered() if k.thesis]
    return not any(k.world_holds(obj, gripper, rules) for k in chosen)


class _CupRules:
    """This module's rules with the robot's own cup tool (its [suction]: the cup, the
    vacuum, the body that must clear the table) in `world_suction_holds`."""

    def __init__(self, suction: SuctionSettings) -> None:
        self._suction = suction

    def world_suction_holds(self, obj: SceneObject, s: SuctionSettings | None = None) -> bool:
        return world_suction_holds(obj, s if s is not None else self._suction)

    def __getattr__(self, name: str) -> Any:
        return getattr(sys.modules[__name__], name)


def world_grasp(
    scene: Scene,
    k: int,
    opening_width_m: float,
    rng: np.random.Generator,
    params: WorldParams = WorldParams(),
    closing_width_m: float = 0.0,
) -> tuple[Scene, str]:
    obj = scene.objects[k]
    width = grasp_width_m(obj)
    if truly_ungraspable(obj, opening_width_m, closing_width_m):
        # the fingers do not fit round it, or close past it: nothing happens
        return scene, "too wide" if width > opening_width_m else "too narrow"
    if width >= opening_width_m - params.tight_grasp_margin_m and rng.random() < params.tight_grasp_fail_probability:
        # the fingers close on an edge and the object slips back, a little displaced
        dx, dy = rng.normal(0.0, 0.004, 2)
        turned = obj.yaw_rad + float(rng.normal(0.0, math.radians(3.0)))
        return with_object_pose(scene, k, obj.x_m + dx, obj.y_m + dy, turned), "slipped"
    return without_object(scene, k), "removed"


def aligned_width(obj: SceneObject, closing_table: np.ndarray) -> float:
    """The object's width across the closing direction once the fingers have squared it:
    a box's size along its axis nearest that direction, a cylinder's diameter."""
    if isinstance(obj, Cylinder):
        return 2.0 * obj.radius_m
    x = np.asarray(closing_table[:2], dtype=float)
    x /= max(float(np.linalg.norm(x)), 1e-12)
    along_local_x = abs(math.cos(obj.yaw_rad) * x[0] + math.sin(obj.yaw_rad) * x[1])
    return obj.size_x_m if along_local_x >= math.sqrt(0.5) else obj.size_y_m


def grasp_contacts(
    scene: Scene,
    tcp_table: np.ndarray,
    closing_table: np.ndarray,
    opening_m: float,
    finger_width_m: float,
    tips_z_m: float,
    finger_thickness_m: float = 0.01,
) -> list[int]:
    """Indices of the objects the open fingers meet when the gripper comes down: the
    footprints that meet the rectangle the fingers and the space between them span (the
    opening and both fingers' thickness along the closing direction, a finger's width
    across), among objects taller than the fingertips. More than one: the fingers come
    down on a neighbour, or close on it with the target."""
    x = np.asarray(closing_table[:2], dtype=float)
    x /= max(float(np.linalg.norm(x)), 1e-12)
    y = np.array([-x[1], x[0]])
    c = np.asarray(tcp_table[:2], dtype=float)
    # a neighbour reaching in by less than a few mm is pushed aside by the finger
    hx = opening_m / 2.0 + finger_thickness_m - GRASP_TOLERANCE_M
    hy = finger_width_m / 2.0 - GRASP_TOLERANCE_M
    rect = np.array([c - hx * x - hy * y, c + hx * x - hy * y, c + hx * x + hy * y, c - hx * x + hy * y])
    return [i for i, o in enumerate(scene.objects) if o.top_z_m > tips_z_m and polygons_overlap(rect, o.footprint())]


def separation(a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
    """The shortest translation of convex polygon ``b`` (2D) that ends its overlap with
    ``a`` (separating-axis method), or None when they do not overlap."""
    best: np.ndarray | None = None
    best_depth = math.inf
    for poly in (a, b):
        edges = np.roll(poly, -1, axis=0) - poly
        normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1)
        lengths = np.linalg.norm(normals, axis=1)
        normals = normals[lengths > 1e-12] / lengths[lengths > 1e-12, None]
        pa, pb = a @ normals.T, b @ normals.T
        forward = pa.max(axis=0) - pb.min(axis=0)  # move b along +normal by this
        backward = pb.max(axis=0) - pa.min(axis=0)  # or along -normal by this
        if (forward <= 0).any() or (backward <= 0).any():
            return None
        for k in range(normals.shape[0]):
            if forward[k] < best_depth:
                best_depth, best = float(forward[k]), normals[k] * forward[k]
            if backward[k] < best_depth:
                best_depth, best = float(backward[k]), -normals[k] * backward[k]
    return best


def _shove(scene: Scene, mover: int, fixed: frozenset[int], depth: int) -> Scene | None:
    """Push every object the ``mover`` now overlaps out of it (along the contact normal),
    and what those overlap in turn, ``depth`` levels deep; None when something is stuck
    (an overlap with a ``fixed`` object, or too deep a chain)."""
    moving = scene.objects[mover]
    poly = moving.footprint()
    for j, other in enumerate(scene.objects):
        if j == mover or other.base_z_m >= moving.top_z_m or moving.base_z_m >= other.top_z_m:
            continue
        shift = separation(poly, other.footprint())
        if shift is None:
            continue
        if j in fixed or depth <= 0:
            return None
        shift = shift * 1.05 + 1e-4 * shift / max(float(np.linalg.norm(shift)), 1e-12)
        scene = with_object_pose(scene, j, other.x_m + shift[0], other.y_m + shift[1], other.yaw_rad)
        result = _shove(scene, j, fixed | {mover}, depth - 1)
        if result is None:
            return None
        scene = result
    return scene


def push_contacts(
    scene: Scene, start_xy: np.ndarray, direction_table: np.ndarray, half_width_m: float, reach_m: float
) -> list[int]:
    """Indices of the objects the gripper's front meets first as it advances from
    ``start_xy`` along ``direction_table`` (table frame), its front ``half_width_m`` to
    either side, at most ``reach_m``: the first one met, and any other met within 5 mm
    of it that the front overlaps by 5 mm or more (the fingers straddle two objects)."""
    d = np.asarray(direction_table[:2], dtype=float)
    d /= max(float(np.linalg.norm(d)), 1e-12)
    n = np.array([-d[1], d[0]])
    p0 = np.asarray(start_xy[:2], dtype=float)
    hits: list[tuple[float, float, int]] = []
    for i, obj in enumerate(scene.objects):
        poly = obj.footprint()
        # the polygon's boundary, densely: where it enters the strip the front sweeps
        edges = np.roll(poly, -1, axis=0) - poly
        t = np.linspace(0.0, 1.0, 40, endpoint=False)
        pts = (poly[:, None, :] + t[None, :, None] * edges[:, None, :]).reshape(-1, 2) - p0
        along, across = pts @ d, pts @ n
        inside = np.abs(across) <= half_width_m
        if not inside.any():
            continue
        first = float(along[inside].min())
        if -0.01 <= first <= reach_m:
            overlap = float(min(across[inside].max(), half_width_m) - max(across[inside].min(), -half_width_m))
            hits.append((first, overlap, i))
    if not hits:
        return []
    hits.sort()
    first_at = hits[0][0]
    met = [h for h in hits if h[0] <= first_at + 0.005 and (h is hits[0] or h[1] >= 0.005)]
    met.sort(key=lambda h: -h[1])  # the one the front overlaps most first
    return [i for _, _, i in met]


def world_push(
    scene: Scene,
    k: int | Sequence[int],
    direction_table: np.ndarray,
    length_m: float,
    rng: np.random.Generator,
    params: WorldParams = WorldParams(),
) -> tuple[Scene, str]:
    """Slide object ``k`` (or the objects ``k``, side by side under the fingers, as one)
    along ``direction_table`` (2D, table frame) for ``length_m``, in steps, heading and
    yaw drifting; what it runs into is shoved out of its way, and the push stops (the
    gripper stalls) when that would need a chain of more than two shoves."""
    d = np.asarray(direction_table[:2], dtype=float)
    d /= max(float(np.linalg.norm(d)), 1e-12)
    steps = max(1, int(math.ceil(length_m / params.push_step_m)))
    step = length_m / steps
    moved = 0.0
    spin = float(rng.choice([-1.0, 1.0]))  # which way this push tends to turn the object
    before = {o.object_id: (o.x_m, o.y_m) for o in scene.objects}
    members = [k] if isinstance(k, (int, np.integer)) else list(k)
    pushed_ids = {scene.objects[i].object_id for i in members}
    for _ in range(steps):
        heading = rot2(math.radians(float(rng.normal(0.0, params.heading_noise_deg)))) @ d
        turn = spin * abs(float(rng.normal(0.0, math.radians(params.yaw_noise_deg))))
        trial = scene
        for i in members:
            obj = trial.objects[i]
            trial = with_object_pose(
                trial, i, obj.x_m + heading[0] * step, obj.y_m + heading[1] * step, obj.yaw_rad + turn
            )
        fixed = frozenset(members)
        shoved: Scene | None = trial
        for i in members:
            shoved = _shove(shoved, i, fixed - {i}, depth=2) if shoved is not None else None
        if shoved is None:
            break  # jammed: the objects stay where the last step left them
        scene = shoved
        moved += step
        off = [i for i in members if not on_table(scene, scene.objects[i])]
        if off:
            for i in sorted(off, reverse=True):
                scene = without_object(scene, i)
            return scene, f"fell off after {moved:.3f} m"
    displaced = sorted(
        o.object_id
        for o in scene.objects
        if o.object_id not in pushed_ids and math.dist((o.x_m, o.y_m), before[o.object_id]) > 0.002
    )
    fallen = [i for i, o in enumerate(scene.objects) if not on_table(scene, o)]
    for i in reversed(fallen):
        scene = without_object(scene, i)
    outcome = f"pushed {moved:.3f} m of {length_m:.3f} m"
    if displaced:
        outcome += f", shoved {', '.join(str(i) for i in displaced)}"
    return scene, outcome


# --- grasp kinds for wide objects: a rim grasp on an open container, a slide to the
# table's edge and a pinch of the overhang. Written from the scene alone (no import from
# clearcli.planning/predicates/geometry): these rules judge the planner's plans.

# Rim grasp: the approach within this of straight down, the closing direction within this
# of the container's radial direction, the fingertips at least this far below the rim.
RIM_MAX_TILT_DEG = 15.0
RIM_MAX_CLOSING_OFF_RADIAL_DEG = 20.0
RIM_MIN_TIP_DEPTH_M = 0.01
# Edge pinch: the overhang must exceed the fingers' grip depth by this (the pads' margin).
EDGE_PINCH_MARGIN_M = 0.005
# world_slide advances in steps this long, then bisects the last one to this precision.
SLIDE_STEP_M = 0.002
SLIDE_PRECISION_M = 1e-6

# The 8 corner signs of a box and its 12 edges (pairs of corners differing in one sign).
_SIGNS = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
_EDGES = [(i, j) for i in range(8) for j in range(i + 1, 8) if np.count_nonzero(_SIGNS[i] != _SIGNS[j]) == 1]


def _finger_corners(
    T_table_gripper: np.ndarray,
    opening_m: float,
    finger_thickness_m: float,
    finger_width_m: float,
    finger_depth_m: float,
    fingertip_z_m: float,
) -> list[np.ndarray]:
    """(8, 3) table-frame corners of each open finger (+x finger, then -x finger).

    Gripper frame as in the project's gripper model: closing point at the origin,
    approach +z, closing along x; a finger's inner face at x = +/- opening/2, its tip at
    z = fingertip_z_m, ``finger_depth_m`` long back along -z."""
    half = np.array([finger_thickness_m / 2, finger_width_m / 2, finger_depth_m / 2])
    R, t = T_table_gripper[:3, :3], T_table_gripper[:3, 3]
    out = []
    for side in (1.0, -1.0):
        centre = np.array([side * (opening_m / 2 + finger_thickness_m / 2), 0.0, fingertip_z_m - finger_depth_m / 2])
        local = centre + _SIGNS * half
        out.append(local @ R.T + t)
    return out


def _below(corners: np.ndarray, z_max: float) -> np.ndarray:
    """Vertices of the part of a box (its 8 corners) at z <= z_max: the corners below and
    where the edges cross the plane (the clipped solid is their convex hull)."""
    pts = [c for c in corners if c[2] <= z_max]
    for i, j in _EDGES:
        a, b = corners[i], corners[j]
        if (a[2] - z_max) * (b[2] - z_max) < 0:
            pts.append(a + (z_max - a[2]) / (b[2] - a[2]) * (b - a))
    return np.array(pts, dtype=float).reshape(-1, 3)


def _distance_to_polygon(point: np.ndarray, poly: np.ndarray) -> float:
    """Distance from a 2D point to a counter-clockwise convex polygon (0 inside it)."""
    n = len(poly)
    if n == 0:
        return math.inf
    if n == 1:
        return float(np.linalg.norm(point - poly[0]))
    inside = n >= 3
    best = math.inf
    for i in range(n):
        a, b = poly[i], poly[(i + 1) % n]
        e = b - a
        if n >= 3 and e[0] * (point[1] - a[1]) - e[1] * (point[0] - a[0]) < 0:
            inside = False  # right of a counter-clockwise edge: outside
        u = float(np.clip((point - a) @ e / max(float(e @ e), 1e-24), 0.0, 1.0))
        best = min(best, float(np.linalg.norm(point - (a + u * e))))
    return 0.0 if inside else best


def world_rim_grasp(
    scene: Scene,
    k: int,
    T_table_gripper: np.ndarray,
    opening_m: float,
    finger_thickness_m: float,
    finger_width_m: float,
    finger_depth_m: float,
    *,
    fingertip_z_m: float | None = None,
) -> tuple[bool, str]:
    """Does the open gripper at ``T_table_gripper`` (table frame; gripper frame: closing
    point at the origin, approach +z, closing along x) hold object ``k`` by its wall
    when it closes? (True, "held ...") or (False, a one-line reason).

    The fingers are the project's gripper model: inner faces at x = +/- opening_m / 2,
    ``finger_thickness_m`` along x, ``finger_width_m`` along y, ``finger_depth_m`` along z
    ending at the fingertips, z = ``fingertip_z_m`` (default ``finger_depth_m / 2``; the
    gripper model puts them at closing_region_height_m / 2, pass that to match it).

    Held when: ``k`` is an open cylinder; the approach is within 15 deg of straight down;
    the closing direction within 20 deg of radial; the wall between the fingers' inner
    faces (so the opening at least the wall's thickness), the inner finger wholly inside
    the inner wall and the outer one wholly outside the outer wall (the parts of them
    below the rim: above it they meet nothing of the wall); both fingertips at least
    1 cm below the rim, the inner one above the container's floor and the outer one above
    the container's base; no finger meeting the mug's handle or another object (their
    footprints overlapping at overlapping heights)."""
    obj = scene.objects[k]
    if not (isinstance(obj, Cylinder) and obj.is_open):
        return False, "not an open container: no rim to grasp"
    T = np.asarray(T_table_gripper, dtype=float)
    R, tcp = T[:3, :3], T[:3, 3]
    approach, closing = R[:, 2], R[:, 0]
    tilt = math.degrees(math.acos(float(np.clip(-approach[2] / np.linalg.norm(approach), -1.0, 1.0))))
    if tilt > RIM_MAX_TILT_DEG:
        return False, f"approach {tilt:.1f} deg from straight down (at most {RIM_MAX_TILT_DEG:g})"
    axis = np.array([obj.x_m, obj.y_m])
    rel = tcp[:2] - axis
    rho = float(np.linalg.norm(rel))
    if rho < 1e-6:
        return False, "closing point on the container's axis: no radial direction to close along"
    radial = np.array([rel[0] / rho, rel[1] / rho, 0.0])
    off = math.degrees(math.acos(float(np.clip(abs(closing @ radial) / np.linalg.norm(closing), 0.0, 1.0))))
    if off > RIM_MAX_CLOSING_OFF_RADIAL_DEG:
        return False, f"closing direction {off:.1f} deg off radial (at most {RIM_MAX_CLOSING_OFF_RADIAL_DEG:g})"
    r_out, r_in = obj.radius_m, obj.radius_m - obj.wall_m
    if opening_m < obj.wall_m:
        return False, f"opening {opening_m * 1000:.1f} mm narrower than the wall ({obj.wall_m * 1000:.1f} mm)"
    # the inner faces' places along the radial line: the wall must lie between them
    unit_closing = closing / np.linalg.norm(closing)
    faces = [float((tcp[:2] + side * opening_m / 2 * unit_closing[:2] - axis) @ radial[:2]) for side in (1.0, -1.0)]
    face_in, face_out = min(faces), max(faces)
    if not (face_in <= r_in and face_out >= r_out):
        return False, (
            f"wall ({r_in * 1000:.1f}-{r_out * 1000:.1f} mm from the axis) not between the fingers' "
            f"inner faces ({face_in * 1000:.1f} and {face_out * 1000:.1f} mm)"
        )
    tip_z = finger_depth_m / 2 if fingertip_z_m is None else float(fingertip_z_m)
    fingers = _finger_corners(T, opening_m, finger_thickness_m, finger_width_m, finger_depth_m, tip_z)
    # the inner finger is the one nearer the axis (the other has the outer wall to clear)
    centres = [float(np.linalg.norm(f.mean(axis=0)[:2] - axis)) for f in fingers]
    inner, outer = (fingers[0], fingers[1]) if centres[0] <= centres[1] else (fingers[1], fingers[0])
    rim_z = obj.top_z_m
    unit_approach = approach / np.linalg.norm(approach)
    for name, finger in (("inner", inner), ("outer", outer)):
        tip_centre = finger.mean(axis=0) + unit_approach * finger_depth_m / 2  # centre of its tip face
        if tip_centre[2] > rim_z - RIM_MIN_TIP_DEPTH_M:
            return False, (
                f"{name} fingertip {(rim_z - tip_centre[2]) * 1000:.1f} mm below the rim "
                f"(at least {RIM_MIN_TIP_DEPTH_M * 1000:.0f} mm)"
            )
    floor_z = obj.base_z_m + obj.floor_m
    if inner[:, 2].min() <= floor_z:
        return (
            False,
            f"inner fingertip at the container's floor ({(floor_z - inner[:, 2].min()) * 1000:.1f} mm into it)",
        )
    if outer[:, 2].min() <= obj.base_z_m:
        return False, "outer fingertip below the container's base"
    # what of each finger is below the rim meets the wall if it crosses r_in or r_out
    inner_low = _below(inner, rim_z)
    reach = float(np.linalg.norm(inner_low[:, :2] - axis, axis=1).max())
    if reach >= r_in:
        return (
            False,
            f"inner finger meets the wall (reaches {reach * 1000:.1f} mm from the axis, inner wall at {r_in * 1000:.1f})",
        )
    outer_low = convex_hull(_below(outer, rim_z)[:, :2])
    gap = _distance_to_polygon(axis, outer_low)
    if gap <= r_out:
        return (
            False,
            f"outer finger meets the wall ({gap * 1000:.1f} mm from the axis, outer wall at {r_out * 1000:.1f})",
        )
    # the mug's own handle, then every other object: footprints at overlapping heights
    handle = obj.handle_box()
    blockers: list[tuple[str, SceneObject]] = [("the handle", handle)] if handle is not None else []
    blockers += [(f"object {o.object_id}", o) for j, o in enumerate(scene.objects) if j != k]
    for name, finger in (("inner", inner), ("outer", outer)):
        lo, hi = float(finger[:, 2].min()), float(finger[:, 2].max())
        finger_print = convex_hull(finger[:, :2])
        for what, other in blockers:
            if other.base_z_m >= hi or lo >= other.top_z_m:
                continue
            if polygons_overlap(finger_print, other.footprint()):
                return False, f"{name} finger meets {what}"
    return True, f"held by the rim ({(rim_z - inner[:, 2].min()) * 1000:.0f} mm below it)"


def _unit_xy(direction_xy: np.ndarray, who: str) -> np.ndarray:
    """The table-plane direction, unit length; a ValueError naming ``who`` for none."""
    d = np.asarray(direction_xy, dtype=float)[:2]
    norm = float(np.linalg.norm(d))
    if norm < 1e-12:
        raise ValueError(f"{who}: direction_xy has no length")
    return d / norm


def world_slide(scene: Scene, k: int, direction_xy: np.ndarray, distance_m: float) -> tuple[Scene, float]:
    """Slide object ``k`` along ``direction_xy`` (table frame, normalised here) by up to
    ``distance_m``, stopping where its footprint would meet another object's (at
    overlapping heights); returns the new scene and the distance travelled.

    It advances in `SLIDE_STEP_M` steps and bisects the step that meets something, so it
    stops at the contact to within `SLIDE_PRECISION_M`. Objects it already overlaps at the
    start (a contact within the builders' tolerance) do not stop it. It does not leave
    the table on its own account: whether it tips is `world_edge_pinch`'s concern."""
    d = _unit_xy(direction_xy, "world_slide")
    obj = scene.objects[k]
    others = [o for j, o in enumerate(scene.objects) if j != k and not objects_overlap(obj, o)]

    def blocked(t: float) -> bool:
        trial = with_object_pose(scene, k, obj.x_m + t * d[0], obj.y_m + t * d[1], obj.yaw_rad).objects[k]
        return any(objects_overlap(trial, o) for o in others)

    travelled = 0.0
    total = max(float(distance_m), 0.0)
    while travelled < total:
        nxt = min(travelled + SLIDE_STEP_M, total)
        if blocked(nxt):
            lo, hi = travelled, nxt  # free at lo, meeting something at hi
            while hi - lo > SLIDE_PRECISION_M:
                mid = (lo + hi) / 2
                lo, hi = (lo, mid) if blocked(mid) else (mid, hi)
            travelled = lo
            break
        travelled = nxt
    return with_object_pose(scene, k, obj.x_m + travelled * d[0], obj.y_m + travelled * d[1], obj.yaw_rad), travelled


def world_edge_pinch(
    scene: Scene,
    k: int,
    direction_xy: np.ndarray,
    grip_depth_m: float,
    opening_m: float,
    closing_m: float,
    tilt_deg: float = EDGE_PINCH_TILT_DEG,
) -> tuple[bool, str]:
    """After object ``k`` was slid along ``direction_xy`` towards a table edge, can the
    gripper, coming down ``tilt_deg`` below the horizontal, pinch the part hanging over
    the edge (fingers above and below it)?

    The edge is the table side the direction leaves through from the object's centre;
    the overhang is how far the footprint reaches past that side, measured along the
    direction (the way the fingers come back in). Held when the centre is still over
    the table (else the object tips off), the overhang is at least ``grip_depth_m`` +
    `EDGE_PINCH_MARGIN_M` (else the pinch slips off the rim), and the object's height is
    within [closing_m, `edge_pinch_span_m`(opening_m, tilt_deg)] (the jaws close on it);
    a tilt below `EDGE_PINCH_MIN_TILT_DEG` does not get there at all."""
    d = _unit_xy(direction_xy, "world_edge_pinch")
    if not tilt_deg >= EDGE_PINCH_MIN_TILT_DEG - 1e-6:
        return (
            False,
            f"the gripper cannot come that low: {tilt_deg:.1f} deg below the horizontal, at least {EDGE_PINCH_MIN_TILT_DEG:g}",
        )
    obj = scene.objects[k]
    if not on_table(scene, obj):
        return False, "tipped off the table: its centre is past the edge"
    half = np.array([scene.table.size_x_m / 2, scene.table.size_y_m / 2])
    centre = np.array([obj.x_m, obj.y_m])
    # the side the direction leaves through: the axis whose border the ray meets first
    exits = [
        (half[a] - math.copysign(1.0, d[a]) * centre[a]) / abs(d[a]) if abs(d[a]) > 1e-12 else math.inf for a in (0, 1)
    ]
    a = int(np.argmin(exits))
    sign = math.copysign(1.0, d[a])
    poly = obj.footprint()
    overhang = (float((sign * poly[:, a]).max()) - half[a]) / abs(d[a])
    need = grip_depth_m + EDGE_PINCH_MARGIN_M
    if overhang < need:
        return False, f"slips: overhang {overhang * 1000:.1f} mm, needs {need * 1000:.1f} mm"
    height = obj.height_m
    span = edge_pinch_span_m(opening_m, tilt_deg)
    if height > span:
        return False, (
            f"too thick to pinch: {height * 1000:.1f} mm, at most {span * 1000:.1f} mm "
            f"with the opening {opening_m * 1000:.1f} mm from {tilt_deg:.0f} deg"
        )
    if height < closing_m:
        return False, f"too thin to pinch: {height * 1000:.1f} mm, the jaws close to {closing_m * 1000:.1f} mm"
    return True, f"pinched: overhang {overhang * 1000:.1f} mm, {height * 1000:.1f} mm thick"


# --- suction: a vacuum cup on a face (issue 36). Written from the scene alone, as the
# rules above: what the cup meets along its axis, whether its lip seals on that true
# face, and whether the seal holds the object's true weight (`Box.true_mass_kg`), with
# no safety factor: the world lifts whatever the cup truly holds.

# The cup meets a surface that lies within this of its lip along its axis (the arm's
# pose and the planner's estimate of the face are each a few mm off): beyond, the cup
# stops short of it; before, it struck the surface on its way.
SUCTION_TOUCH_M = 0.005
# A bellows lip follows a face tilted this far off the cup's axis (makers quote 15-20 deg
# for a 1.5-fold bellows); farther, it peels at its high side.
SUCTION_MAX_TILT_DEG = 15.0
# The approach: the world follows the cup's axis from this far back from the lip.
SUCTION_APPROACH_M = 0.15
GRAVITY_M_S2 = 9.81
# The cup's disc as the world samples it for other objects under it: its centre and
# rings at these shares of the lip's radius, 16 samples each.
_DISC_RINGS = (0.5, 1.0)
_DISC_SAMPLES = 16
_BOX_FACES = ("side", "side", "side", "side", "top", "bottom")  # +x, -x, +y, -y, +z, -z


def _slab(o: np.ndarray, d: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(N,) entry and exit parameters of rays o + t d (o (N, k), d (k,)) into the box
    lo <= p <= hi, and which axis the entry crosses; entry > exit: no hit."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t1, t2 = (lo - o) / d, (hi - o) / d
    tmin, tmax = np.minimum(t1, t2), np.maximum(t1, t2)
    flat = np.abs(d) < 1e-12
    if flat.any():
        inside = (o >= lo) & (o <= hi)
        tmin = np.where(flat, np.where(inside, -np.inf, np.inf), tmin)
        tmax = np.where(flat, np.where(inside, np.inf, -np.inf), tmax)
    return tmin.max(axis=1), tmax.min(axis=1), tmin.argmax(axis=1)


def _box_entry(box: Box, origins: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N,) where rays ``origins`` + t ``d`` (table frame) enter the box (inf: they miss
    it), and the face each enters (an index into `_BOX_FACES`)."""
    c, s = math.cos(box.yaw_rad), math.sin(box.yaw_rad)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    centre = np.array([box.x_m, box.y_m, box.base_z_m + box.size_z_m / 2])
    half = np.array([box.size_x_m, box.size_y_m, box.size_z_m]) / 2
    o, dl = (origins - centre) @ R, R.T @ d
    enter, leave, axis = _slab(o, dl, -half, half)
    hit = (enter <= leave) & (leave >= 0)
    face = 2 * axis + (dl[axis] > 0)  # entered on the side the ray comes from: -x when it runs along +x
    return np.where(hit, enter, np.inf), face


def _cylinder_entry(cyl: Cylinder, origins: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """As `_box_entry` for the solid upright cylinder the object's outside bounds (an
    open container's opening counts as its top): faces 0 side, 4 top, 5 bottom."""
    o = origins - np.array([cyl.x_m, cyl.y_m, cyl.base_z_m])
    a = d[0] ** 2 + d[1] ** 2
    b = 2.0 * (o[:, 0] * d[0] + o[:, 1] * d[1])
    c = o[:, 0] ** 2 + o[:, 1] ** 2 - cyl.radius_m**2
    if a < 1e-18:
        t0 = np.where(c <= 0, -np.inf, np.inf)
        t1 = np.where(c <= 0, np.inf, -np.inf)
    else:
        disc = b * b - 4 * a * c
        root = np.sqrt(np.maximum(disc, 0.0))
        t0 = np.where(disc >= 0, (-b - root) / (2 * a), np.inf)
        t1 = np.where(disc >= 0, (-b + root) / (2 * a), -np.inf)
    z0, z1, _ = _slab(o[:, 2:], d[2:], np.zeros(1), np.array([cyl.height_m]))
    enter, leave = np.maximum(t0, z0), np.minimum(t1, z1)
    hit = (enter <= leave) & (leave >= 0)
    face = np.where(t0 >= z0, 0, np.where(d[2] > 0, 5, 4))
    return np.where(hit, enter, np.inf), face


def _parts(scene: Scene) -> list[tuple[int, str, SceneObject]]:
    """What a cup may meet: each object (its index), and a mug's handle as its own part."""
    out: list[tuple[int, str, SceneObject]] = []
    for i, obj in enumerate(scene.objects):
        out.append((i, "body", obj))
        handle = obj.handle_box() if isinstance(obj, Cylinder) else None
        if handle is not None:
            out.append((i, "handle", handle))
    return out


def _entries(
    parts: list[tuple[int, str, SceneObject]], origins: np.ndarray, d: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(parts, N) entry parameters and faces of every part along every ray."""
    ts, faces = [], []
    for _, _, obj in parts:
        t, f = _box_entry(obj, origins, d) if isinstance(obj, Box) else _cylinder_entry(obj, origins, d)
        ts.append(t)
        faces.append(f)
    return np.array(ts).reshape(len(parts), -1), np.array(faces).reshape(len(parts), -1)


def centre_of_mass(obj: SceneObject) -> np.ndarray:
    """(3,) the object's centre of mass, table frame: a box's or a closed cylinder's
    middle; an open container's from its wall and floor (its handle left out)."""
    x, y, z0 = obj.x_m, obj.y_m, obj.base_z_m
    if isinstance(obj, Cylinder) and obj.is_open:
        floor = math.pi * obj.radius_m**2 * obj.floor_m
        wall = obj.volume_m3 - floor
        z = (floor * obj.floor_m / 2 + wall * (obj.floor_m + obj.height_m) / 2) / obj.volume_m3
        return np.array([x, y, z0 + z])
    return np.array([x, y, z0 + obj.height_m / 2])


def _unit(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v, dtype=float).reshape(3)
    return v / max(float(np.linalg.norm(v)), 1e-12)


def _face_seal(obj: SceneObject, face: int, p: np.ndarray, a: np.ndarray, s: SuctionSettings) -> str:
    """Why the lip does not seal on face ``face`` of ``obj`` met at ``p`` along ``a``
    ("" when it seals)."""
    r = s.cup_diameter_m / 2.0
    if isinstance(obj, Box):
        c, sn = math.cos(obj.yaw_rad), math.sin(obj.yaw_rad)
        R = np.array([[c, -sn, 0.0], [sn, c, 0.0], [0.0, 0.0, 1.0]])
        axis, sign = face // 2, (-1.0 if face % 2 else 1.0)
        normal = R[:, axis] * sign
        name = _BOX_FACES[face]
        half = np.array([obj.size_x_m, obj.size_y_m, obj.size_z_m]) / 2
        local = R.T @ (p - np.array([obj.x_m, obj.y_m, obj.base_z_m + half[2]]))
        across = [j for j in range(3) if j != axis]
        over = max(float(abs(local[j]) + r - half[j]) for j in across)
    else:
        rel = p - np.array([obj.x_m, obj.y_m, obj.base_z_m])
        rho = float(np.hypot(rel[0], rel[1]))
        if face == 0:
            name = "side"
            normal = np.array([rel[0] / max(rho, 1e-12), rel[1] / max(rho, 1e-12), 0.0])
            over = max(float(r - rel[2]), float(rel[2] + r - obj.height_m))
        else:
            name = "top" if face == 4 else "bottom"
            normal = np.array([0.0, 0.0, 1.0 if face == 4 else -1.0])
            over = rho + r - obj.radius_m
    if name == "bottom":
        return "no seal: the cup came from under the object"
    if isinstance(obj, Cylinder) and obj.is_open and name == "top":
        return "no seal: an open container's top (its rim is no face)"
    if name == "top" and obj.surface != "smooth":
        return f"no seal: the top is {obj.surface}"
    tilt = math.degrees(math.acos(float(np.clip(-(a @ normal), -1.0, 1.0))))
    if tilt > SUCTION_MAX_TILT_DEG:
        return f"no seal: the cup meets the {name} {tilt:.0f} deg askew (the lip follows {SUCTION_MAX_TILT_DEG:g})"
    if isinstance(obj, Cylinder) and name == "side":
        R_c = obj.radius_m
        sag = R_c - math.sqrt(R_c**2 - r**2) if R_c > r else math.inf
        if sag > s.bellows_compliance_m:
            return (
                f"no seal: the side curves {sag * 1000:.1f} mm under the cup (the bellows follow "
                f"{s.bellows_compliance_m * 1000:.1f})"
            )
    if over > 0:
        return f"no seal: the lip overhangs the {name}'s edge by {over * 1000:.1f} mm"
    return ""


def _load(obj: SceneObject, p: np.ndarray, a: np.ndarray, s: SuctionSettings) -> tuple[float, str]:
    """The share of the cup's hold the object's true weight takes (lifted when <= 1), and
    its terms. The weight pulls the face off the lip along the axis (against the holding
    force), slides it across (against the lip's friction), bends the lip about the
    contact (its moment across the axis, against the force at the cup's radius) and
    twists it (its moment along the axis, against the friction at the radius)."""
    m = obj.true_mass_kg
    weight = np.array([0.0, 0.0, -m * GRAVITY_M_S2])
    F, mu, r = s.holding_force_n, s.lip_friction, s.cup_diameter_m / 2.0
    pull = max(float(weight @ a), 0.0)
    shear = float(np.linalg.norm(weight - (weight @ a) * a))
    M = np.cross(centre_of_mass(obj) - p, weight)
    twist = abs(float(M @ a))
    bend = float(np.linalg.norm(M - (M @ a) * a))
    use = pull / F + shear / (mu * F) + bend / (F * r) + twist / (mu * F * r)
    terms = f"pull {pull:.1f} N, shear {shear:.1f} N, moment {bend:.2f} N m"
    if twist >= 0.005:
        terms += f", twist {twist:.2f} N m"
    return use, f"{m:.2f} kg, {use:.2f} of the cup's hold ({terms}; {F:g} N)"


def world_suction(
    scene: Scene, lip_table: np.ndarray, axis_table: np.ndarray, s: SuctionSettings
) -> tuple[bool, str, int | None]:
    """The cup at ``lip_table`` (its lip's centre, table frame), its axis ``axis_table``
    pointing into the surface, with the tool ``s`` ([suction]): (lifted?, what happened,
    index in ``scene.objects`` of the object the cup met, or None).

    What it meets: following the axis from `SUCTION_APPROACH_M` back, the first true
    surface; met when it lies within `SUCTION_TOUCH_M` of the lip ("missed: the cup met
    nothing" beyond; "missed: the cup struck ..." when it lies farther before the lip).
    The seal: on a true face flat within the bellows' compliance under the whole lip (a
    box's face, the lip's disc within its rectangle; a closed cylinder's top, the disc
    within it, or its side where its sag R - sqrt(R^2 - r^2) under the cup is within the
    compliance and the disc within its height); never on an open container's top, a
    mug's handle or a top marked porous or ribbed (`Box.surface`); the face within
    `SUCTION_MAX_TILT_DEG` of the axis; no other object under the disc. The load
    (`_load`): the true mass, no safety factor; lifted when it takes at most the whole
    hold, else dropped where it stood. The causes start "missed: ", "no seal: ",
    "dropped: too heavy" (a benchmark counts them)."""
    a = _unit(axis_table)
    lip = np.asarray(lip_table, dtype=float).reshape(3)
    parts = _parts(scene)
    if not parts:
        return False, "missed: the cup met nothing", None
    origin = lip - SUCTION_APPROACH_M * a
    t, faces = _entries(parts, origin[None, :], a)
    first = int(np.argmin(t[:, 0]))
    at = float(t[first, 0]) - SUCTION_APPROACH_M  # > 0: the surface lies beyond the lip
    if not math.isfinite(at) or at > SUCTION_TOUCH_M:
        return False, "missed: the cup met nothing", None
    k, part, obj = parts[first]
    wid = scene.objects[k].object_id
    if at < -SUCTION_TOUCH_M:
        return False, f"missed: the cup struck object {wid} {-at * 1000:.0f} mm short of its contact", k
    if part == "handle":
        return False, "no seal: on the mug's handle", k
    p = origin + float(t[first, 0]) * a
    why = _face_seal(obj, int(faces[first, 0]), p, a, s)
    if why:
        return False, why, k
    # every other part under the lip's disc, met before this face along the axis
    e1 = np.cross(a, np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0]))
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    ang = np.arange(_DISC_SAMPLES) * (2 * math.pi / _DISC_SAMPLES)
    ring = np.cos(ang)[:, None] * e1 + np.sin(ang)[:, None] * e2
    r = s.cup_diameter_m / 2.0
    disc = np.concatenate([share * r * ring for share in _DISC_RINGS])
    t_disc, _ = _entries(parts, origin + disc, a)
    own = t_disc[first]
    under = [j for j in range(len(parts)) if j != first and bool((t_disc[j] < own + s.bellows_compliance_m).any())]
    if under:
        j = under[0]
        what = "its handle" if parts[j][0] == k else f"object {scene.objects[parts[j][0]].object_id}"
        return False, f"no seal: {what} under the cup", k
    use, load = _load(scene.objects[k], p, a, s)
    if use > 1.0:
        return False, f"dropped: too heavy: {load}", k
    return True, f"lifted: {load}", k


def world_suction_holds(obj: SceneObject, s: SuctionSettings | None = None) -> bool:
    """By `world_suction`'s rules: does some face of ``obj``, alone on the table, seal
    under the cup (``s``, default the [suction] defaults: a 30 mm cup) and hold its true
    mass? Each face is tried where its load is least: at its middle (a top straight
    down, a side level at its middle height; a cylinder's side from four directions
    clear of its handle), but no lower than the tool lying level clears the table: its
    cup's or its body's radius (``body_radius_m``: a hand 21 cm wide carrying the cup
    puts it on no side lower than 10.5 cm)."""
    s = SuctionSettings() if s is None else s
    alone = make_scene("alone", [obj])
    level = max(obj.height_m / 2, s.cup_diameter_m / 2, s.body_radius_m)
    mid = np.array([obj.x_m, obj.y_m, obj.base_z_m + level])
    tries: list[tuple[np.ndarray, np.ndarray]] = [
        (np.array([obj.x_m, obj.y_m, obj.top_z_m]), np.array([0.0, 0.0, -1.0]))
    ]
    if isinstance(obj, Box):
        for j, half in ((0, obj.size_x_m / 2), (1, obj.size_y_m / 2)):
            out = np.array([*rot2(obj.yaw_rad)[:, j], 0.0])
            tries += [(mid + sign * half * out, -sign * out) for sign in (1.0, -1.0)]
    else:
        for q in range(4):
            yaw = obj.yaw_rad + math.pi / 4 + q * math.pi / 2
            out = np.array([math.cos(yaw), math.sin(yaw), 0.0])
            tries.append((mid + obj.radius_m * out, -out))
    return any(world_suction(alone, lip, axis, s)[0] for lip, axis in tries)


# --- perception of the simulated world ------------------------------------------------------
