"""Planner settings (section [plan])."""

from __future__ import annotations

from dataclasses import dataclass

from clearcli.settings import kinds
from clearcli.settings.fields import Section, param


@dataclass(frozen=True)
class PlanSettings(Section):
    NAME = "plan"

    # Wall-clock bound on the whole planning, backtracking included (--time-limit). When
    # it ends the anytime search, its best plan is used if every action of it checks out.
    time_limit_s: float = param(30.0, ge=0.1, le=86400)
    # Which actions of a plan are IK-checked before it is accepted: "whole" (every action,
    # each in the scene as the earlier ones leave it) or "first" (the thesis: the robot
    # replans after every action). `clear plan` uses `check` (--first-only: "first");
    # `replay` and `simulate` use `replay_check`: they act on the first action only and
    # plan again from the next frame, so checking the rest would be work thrown away.
    check: str = param("whole", choices=("whole", "first"))
    replay_check: str = param("first", choices=("whole", "first"))
    # Optimal A* + LM-cut on the grounded form takes < 1 s for random states of up to 50
    # objects here in 5 of 6 cases (25 s once, at 40; benchmarks/plan.py): try it up to
    # this many goal objects, for at most optimal_time_s, then fall back to LAMA.
    optimal_max_objects: int = param(40, ge=0, le=1000)
    optimal_time_s: float = param(10.0, gt=0, le=3600)
    max_backtracks: int = param(200, ge=1, le=10000)
    # Budget of the anytime (LAMA) search: it keeps improving its plan until this runs
    # out, then the best plan so far is used (not proven optimal).
    anytime_time_s: float = param(5.0, gt=0, le=3600)
    # "positive": not-blocked compiled to complement facts (delete-free STRIPS), 0.46 s
    # for 24 objects; "negative": the same actions with (not ...) preconditions, 16 s.
    formulation: str = param("positive", choices=("positive", "negative"))
    # Before planning, mark every action whose gripper poses all lie beyond the arm's
    # reach (tool plate > 0.915 m from the shoulder) as IK-infeasible: no IK needed.
    reach_precheck: bool = param(True)
    # A push passes the IK check only when the object can still be grasped where the
    # push leaves it (the grasp poses moved by the push, checked with IK and collisions):
    # the planner's model takes a pushed object as graspable anywhere, and a push
    # towards the robot's base can carry it out of the arm's reach for good.
    push_lookahead: bool = param(True)
    # Closed loops only (replay, simulate): when nothing else can be done, an object
    # modelled wider than the gripper's opening but at most this wide (two of the widest
    # objects the gripper holds, side by side) is pushed once, to see whether it is two
    # objects the segmentation merged (clearcli/planning/probe.py). 0 = never.
    probe_max_width_m: float = param(0.14, ge=0, le=1)
    # Closed loops only: after this many grasps of one object in a row that did not take
    # it (slipped, or closed on another object too), its grasp counts as infeasible where
    # it stands (ik_unfeasible_grasp): the planner pushes it first, or gives it up, rather
    # than retry the same grasp until the action budget runs out.
    max_failed_grasps: int = param(3, ge=1, le=100)
    # Closed loops only: after a grasp that did not take its object, the next grasps of
    # it try the fingers towards either end first (its off-centre grasps, one end then
    # the other): a grasp at the middle of a segment that is two objects merged end to
    # end closes on both at their seam.
    regrasp_off_centre: bool = param(True)
    # Which grasp kinds the planner may use: the registered ones (clearcli/settings/kinds.py,
    # in preference order; each a module of clearcli/predicates/grasps), cheapest first by
    # action cost: the thesis's pinch from above (1), the rim of an open container (2), a
    # flat object slid to a seen table edge and pinched there (3). "pinch" alone is the
    # thesis's behaviour exactly (--grasps pinch). Any order, each kind at most once
    # ("rim, pinch" is "pinch,rim"); a file, --set and --grasps follow the one rule.
    grasps: str = param(kinds.default_kinds(), members=kinds.KIND_NAMES, required=kinds.REQUIRED_KINDS)
