"""`clear plan FRAME`: segment -> predicates -> plan, every action IK-checked.

Exit codes: 0 the plan removes every object (an empty table included); 10 it removes
some and leaves others, each with its reason; 5 nothing can be done. With ``--json`` a
document is printed in all three cases (and for a deadline that ends with a checked
plan); errors (3, 4, 6, 8) are one line on stderr.

--json prints one document, schema ``clear.plan`` version 5 (version 1 had no
``status``/``left``, and its ``optimal`` and ``steps`` meant less; version 2 had no
``robot`` and no ``T_base_gripper`` per step; version 3 no ``grasp_kind`` per step;
version 4 no ``assumes``: a plan always rested on the estimated mass):

    source, frame_id          where the frame came from
    status                    "complete" | "partial" | "no_plan"
    actions                   ["(grasp o1)", "(push o0 dir1)", "(grasp_rim o2)",
                              "(slide_grasp o3)", ...] in order
    steps                     per action: {"kind": "grasp"|"push", "grasp_kind": a
                              registered kind's name (clearcli/settings/kinds.py: "pinch",
                              "rim", "slide", ...; null for a push), "object": "o1",
                              "direction": null|"dir1", "checked": bool,
                              "candidate": int|null (gripper candidate used: half-turn /
                              quarter-turn alternative), "joints_rad": [[one float per
                              joint of robot.joint_names] per gripper pose]|null,
                              "T_base_gripper": [[4x4] per pose]|null (the pose each joint
                              vector was solved for: check it by forward kinematics)};
                              with --first-only only the first action is checked, the
                              others have nulls
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
                              against the opening, and why each other grasp kind is not
                              offered; what holds it), "actions": {a grasp kind's label
                              ("grasp", "rim grasp", "slide grasp", ...)|"push dirN": why
                              it has no arm motion},
                              "blockers": [..],
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
    T_base_camera             4x4 used, in the robot's base frame (robot.base_frame: the
                              WAM's shoulder, DH frame 0; panda_link0; the UR5e's base_link)
    robot                     {"name": the profile (--robot), "urdf_sha256": digest of its
                              description, "base_frame", "tcp_frame", "joint_names": the
                              order of every joint vector, "gripper": {"name",
                              "opening_width_m", "closing_width_m"}}
    camera_pose_source        "given" | "thesis" | "default from table"
    assumes                   only when the plan rests on it: {"suction_mass":
                              {"density_kg_m3", "safety_factor": what was assumed,
                              "estimate_density_kg_m3", "estimate_safety_factor": the
                              [suction] values that refused, "objects": those the plan
                              lifts only so}}: nothing could be removed on the estimated
                              mass, so the frame was planned again as if its objects were
                              as light as a cracker box (170 kg/m^3), against the cup's own
                              hold (factor 1); the lift weighs them (clearcli/settings/weigh.py)
    timings_s                 seconds per stage
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Any

import typer

from clearcli.commands import options as bo
from clearcli.commands.common import check_output_path, print_json, stderr, stdout
from clearcli.errors import EXIT_NO_PLAN, InputError
from clearcli.tasks.base import Outputs, Source
from clearcli.tasks.versions import PLAN_SCHEMA, PLAN_VERSION


def print_plan(payload: Mapping[str, Any]) -> None:
    def out(text: str) -> None:
        stdout.print(text, markup=False, highlight=False)

    for i, (a, s) in enumerate(zip(payload["actions"], payload["steps"]), 1):
        out(f"{i:3d}. {a}" + ("" if s["checked"] else "   (not IK-checked)"))
    status = payload["status"]
    n_goal, n_left = len(payload["goal"]), len(payload["left"])
    if status == "complete":
        out(
            "nothing to do: no objects on the table"
            if not payload["actions"]
            else f"complete: removes all {n_goal} objects"
        )
    elif status == "partial":
        out(f"partial: removes {n_goal} objects, leaves {n_left}")
    else:
        out(f"no plan: none of the {n_left} objects can be removed")
    light = payload.get("assumes", {}).get("suction_mass")
    if light:
        out(
            f"assumes {', '.join(light['objects']) or 'the objects'} as light as "
            f"{light['density_kg_m3']:g} kg/m^3 on the cup's own hold (factor {light['safety_factor']:g}): "
            f"the estimate at {light['estimate_density_kg_m3']:g} kg/m^3 with factor "
            f"{light['estimate_safety_factor']:g} refused them; the lift weighs them"
        )
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
                out(
                    f"  step {s['prefix'] + s['failed_step'] + 1} {s['plan'][s['failed_step']]}: {s['reason']}"
                    + (f" -> {learnt}" if learnt else "")
                )
    first = payload["first_action"]
    if first:
        out(f"first action {first['action']}, joint solution (rad) per pose:")
        for q in first["joints_rad"]:
            out("  [" + ", ".join(f"{v:+.3f}" for v in q) + "]")
    out(f"camera pose: {payload['camera_pose_source']}")


@bo.batch_options(("problem", "domain", "plan", "png"))
def plan_cmd(
    inputs: bo.Inputs,
    output: Annotated[
        Path | None,
        typer.Option(
            "-o", "--output", help="Write the plan in Fast Downward's plan-file format (lifted domain terms)."
        ),
    ] = None,
    problem: Annotated[
        Path | None,
        typer.Option(
            "--problem",
            help="Write the PDDL problem the plan solves: the scene's facts, what backtracking learnt, "
            "the goal reduced to the objects the plan removes.",
        ),
    ] = None,
    domain: Annotated[
        Path | None,
        typer.Option(
            "--domain", help="Write the PDDL domain the plan is for (the push-cost variant when costs were used)."
        ),
    ] = None,
    json_out: Annotated[
        bool,
        typer.Option("--json", help=f"Machine-readable output (schema clear.{PLAN_SCHEMA}, version {PLAN_VERSION})."),
    ] = False,
    png: Annotated[Path | None, typer.Option("--png", help="Draw the scene and the plan to this PNG.")] = None,
    force: bo.Force = False,
    first_only: Annotated[
        bool,
        typer.Option(
            "--first-only",
            help="IK-check only the plan's first action (the thesis's Algorithm 1); default: every action.",
        ),
    ] = False,
    settings: bo.SettingsFile = None,
    sets: bo.Set = None,
    robot: bo.Robot = None,
    grasps: bo.Grasps = None,
    camera_pose: Annotated[
        str | None,
        typer.Option(
            "--camera-pose",
            help="Pose of the points' (optical) frame in the robot's base frame: 'x y z qx qy qz qw' "
            "(one quoted argument), or 'thesis' for the thesis's Kinect extrinsic (the WAM only). "
            "Default: [robot] camera_pose, else the robot just outside the table edge "
            "nearest the camera, facing the objects.",
        ),
    ] = None,
    time_limit: Annotated[
        float | None,
        typer.Option(
            "--time-limit",
            help="Seconds for the whole planning, backtracking included. When it runs out with a plan "
            "whose actions all check out, that plan is printed with deadline true; with none, exit 6. "
            "An alias of --set plan.time_limit_s=SECONDS (checked like it).",
        ),
    ] = None,
    topic: bo.Topic = None,
    frame_index: bo.FrameIndex = 0,
    intrinsics: bo.Intrinsics = None,
    color: bo.Color = None,
    depth_scale: bo.DepthScale = None,
    batch: bo.Batch = bo.Batch(),
) -> None:
    """Plan how to clear the table in FRAME: numbered actions, every one IK-checked in the
    scene the earlier ones leave (backtracking as in the thesis's Algorithm 1, extended
    to the whole plan), and every object left with its reason.

    Exit 0: every object removed. Exit 10: some removed, the others left (listed with
    reasons). Exit 5: nothing can be done. -o, --problem and --domain are written for all
    three (problem and domain first, the plan file last)."""
    from clearcli.tasks import plan as task  # noqa: PLC0415  (the task, ~1.1 s: not for `clear --help`)
    from clearcli.tasks import sources  # noqa: PLC0415  (~170 ms: not for `clear --help`)

    cfg = bo.with_images(
        bo.resolve_settings(settings, sets, "plan", robot=robot, grasps=grasps, time_limit_s=time_limit),
        intrinsics,
        depth_scale,
    )
    request = task.Request(cfg, camera_pose=camera_pose, first_only=first_only)
    if batch.wanted(inputs):
        bo.no_color_in_batch(color)
        bo.single_only(**{"-o": output, "--problem": problem, "--domain": domain, "--png": png})
        raise typer.Exit(
            batch.run(
                "plan",
                inputs,
                request,
                frame=frame_index,
                topic=topic,
                force=force,
                json_out=json_out,
                reads=(settings,),
            )
        )
    frame = inputs[0]
    outputs = [p for p in (problem, domain, output, png) if p is not None]
    read = sources.files_read(frame, cfg, color, also=(settings,))
    for p in outputs:
        check_output_path(p, force, read)
    resolved = [Path(p).resolve() for p in outputs]
    if len(set(resolved)) != len(resolved):
        raise InputError("-o, --problem, --domain and --png must name different files")
    request = task.Request(
        cfg,
        camera_pose=camera_pose,
        first_only=first_only,
        outputs=Outputs.of(problem=problem, domain=domain, plan=output, png=png),
    )
    outcome = task.run(request, Source(str(frame), frame_index, topic, color=str(color) if color else None))
    payload, code = outcome.payload, outcome.exit_code
    if json_out:
        print_json(outcome.schema, outcome.version, payload, cfg, "plan")
    else:
        print_plan(payload)
    if code == EXIT_NO_PLAN:
        stderr.print(f"clear: {payload['no_plan_reason']}", markup=False, highlight=False)
    if code != 0:
        raise typer.Exit(code)
