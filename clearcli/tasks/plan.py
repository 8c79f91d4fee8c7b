"""`plan`: segment -> predicates -> plan, every action IK-checked; the plan's files."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from clearcli import pipeline
from clearcli.errors import EXIT_NO_PLAN, EXIT_OK, EXIT_PARTIAL_PLAN
from clearcli.files import atomic_output, atomic_path
from clearcli.planning.backtrack import with_grasp_kinds
from clearcli.planning.payload import plan_payload
from clearcli.planning.pddl import domain_for, unit_cost, write_plan, write_problem
from clearcli.planning.types import Plan
from clearcli.planning.versions import PLAN_SCHEMA as PLAN_SCHEMA  # the commands read it here
from clearcli.planning.versions import PLAN_VERSION as PLAN_VERSION
from clearcli.predicates.grasps import parse_kinds
from clearcli.predicates.state import SymbolicState
from clearcli.render.plan_png import render_plan
from clearcli.robot.arm import resolve_arm
from clearcli.settings import Settings
from clearcli.tasks.base import NO_OUTPUTS, Outcome, Outputs, Source

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
    # the robot, resolved once: placement, planning, the payload's block and the picture
    robot = resolve_arm(request.settings)
    frame = pipeline.read(source.path, source.topic, source.index, request.settings, source.color)
    seg = pipeline.segmented(frame, request.settings)
    state = pipeline.stated(frame, seg, request.settings)
    done = pipeline.planned(
        state, request.settings, robot, request.camera_pose, "first" if request.first_only else None
    )
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
    out = request.outputs
    write_plan_files(state, plan, problem=out.get("problem"), domain=out.get("domain"), output=out.get("plan"))
    png = out.get("png")
    if png is not None:
        with atomic_path(png) as tmp:
            render_plan(tmp, frame, state, plan, seg, robot)
    if done.no_plan is not None:
        payload["no_plan_reason"] = str(done.no_plan)
        code = EXIT_NO_PLAN
    else:
        code = EXIT_PARTIAL_PLAN if plan.status == "partial" else EXIT_OK
    kept = {"frame": frame, "segmentation": seg, "state": state} if request.keep else {}
    return Outcome(SCHEMA, VERSION, payload, code, out.all(), kept)


def write_plan_files(
    state: SymbolicState, plan: Plan, *, problem: Path | None, domain: Path | None, output: Path | None
) -> None:
    """The problem (and domain) first, the plan file last, each written whole or not at
    all: a plan file on disk means its problem is complete."""
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
