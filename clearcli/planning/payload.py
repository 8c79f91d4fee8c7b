"""The JSON payloads of the planning layer: a symbolic state (schema
``clear.predicates``, its facts in PDDL) and a plan (schema ``clear.plan``). One home for
both, so that `clear predicates`, `clear plan` and a batch's lines serialise alike."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from clearcli.planning.pddl import fact_to_pddl
from clearcli.rounding import rounded, timings

if TYPE_CHECKING:
    from clearcli.planning.types import Action, Plan
    from clearcli.predicates.state import SymbolicState

from clearcli.planning.versions import PLAN_SCHEMA, PLAN_VERSION, PREDICATES_SCHEMA, PREDICATES_VERSION  # noqa: F401


def predicates_payload(state: SymbolicState) -> dict[str, Any]:
    """The payload of schema ``clear.predicates``."""
    objects = []
    for o in state.objects:
        objects.append(
            {
                "name": o.name,
                "segment_index": int(o.segment_index),
                "centroid": rounded(o.centroid),
                "extents_m": rounded(o.extents_m),
                "principal_axes": rounded(o.principal_axes),
                "height_m": rounded(o.height_m),
                "grasp_width_m": rounded(o.grasp_width_m),
                "directions": {d: rounded(p.unit_vector) for d, p in o.pushes.items()},
                "grasp_poses": [rounded(c[1]) for c in o.grasp_candidates],
                "push": {
                    d: {"length_m": rounded(p.push_length_m), "start_poses": [rounded(c[1]) for c in p.candidates]}
                    for d, p in o.pushes.items()
                },
                # the grasp kinds beyond the pinch offered for it (a rim's circle and wall,
                # a slide's direction and length; the poses each candidate grasps at), and
                # why the others are not
                "grasp_kinds": {
                    k: {
                        **_rounded_detail(o.kind_details.get(k, {})),
                        "grasp_poses": [rounded(_grasp_pose(c)) for c in cands],
                    }
                    for k, cands in o.kind_candidates.items()
                },
                "not_offered": dict(o.kind_refusals),
            }
        )
    return {
        "source": state.source,
        "frame": "sensor (optical)",
        "table": {
            "normal": rounded(state.table.normal),
            "offset": rounded(state.table.offset),
            "polygon": rounded(state.table_polygon),
        },
        "objects": objects,
        "facts": sorted(fact_to_pddl(f) for f in state.facts),
        "skipped": [{"segment_index": int(i), "reason": r} for i, r in state.skipped],
        "push_costs": {f"{o} {d}": int(c) for (o, d), c in sorted(state.push_costs.items())},
        "timings_s": timings(state.timings_s),
    }


def _rounded_detail(detail: Any) -> Any:
    """A kind's detail for the JSON: numbers and vectors rounded, in lists and dicts too
    (a slide's per-candidate ``slides``)."""
    if isinstance(detail, dict):
        return {k: _rounded_detail(v) for k, v in detail.items()}
    if isinstance(detail, (list, tuple)) and detail and isinstance(detail[0], dict):
        return [_rounded_detail(v) for v in detail]
    if isinstance(detail, str):
        return detail
    return rounded(detail)


def _grasp_pose(seq: Any) -> Any:
    # the pose that closes the fingers: the pinch's middle of three; a slide's is its
    # second last (after the push along the table and the approach from the edge)
    return seq[-2]


def plan_payload(
    plan: Plan,
    source: str,
    frame_id: str,
    pose_source: str,
    unit_cost: bool,
    details: Mapping[str, Mapping[str, Mapping[str, Any]]] | None = None,
) -> dict[str, Any]:
    """The payload of schema ``clear.plan`` (documented in `clearcli/commands/plan.py`).
    ``details``: object -> grasp kind -> what the predicates stage tells of it (sensor
    frame): a suction step's contact comes from there."""
    first = None
    if plan.first is not None:
        first = {
            "action": plan.first.action.pddl(),
            "candidate": plan.first.candidate,
            "T_base_gripper": [rounded(T) for T in plan.first.T_base_gripper],
            "joints_rad": [rounded(q) for q in plan.first.joint_solutions],
        }
    checked = list(plan.checked) + [None] * (len(plan.actions) - len(plan.checked))
    steps: list[dict[str, Any]] = []
    for a, c in zip(plan.actions, checked):
        steps.append(
            {
                "kind": a.kind,
                # which grasp: "pinch" (the thesis's), "rim", "slide"; null for a push
                "grasp_kind": a.grasp_kind if a.kind == "grasp" else None,
                "object": a.obj,
                "direction": a.direction,
                "checked": c is not None,
                "candidate": None if c is None else int(c.candidate),
                "joints_rad": None if c is None else [rounded(q) for q in c.joint_solutions],
                # the gripper pose each joint vector was solved for (robot base frame)
                "T_base_gripper": None if c is None else [rounded(T) for T in c.T_base_gripper],
            }
        )
        contact = _contact(a, details, plan.T_base_camera)
        if contact is not None:
            steps[-1]["contact"] = contact
    left = [
        {
            "object": x.name,
            "reason": x.reason,
            "detail": x.detail,
            "actions": dict(x.actions),
            "blockers": list(x.blockers),
            "width_m": None if x.width_m is None else rounded(x.width_m, 4),
        }
        for x in plan.left
    ]
    return {
        "source": source,
        "frame_id": frame_id,
        "status": plan.status,
        "actions": [a.pddl() for a in plan.actions],
        "steps": steps,
        "check": plan.check,
        "cost": int(plan.cost),
        "unit_cost": bool(unit_cost),
        "optimal": bool(plan.optimal),
        "deadline": bool(plan.deadline),
        "search": plan.search,
        "goal": list(plan.goal),
        "left": left,
        "no_plan_reason": None,
        "unreachable": list(plan.unreachable),
        "stuck": list(plan.stuck),
        "ungraspable": list(plan.ungraspable),
        "ik_unfeasible": [list(f) for f in sorted(plan.ik_facts)],
        "learnt_later": [{"after_step": k, "fact": list(f)} for k, f in plan.learnt_later],
        "replans": int(plan.replans),
        "max_backtracks": int(plan.max_backtracks),
        "backtracking": [
            {
                "plan": [a.pddl() for a in s.plan],
                "cost": s.cost,
                "feasible": s.feasible,
                "failed_step": s.failed_step,
                "reason": s.reason,
                "learnt": [list(f) for f in s.learnt],
                "prefix": s.prefix,
            }
            for s in plan.steps
        ],
        "first_action": first,
        "T_base_camera": None if plan.T_base_camera is None else rounded(plan.T_base_camera),
        "camera_pose_source": pose_source,
        "timings_s": timings(plan.timings_s),
    }


def _contact(
    action: Action, details: Mapping[str, Mapping[str, Mapping[str, Any]]] | None, T_base_camera: np.ndarray | None
) -> dict[str, Any] | None:
    """A grasp's contact, where its kind has one (a suction cup's: the point on the face,
    its outward normal, the cup), in the robot base frame; None for the others."""
    if action.kind != "grasp" or not details or T_base_camera is None:
        return None
    d = details.get(action.obj, {}).get(str(action.grasp_kind), {})
    if "point" not in d or "normal" not in d:
        return None
    T = np.asarray(T_base_camera, dtype=float)
    point = T[:3, :3] @ np.asarray(d["point"], dtype=float) + T[:3, 3]
    normal = T[:3, :3] @ np.asarray(d["normal"], dtype=float)
    return {
        "face": d.get("face"),
        "point_base_m": rounded(point),
        "normal_base": rounded(normal),
        "cup_diameter_m": d.get("cup_diameter_m"),
        "margin": d.get("margin"),
    }
