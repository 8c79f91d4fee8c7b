"""A probing push for a closed loop (replay, simulate) that has nothing else to do.

Two graspable objects standing against each other with their tops at one height show
the depth camera one surface: the segmentation gives one segment, the model finds it
wider than the gripper's opening, and the plan leaves it as "too wide". On one frame
that is all anyone can say. A robot that acts can find out: pushing the segment moves
the object the gripper touches, and if it was two, the next frame shows them apart
(pushing to singulate: Hermans, Rehg and Bobick, "Guided pushing for object
singulation", IROS 2012). If it was one wide object, it has only moved, and the loop
ends as before.

Only objects modelled wider than the opening but at most ``[plan] probe_max_width_m``
(two of the widest objects the gripper holds, side by side) are probed, with the contact
off the middle of the rear face (`off_seam`), with a push no
object blocks (the model's ``block_dir``, ``push_off_table``, ``on``) whose every pose
has an arm motion clear of the other objects (the IK check of the plan stage). Each
object is probed at most once along each of its two push axes, so a truly wide one ends
the loop after two pushes at most.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Collection, Mapping
from typing import Any

import numpy as np

from clearcli.geometry.gripper import push_contact_halves
from clearcli.planning.feasibility import IKActionChecker
from clearcli.planning.types import Action, CheckedAction, Plan
from clearcli.predicates.state import DIRECTIONS, SymbolicState
from clearcli.robot.arm import Arm, resolve_arm
from clearcli.robot.collision import make_obstacles


def probe_candidates(
    state: SymbolicState,
    plan: Plan,
    opening_width_m: float,
    max_width_m: float,
    failed: Collection[str] = (),
) -> list[str]:
    """Objects the plan left as too wide that may be two objects merged, widest last:
    too wide for the pinch and no other grasp kind offered, or (``failed``: named by the
    caller, replay's ``max_failed_grasps``) those whose other kinds, a rim or a slide,
    kept failing when carried out - a slide of two merged objects moves neither far. One
    whose other kinds merely have no arm motion is not probed: a push would not help."""
    out = []
    tried_and_failed = [n for n in plan.unreachable if n in failed and ("ungraspable", n) in state.facts]
    for name in (*plan.ungraspable, *tried_and_failed):
        width = float(state.by_name(name).grasp_width_m)
        if opening_width_m < width <= max_width_m:
            out.append((width, name))
    return [name for _, name in sorted(out)]


def free_pushes(state: SymbolicState, name: str) -> list[str]:
    """Directions along which the model lets ``name`` be pushed: nothing blocks it, it
    stays on the table, nothing stands on it and it stands on nothing."""
    facts = state.facts
    if any(f[0] == "on" and name in (f[1], f[2]) for f in facts):
        return []
    blocked = {f[3] for f in facts if f[0] == "block_dir" and f[2] == name}
    off = {f[2] for f in facts if f[0] == "push_off_table" and f[1] == name}
    return [d for d in DIRECTIONS if d not in blocked and d not in off]


AXES = {"dir1": "first", "dir2": "first", "dir3": "second", "dir4": "second"}
# the contact stays this far (m) from the ends of the rear face
EDGE_MARGIN_M = 0.005


def off_centre_first(state: SymbolicState, name: str, failures: int) -> SymbolicState:
    """``state`` with the grasps of ``name`` moved off its middle tried first (the
    off-centre grasps of `geometry.poses.grasp_geometry`, one end after ``failures``
    odd, the other after even): a grasp that took nothing may have closed at the seam of
    two objects the segmentation merged end to end, and a grasp towards either end
    closes on one of them. Unchanged when the object has no off-centre grasp."""
    obj = state.by_name(name)
    cands = obj.grasp_candidates
    if len(cands) < 2:
        return state
    pos = np.array([np.asarray(seq[1], dtype=float)[:3, 3] for seq in cands])
    offset = pos - pos[0]
    dist = np.linalg.norm(offset, axis=1)
    off = np.flatnonzero(dist >= 0.01)
    if off.size == 0:
        return state
    axis = offset[off[0]] / dist[off[0]]
    side = np.sign(offset[off] @ axis) * (1.0 if failures % 2 else -1.0)
    first = [int(k) for k in off[np.argsort(-side, kind="stable")]]
    order = first + [k for k in range(len(cands)) if k not in set(first)]
    moved = dataclasses.replace(obj, grasp_candidates=tuple(cands[k] for k in order))
    return dataclasses.replace(state, objects=tuple(moved if o.name == name else o for o in state.objects))


def off_seam(state: SymbolicState, name: str, direction: str, gripper: Any) -> SymbolicState:
    """``state`` with the push of ``name`` along ``direction`` moved off the middle of its
    rear face, towards either end (5 mm short of it): fingers centred on a segment that
    is two objects side by side meet both at their seam and push them together, while
    fingers on one of them slide it past the other. Unchanged when the face is too narrow
    to move the contact by 1 cm."""
    obj = state.by_name(name)
    push = obj.pushes[direction]
    u = np.asarray(push.unit_vector, dtype=float)
    axes = np.asarray(obj.principal_axes, dtype=float)
    normal = axes[2] / np.linalg.norm(axes[2])
    side = np.cross(normal, u)
    side /= max(float(np.linalg.norm(side)), 1e-12)
    across_m = float(obj.extents_m[1] if direction in ("dir1", "dir2") else obj.extents_m[0])
    variants = []
    for seq in push.candidates:
        _, contact_half = push_contact_halves(gripper, np.asarray(seq[1], dtype=float)[:3, 0], u)
        reach = across_m / 2.0 - contact_half - EDGE_MARGIN_M
        if reach < 0.01:
            variants.append(seq)
            continue
        for sign in (1.0, -1.0):
            shifted = []
            for T in seq:
                T2 = np.array(T, dtype=float)
                T2[:3, 3] += sign * reach * side
                shifted.append(T2)
            variants.append(tuple(shifted))
    moved = dataclasses.replace(
        obj, pushes={**obj.pushes, direction: dataclasses.replace(push, candidates=tuple(variants))}
    )
    return dataclasses.replace(state, objects=tuple(moved if o.name == name else o for o in state.objects))


def probe_push(
    state: SymbolicState,
    plan: Plan,
    settings: Any,
    T_base_camera: np.ndarray,
    tried: Mapping[str, frozenset[str]] | None = None,
    failed: Collection[str] = (),
    robot: Arm | None = None,
) -> Plan | None:
    """A one-action plan pushing the first candidate that has a free, IK-feasible push
    along an axis not tried on it yet, or None. ``failed``: as `probe_candidates`.
    ``tried``: per name, the axes ("first":
    dir1/dir2, "second": dir3/dir4) of earlier probes. Both axes get a probe: a push across
    the seam of two merged objects drives the nearer into the other (they stay together),
    one along the seam slides it past. ``robot``: the command's resolved arm (else the
    one ``settings`` describe)."""
    tried = tried or {}
    names = [
        n
        for n in probe_candidates(
            state, plan, settings.gripper.opening_width_m, settings.plan.probe_max_width_m, failed
        )
        if len(tried.get(n, ())) < 2
    ]
    if not names:
        return None
    arm = robot if robot is not None else resolve_arm(settings)
    kin = arm.kinematics()
    T = np.asarray(T_base_camera, dtype=float)
    obstacles = make_obstacles(state, T, arm.settings.collision_margin_m)
    for name in names:
        for d in free_pushes(state, name):
            if AXES[d] in tried.get(name, ()):
                continue
            action = Action("push", name, d)
            checker = IKActionChecker(off_seam(state, name, d, settings.gripper), T, kin, obstacles)
            checked = checker(action)
            if isinstance(checked, CheckedAction):
                return dataclasses.replace(
                    plan,
                    actions=(action,),
                    cost=1,
                    optimal=False,
                    first=checked,
                    checked=(checked,),
                    check="first",
                    probe=name,
                    T_base_camera=T,
                )
    return None
