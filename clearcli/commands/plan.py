"""`clear plan FRAME`: segment -> predicates -> plan, every action IK-checked.

Exit codes: 0 the plan removes every object (an empty table included); 10 it removes
some and leaves others, each with its reason; 5 nothing can be done. With ``--json`` a
document is printed in all three cases (and for a deadline that ends with a checked
plan); errors (3, 4, 6, 8) are one line on stderr.

--json prints one document, schema ``clear.plan`` version 2 (version 1 had no
``status``/``left``, and its ``optimal`` and ``steps`` meant less):

    source, frame_id          where the frame came from
    status                    "complete" | "partial" | "no_plan"
    actions                   ["(grasp o1)", "(push o0 dir1)", ...] in order
    steps                     per action: {"kind": "grasp"|"push", "object": "o1",
                              "direction": null|"dir1", "checked": bool,
                              "candidate": int|null (gripper candidate used: half-turn /
                              quarter-turn alternative), "joints_rad": [[7 floats] per
                              gripper pose]|null}; with --first-only only the first
                              action is checked, the others have nulls
    check                     "whole" (every action checked, each in the scene as the
                              earlier actions leave it) | "first" (--first-only)
    cost                      plan cost (number of actions with unit costs)
    unit_cost                 false when push costs (clearance cost) were used
    optimal                   true when the search proved the plan optimal for the model
                              and the facts learnt (false after a deadline, or when
                              part of the plan was fixed while backtracking)
    deadline                  true when --time-limit ended the search: the plan is the
                              best found, every action of it checked
    search                    the Fast Downward configuration used
    goal                      objects the plan removes
    left                      [{"object", "reason": "unreachable"|"ungraspable"|"stuck",
                              "detail" (which pose failed and how; the measured width
                              against the opening; what holds it), "actions": {"grasp"|
                              "push dirN": why it has no arm motion}, "blockers": [..],
                              "width_m": float|null}] for every object not removed
    no_plan_reason            null, or (status no_plan) the one-line reason also printed on stderr
    unreachable, stuck, ungraspable   the names in ``left``, by reason
    ik_unfeasible             facts learnt that hold in the recorded scene (the --problem
                              file's additions), e.g. ["ik_unfeasible_grasp", "o2"],
                              ["block_grasp", "o3", "o2"] (the arm hits o3)
    learnt_later              [{"after_step": k, "fact": [...]}]: learnt in the scene the
                              first k actions leave (not in the problem file)
    replans                   Fast Downward calls made by backtracking
    max_backtracks            the bound on those calls ([plan] max_backtracks): planning
                              ends with a plan, a proof there is none, or an error there
    backtracking              [{"plan", "cost", "feasible", "failed_step", "reason",
                              "learnt", "prefix"}] per call
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

from clearcli.commands import batchopts as bo
from clearcli.commands.common import stderr, stdout

PlanOutputs = bo.outputs_option(("problem", "domain", "plan", "png"))

PLAN_SCHEMA_VERSION = 2


def _round(a: Any, nd: int = 6) -> Any:
    import numpy as np

    return np.round(np.asarray(a, dtype=float), nd).tolist()


def plan_payload(plan: Any, source: str, frame_id: str, pose_source: str, unit_cost: bool = True) -> dict[str, Any]:
    first = None
    if plan.first is not None:
        first = {
            "action": plan.first.action.pddl(),
            "candidate": plan.first.candidate,
            "T_base_gripper": [_round(T) for T in plan.first.T_base_gripper],
            "joints_rad": [_round(q) for q in plan.first.joint_solutions],
        }
    checked = list(plan.checked) + [None] * (len(plan.actions) - len(plan.checked))
    steps = []
    for a, c in zip(plan.actions, checked):
        steps.append(
            {
                "kind": a.kind,
                "object": a.obj,
                "direction": a.direction,
                "checked": c is not None,
                "candidate": None if c is None else int(c.candidate),
                "joints_rad": None if c is None else [_round(q) for q in c.joint_solutions],
            }
        )
    left = [
        {
            "object": x.name,
            "reason": x.reason,
            "detail": x.detail,
            "actions": dict(x.actions),
            "blockers": list(x.blockers),
            "width_m": None if x.width_m is None else round(float(x.width_m), 4),
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
        "T_base_camera": None if plan.T_base_camera is None else _round(plan.T_base_camera),
        "camera_pose_source": pose_source,
        "timings_s": {k: round(float(v), 4) for k, v in plan.timings_s.items()},
    }


def print_plan(payload: dict[str, Any]) -> None:
    def out(text: str) -> None:
        stdout.print(text, markup=False, highlight=False)

    for i, (a, s) in enumerate(zip(payload["actions"], payload["steps"]), 1):
        out(f"{i:3d}. {a}" + ("" if s["checked"] else "   (not IK-checked)"))
    status = payload["status"]
    n_goal, n_left = len(payload["goal"]), len(payload["left"])
    if status == "complete":
        out("nothing to do: no objects on the table" if not payload["actions"] else f"complete: removes all {n_goal} objects")
    elif status == "partial":
        out(f"partial: removes {n_goal} objects, leaves {n_left}")
    else:
        out(f"no plan: none of the {n_left} objects can be removed")
    kind = "optimal (proven)" if payload["optimal"] else "not proven optimal"
    if payload["deadline"]:
        kind += ", time limit reached"
    checked = "every action IK-checked" if payload["check"] == "whole" else "first action IK-checked"
    if payload["actions"]:
        out(f"cost {payload['cost']}, {kind}, {checked}, search {payload['search'] or '-'}")
    for x in payload["left"]:
        out(f"  {x['object']} {x['reason']}: {x['detail']}")
    if payload["replans"] > 1:
        out(f"backtracking: {payload['replans']} plans")
        for s in payload["backtracking"]:
            if not s["feasible"] and 0 <= s["failed_step"] < len(s["plan"]):
                learnt = " ".join("(" + " ".join(f) + ")" for f in s["learnt"])
                out(f"  step {s['prefix'] + s['failed_step'] + 1} {s['plan'][s['failed_step']]}: {s['reason']}" + (f" -> {learnt}" if learnt else ""))
    first = payload["first_action"]
    if first:
        out(f"first action {first['action']}, joint solution (rad) per pose:")
        for q in first["joints_rad"]:
            out("  [" + ", ".join(f"{v:+.3f}" for v in q) + "]")
    out(f"camera pose: {payload['camera_pose_source']}")


def plan_cmd(
    inputs: bo.Inputs,
    output: Annotated[
        Optional[Path],
        typer.Option("-o", "--output", help="Write the plan in Fast Downward's plan-file format (lifted domain terms)."),
    ] = None,
    problem: Annotated[
        Optional[Path],
        typer.Option(
            "--problem",
            help="Write the PDDL problem the plan solves: the scene's facts, what backtracking learnt, "
            "the goal reduced to the objects the plan removes.",
        ),
    ] = None,
    domain: Annotated[
        Optional[Path],
        typer.Option("--domain", help="Write the PDDL domain the plan is for (the push-cost variant when costs were used)."),
    ] = None,
    json_out: Annotated[bool, typer.Option("--json", help="Machine-readable output (schema clear.plan, version 2).")] = False,
    png: Annotated[Optional[Path], typer.Option("--png", help="Draw the scene and the plan to this PNG.")] = None,
    force: Annotated[bool, typer.Option("--force", help="Overwrite existing output files.")] = False,
    first_only: Annotated[
        bool,
        typer.Option(
            "--first-only",
            help="IK-check only the plan's first action (the thesis's Algorithm 1); default: every action.",
        ),
    ] = False,
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
        Optional[float],
        typer.Option(
            "--time-limit",
            help="Seconds for the whole planning, backtracking included. When it runs out with a plan "
            "whose actions all check out, that plan is printed with deadline true; with none, exit 6.",
            min=0.1,
        ),
    ] = None,
    topic: Annotated[Optional[str], typer.Option("--topic", help="MCAP topic with the point clouds.")] = None,
    frame_index: Annotated[int, typer.Option("--frame", help="Frame index in an MCAP log.", min=0)] = 0,
    every: bo.Every = None,
    out_dir: bo.OutDir = None,
    outputs_kinds: PlanOutputs = None,
    resume: bo.Resume = False,
    jobs: bo.Jobs = None,
    ray: bo.Ray = None,
    fail_fast: bo.FailFast = False,
) -> None:
    """Plan how to clear the table in FRAME: numbered actions, every one IK-checked in the
    scene the earlier ones leave (backtracking as in the thesis's Algorithm 1, extended
    to the whole plan), and every object left with its reason.

    Exit 0: every object removed. Exit 10: some removed, the others left (listed with
    reasons). Exit 5: nothing can be done. -o, --problem and --domain are written for all
    three (problem and domain first, the plan file last)."""
    from clearcli.commands.common import check_output_path
    from clearcli.errors import EXIT_NO_PLAN, InputError
    from clearcli.settings import load_settings, override


    if bo.is_batch(inputs, every, out_dir, ray):
        from clearcli.batch.run import run_command_batch

        bo.single_only(**{"-o": output, "--problem": problem, "--domain": domain, "--png": png})
        raise typer.Exit(run_command_batch(
            "plan", inputs,
            {"settings": None if settings is None else str(settings), "overrides": {"plan": {"time_limit_s": time_limit}},
             "camera_pose": camera_pose, "first_only": first_only},
            outputs=outputs_kinds, jobs=jobs, frame=frame_index, every=every, topic=topic, out_dir=out_dir,
            force=force, resume=resume, ray=ray, fail_fast=fail_fast, json_out=json_out,
        ))
    frame = inputs[0]
    cfg = load_settings(settings)
    cfg = override(cfg, "plan", time_limit_s=time_limit)
    outputs = [p for p in (problem, domain, output, png) if p is not None]
    for p in outputs:
        check_output_path(p, force, (frame,))
    resolved = [Path(p).resolve() for p in outputs]
    if len(set(resolved)) != len(resolved):
        raise InputError("-o, --problem, --domain and --png must name different files")
    payload, code = plan_frame(
        frame, frame_index, cfg, topic=topic, camera_pose=camera_pose, first_only=first_only,
        problem=problem, domain=domain, output=output, png=png,
    )
    if json_out:
        from clearcli.commands.common import print_json

        print_json("plan", payload, version=PLAN_SCHEMA_VERSION)
    else:
        print_plan(payload)
    if code == EXIT_NO_PLAN:
        stderr.print(f"clear: {payload['no_plan_reason']}", markup=False, highlight=False)
    if code != 0:
        raise typer.Exit(code)


def plan_frame(
    frame: Path,
    frame_index: int,
    cfg: Any,
    *,
    topic: str | None = None,
    camera_pose: str | None = None,
    first_only: bool = False,
    problem: Path | None = None,
    domain: Path | None = None,
    output: Path | None = None,
    png: Path | None = None,
) -> tuple[dict[str, Any], int]:
    """One frame planned: its clear.plan payload and exit code (0 complete, 10 partial,
    5 nothing can be done), the output files written. Errors raise ClearError."""
    from clearcli.errors import EXIT_NO_PLAN, EXIT_OK, EXIT_PARTIAL_PLAN, NoPlanError
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment
    from clearcli.planning.backtrack import make_plan
    from clearcli.predicates.state_builder import compute_state
    from clearcli.robot.placement import placement_from_settings

    frm = read_frame(frame, topic, frame_index)
    seg = segment(frm, cfg.segment)
    state = compute_state(frm, seg, cfg)
    T_base_camera, pose_source = placement_from_settings(cfg.robot, state, camera_pose)
    no_plan: NoPlanError | None = None
    try:
        plan = make_plan(state, cfg, T_base_camera, check="first" if first_only else None)
    except NoPlanError as err:
        if getattr(err, "plan", None) is None:
            raise
        no_plan, plan = err, err.plan  # type: ignore[attr-defined]
    payload = plan_payload(plan, str(frame), getattr(frm, "frame_id", ""), pose_source, not state.push_costs)
    write_plan_files(state, plan, problem=problem, domain=domain, output=output)
    if png is not None:
        from clearcli.io.files import atomic_path
        from clearcli.render.plan_png import render_plan

        with atomic_path(png) as tmp:
            render_plan(tmp, frm, state, plan)
    if no_plan is not None:
        payload["no_plan_reason"] = str(no_plan)
        return payload, EXIT_NO_PLAN
    return payload, EXIT_PARTIAL_PLAN if plan.status == "partial" else EXIT_OK


def write_plan_files(state: Any, plan: Any, *, problem: Path | None, domain: Path | None, output: Path | None) -> None:
    """The problem (and domain) first, the plan file last, each written whole or not at
    all: a plan file on disk means its problem is complete."""
    from clearcli.commands.common import atomic_output
    from clearcli.planning.pddl import domain_for, write_plan, write_problem

    if problem is not None:
        text = write_problem(state, goal_objects=plan.goal, extra_facts=plan.ik_facts)
        with atomic_output(problem, "w") as handle:
            handle.write(text)
    if domain is not None:
        with atomic_output(domain, "w") as handle:
            handle.write(domain_for(state))
    if output is not None:
        with atomic_output(output, "w") as handle:
            handle.write(write_plan(plan.actions, plan.cost, unit_cost=not state.push_costs))
