"""The simulated world's own physics of a grasp and a push: what the fingers meet, what
a push moves and shoves, what slips; judged on the scene itself, never on the planner's
model of it (see `clearcli.sim.episode`)."""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from clearcli.transforms import rot2

from clearcli.settings.sim import WorldParams
from clearcli.sim.scene import Cylinder, Scene, SceneObject, with_object_pose, without_object

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
    from clearcli.sim.scene import polygons_overlap

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
    k: "int | Sequence[int]",
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
            trial = with_object_pose(trial, i, obj.x_m + heading[0] * step, obj.y_m + heading[1] * step, obj.yaw_rad + turn)
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


# --- perception of the simulated world ------------------------------------------------------
