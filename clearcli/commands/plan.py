"""`clear plan FRAME`: segment -> predicates -> plan with IK backtracking.

--json prints one document (``print_json("plan", ...)``), schema ``clear.plan`` v1:

    source, frame_id          where the frame came from
    actions                   ["(grasp o1)", "(push o0 dir1)", ...] in order
    steps                     [{"kind": "grasp"|"push", "object": "o1", "direction": null|"dir1"}]
    cost                      plan cost (number of actions with unit costs)
    optimal                   true when the search proved the plan optimal
    search                    the Fast Downward configuration used
    goal                      objects the plan removes
    unreachable               objects dropped from the goal: every action IK-infeasible
    stuck                     objects no sequence of actions can free (blocked by unreachable ones)
    ungraspable               objects the gripper cannot hold (never in the goal)
    ik_unfeasible             facts added by backtracking, e.g. ["ik_unfeasible_grasp", "o2"]
    replans                   Fast Downward calls made by backtracking
    backtracking              [{"plan": [...], "cost", "feasible", "reason"}] per call
    first_action              null, or {"action", "candidate", "T_base_gripper": [[4x4]...],
                              "joints_rad": [[7 floats] per pose]}
    T_base_camera             4x4 used (robot base = WAM shoulder, DH frame 0)
    camera_pose_source        "given" | "thesis" | "default from table"
    timings_s                 seconds per stage
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Optional

import typer

from clearcli.commands.common import stdout


def _round(a: Any, nd: int = 6) -> Any:
    import numpy as np

    return np.round(np.asarray(a, dtype=float), nd).tolist()


def plan_payload(plan: Any, source: str, frame_id: str, pose_source: str) -> dict[str, Any]:
    first = None
    if plan.first is not None:
        first = {
            "action": plan.first.action.pddl(),
            "candidate": plan.first.candidate,
            "T_base_gripper": [_round(T) for T in plan.first.T_base_gripper],
            "joints_rad": [_round(q) for q in plan.first.joint_solutions],
        }
    return {
        "source": source,
        "frame_id": frame_id,
        "actions": [a.pddl() for a in plan.actions],
        "steps": [{"kind": a.kind, "object": a.obj, "direction": a.direction} for a in plan.actions],
        "cost": int(plan.cost),
        "optimal": bool(plan.optimal),
        "search": plan.search,
        "goal": list(plan.goal),
        "unreachable": list(plan.unreachable),
        "stuck": list(plan.stuck),
        "ungraspable": list(plan.ungraspable),
        "ik_unfeasible": [list(f) for f in sorted(plan.ik_facts)],
        "replans": int(plan.replans),
        "backtracking": [
            {"plan": [a.pddl() for a in s.plan], "cost": s.cost, "feasible": s.feasible, "reason": s.reason}
            for s in plan.steps
        ],
        "first_action": first,
        "T_base_camera": None if plan.T_base_camera is None else _round(plan.T_base_camera),
        "camera_pose_source": pose_source,
        "timings_s": {k: round(float(v), 4) for k, v in plan.timings_s.items()},
    }


def print_plan(payload: dict[str, Any]) -> None:
    if payload["actions"]:
        for i, a in enumerate(payload["actions"], 1):
            stdout.print(f"{i:3d}. {a}", markup=False, highlight=False)
    else:
        stdout.print("nothing to do: no objects on the table", markup=False)
    kind = "optimal (proven)" if payload["optimal"] else "not proven optimal"
    stdout.print(f"cost {payload['cost']}, {kind}, search {payload['search'] or '-'}", markup=False)
    for key, label in (
        ("unreachable", "unreachable (left out of the goal)"),
        ("stuck", "cannot be freed (left out of the goal)"),
        ("ungraspable", "ungraspable (left out of the goal)"),
    ):
        if payload[key]:
            stdout.print(f"{label}: {', '.join(payload[key])}", markup=False)
    if payload["replans"] > 1:
        stdout.print(f"backtracking: {payload['replans']} plans, IK-infeasible:", markup=False)
        for s in payload["backtracking"]:
            if not s["feasible"]:
                stdout.print(f"  {s['plan'][0]}: {s['reason']}", markup=False)
    first = payload["first_action"]
    if first:
        stdout.print(f"first action {first['action']}, joint solution (rad) per pose:", markup=False)
        for q in first["joints_rad"]:
            stdout.print("  [" + ", ".join(f"{v:+.3f}" for v in q) + "]", markup=False, highlight=False)
    stdout.print(f"camera pose: {payload['camera_pose_source']}", markup=False)


def plan_cmd(
    frame: Annotated[Path, typer.Argument(help="A .pcd or .mcap file.")],
    json_out: Annotated[bool, typer.Option("--json", help="Machine-readable output (schema clear.plan).")] = False,
    png: Annotated[Optional[Path], typer.Option("--png", help="Draw the scene and the plan to this PNG.")] = None,
    force: Annotated[bool, typer.Option("--force", help="Overwrite an existing --png file.")] = False,
    settings: Annotated[Optional[Path], typer.Option("--settings", help="TOML settings file (see `clear settings`).")] = None,
    camera_pose: Annotated[
        Optional[str],
        typer.Option(
            "--camera-pose",
            help="Pose of the points' (optical) frame in the WAM base: 'x y z qx qy qz qw' "
            "(one quoted argument), or 'thesis' for the thesis's Kinect extrinsic. "
            "Default: [robot] camera_pose, else the WAM just outside the table edge "
            "nearest the camera, facing the objects.",
        ),
    ] = None,
    time_limit: Annotated[
        Optional[float], typer.Option("--time-limit", help="Seconds per Fast Downward call.", min=0.1)
    ] = None,
    topic: Annotated[Optional[str], typer.Option("--topic", help="MCAP topic with the point clouds.")] = None,
    frame_index: Annotated[int, typer.Option("--frame", help="Frame index in an MCAP log.", min=0)] = 0,
) -> None:
    """Plan how to clear the table in FRAME: numbered actions, cost, whether optimal,
    unreachable objects, and the first action's joint solution (IK-checked, with
    backtracking as in the thesis's Algorithm 1)."""
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment
    from clearcli.planning.backtrack import make_plan
    from clearcli.predicates.state_builder import compute_state
    from clearcli.robot.placement import placement_from_settings
    from clearcli.settings import load_settings, override

    cfg = load_settings(settings)
    cfg = override(cfg, "plan", time_limit_s=time_limit)
    if png is not None:
        from clearcli.commands.common import check_output_path

        check_output_path(png, force, (frame,))
    frm = read_frame(frame, topic, frame_index)
    seg = segment(frm, cfg.segment)
    state = compute_state(frm, seg, cfg)
    T_base_camera, pose_source = placement_from_settings(cfg.robot, state, camera_pose)
    # NoPlanError / PlannerError propagate: the CLI prints the reason, exit 5 / 6.
    plan = make_plan(state, cfg, T_base_camera)
    payload = plan_payload(plan, str(frame), getattr(frm, "frame_id", ""), pose_source)
    if png is not None:
        from clearcli.commands.common import atomic_path
        from clearcli.render.plan_png import render_plan

        with atomic_path(png) as tmp:
            render_plan(tmp, frm, state, plan)
    if json_out:
        from clearcli.commands.common import print_json

        print_json("plan", payload)
    else:
        print_plan(payload)
