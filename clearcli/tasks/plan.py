"""`plan`: segment -> predicates -> plan, every action IK-checked; the plan's files."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from clearcli.errors import EXIT_NO_PLAN, EXIT_OK, EXIT_PARTIAL_PLAN, ClearError
from clearcli.planning.versions import PLAN_SCHEMA as PLAN_SCHEMA  # the commands read it here
from clearcli.planning.versions import PLAN_VERSION as PLAN_VERSION
from clearcli.tasks.base import NO_OUTPUTS, Outcome, Outputs, Source

if TYPE_CHECKING:
    # The stages, the planner, the arm and the picture are imported where `run` first
    # needs them: a batch's parent builds a Request and never runs one (its workers do),
    # and it imported them all (~0.3 s of CPU, before its workers were started; issue 39).
    from clearcli import pipeline
    from clearcli.io.frames import Frame
    from clearcli.perception.types import Segmentation
    from clearcli.planning.types import Plan
    from clearcli.predicates.state import SymbolicState
    from clearcli.robot.arm import Arm
    from clearcli.settings import Settings

SCHEMA, VERSION = PLAN_SCHEMA, PLAN_VERSION  # the planner's (clearcli/planning/versions.py)
OUTPUTS = ("problem", "domain", "plan", "png")


@dataclass(frozen=True)
class Request:
    settings: Settings
    camera_pose: str | None = None  # --camera-pose: 'x y z qx qy qz qw' or 'thesis'
    first_only: bool = False  # check the first action only (the thesis's Algorithm 1)
    outputs: Outputs = NO_OUTPUTS
    keep: bool = False  # the outcome keeps the frame, the segmentation and the state (the Python API)


def run(request: Request, source: Source) -> Outcome:
    """The clear.plan payload and exit code (0 complete, 10 partial, 5 nothing can be
    done), the output files written. Errors raise ClearError."""
    from clearcli import pipeline  # noqa: PLC0415  (see the top)
    from clearcli.planning.backtrack import with_grasp_kinds  # noqa: PLC0415
    from clearcli.planning.payload import plan_payload  # noqa: PLC0415
    from clearcli.planning.pddl import unit_cost  # noqa: PLC0415
    from clearcli.predicates.grasps import parse_kinds  # noqa: PLC0415
    from clearcli.robot.arm import resolve_arm  # noqa: PLC0415

    # the robot, resolved once: placement, planning, the payload's block and the picture
    robot = resolve_arm(request.settings)
    frame = pipeline.read(source.path, source.topic, source.index, request.settings, source.color)
    seg = pipeline.segmented(frame, request.settings)
    state = pipeline.stated(frame, seg, request.settings)
    done = pipeline.planned(
        state, request.settings, robot, request.camera_pose, "first" if request.first_only else None
    )
    assumes: dict[str, Any] = {}
    if done.no_plan is not None:
        weighed = _weigh_on_lift(request, robot, frame, seg, state)
        if weighed is not None:
            state, done, assumes = weighed
    plan = done.plan
    # the model the plan was made in: the facts of the grasp kinds [plan] grasps allows
    state = with_grasp_kinds(state, parse_kinds(request.settings.plan.grasps))
    payload = plan_payload(
        plan,
        str(source.path),
        getattr(frame, "frame_id", ""),
        done.pose_source,
        unit_cost(state),
        {o.name: o.kind_details for o in state.objects},
    )
    payload["robot"] = robot.block()
    if assumes:
        payload["assumes"] = assumes
    out = request.outputs
    write_plan_files(state, plan, problem=out.get("problem"), domain=out.get("domain"), output=out.get("plan"))
    png = out.get("png")
    if png is not None:
        from clearcli.files import atomic_path  # noqa: PLC0415  (see the top)
        from clearcli.render.plan_png import render_plan  # noqa: PLC0415  (--png only)

        with atomic_path(png) as tmp:
            render_plan(tmp, frame, state, plan, seg, robot)
    if done.no_plan is not None:
        payload["no_plan_reason"] = str(done.no_plan)
        code = EXIT_NO_PLAN
    else:
        code = EXIT_PARTIAL_PLAN if plan.status == "partial" else EXIT_OK
    kept = {"frame": frame, "segmentation": seg, "state": state} if request.keep else {}
    return Outcome(SCHEMA, VERSION, payload, code, out.all(), kept)


def _weigh_on_lift(
    request: Request, robot: Arm, frame: Frame, seg: Segmentation, state: SymbolicState
) -> tuple[SymbolicState, pipeline.Planned, dict[str, Any]] | None:
    """Nothing can be done while a cup's load was judged on the mass estimated from the
    volume (clearcli/settings/weigh.py): the frame planned once more as if its objects
    were as light as a household object plausibly is, against the cup's own hold, as the
    closed loop does (clearcli/replay/session.py): the lift weighs them. That state, plan
    and the document's ``assumes`` block (the settings assumed, the estimate's, and the
    objects only the estimate refused the cup) when that plan removes something; else
    None (the first answer stands, an error of the second attempt included)."""
    from clearcli import pipeline  # noqa: PLC0415  (see the top)
    from clearcli.settings.weigh import lightest_plausible  # noqa: PLC0415

    relaxed = lightest_plausible(request.settings)
    if relaxed is None:
        return None
    check = "first" if request.first_only else None
    try:
        light = pipeline.stated(frame, seg, relaxed)
        done = pipeline.planned(light, relaxed, robot, request.camera_pose, check)
    except ClearError:
        return None
    if done.no_plan is not None or not done.plan.actions:
        return None
    refused = {o.name for o in state.objects if "suction" not in o.kind_details}
    lifted = sorted({a.obj for a in done.plan.actions if a.kind == "grasp" and a.grasp_kind == "suction"} & refused)
    assumes = {
        "suction_mass": {
            "density_kg_m3": relaxed.suction.density_kg_m3,
            "safety_factor": relaxed.suction.safety_factor,
            "estimate_density_kg_m3": request.settings.suction.density_kg_m3,
            "estimate_safety_factor": request.settings.suction.safety_factor,
            "objects": lifted,
        }
    }
    return light, done, assumes


def write_plan_files(
    state: SymbolicState, plan: Plan, *, problem: Path | None, domain: Path | None, output: Path | None
) -> None:
    """The problem (and domain) first, the plan file last, each written whole or not at
    all: a plan file on disk means its problem is complete."""
    from clearcli.files import atomic_output  # noqa: PLC0415  (see the top)
    from clearcli.planning.pddl import domain_for, unit_cost, write_plan, write_problem  # noqa: PLC0415

    if problem is not None:
        text = write_problem(state, goal_objects=plan.goal, extra_facts=plan.ik_facts)
        with atomic_output(problem, "w") as handle:
            handle.write(text)
    if domain is not None:
        with atomic_output(domain, "w") as handle:
            handle.write(domain_for(state))
    if output is not None:
        with atomic_output(output, "w") as handle:
            handle.write(write_plan(plan.actions, plan.cost, unit_cost=unit_cost(state)))
