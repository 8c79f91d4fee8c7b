"""`Plan`: the result of `plan`, for one frame."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from clearcli.predicates.grasps import kind as grasp_kind
from clearcli.predicates.state import Fact
from clearcli.status import PlanStatus


@dataclass(frozen=True)
class Action:
    """A grounded action: ("grasp", "o2") or ("push", "o0", "dir1"); a grasp of another
    kind than the thesis's pinch carries it: ("grasp", "o3", None, "rim")."""

    kind: str  # "grasp" | "push": a grasp of any kind removes the object
    obj: str
    direction: str | None = None
    grasp_kind: str = "pinch"  # grasps only: a registered kind's name (clearcli/settings/kinds.py)

    @property
    def pddl_name(self) -> str:
        if self.kind == "grasp":
            return grasp_kind(self.grasp_kind).facts.action
        return "push"

    def pddl(self) -> str:
        if self.kind == "grasp":
            return f"({self.pddl_name} {self.obj})"
        return f"(push {self.obj} {self.direction})"

    def ik_fact(self) -> Fact:
        """The fact backtracking adds when this action has no IK solution."""
        if self.kind == "grasp":
            return (grasp_kind(self.grasp_kind).facts.ik, self.obj)
        return ("ik_unfeasible_dir", self.obj, str(self.direction))


@dataclass(frozen=True, eq=False)
class CheckedAction:
    """The first action with the joint solutions that make it feasible."""

    action: Action
    T_base_gripper: tuple[np.ndarray, ...]  # the poses checked, robot base frame
    joint_solutions: tuple[np.ndarray, ...]  # (7,) per pose
    candidate: int = 0  # which gripper half-turn candidate succeeded


@dataclass(frozen=True)
class BacktrackStep:
    """One round of backtracking: the plan found and what the IK check said of it."""

    plan: tuple[Action, ...]  # the plan searched for in this round (after ``prefix``)
    cost: int
    optimal: bool
    feasible: bool  # every action checked had an arm motion
    reason: str = ""  # why the failing action has none ("no IK solution for pose 2/3", ...)
    failed_step: int = -1  # index in ``plan`` of the action that failed, -1 when none did
    learnt: tuple[Fact, ...] = ()  # facts learnt from the failure
    prefix: int = 0  # actions already fixed before this round's plan (see backtrack.py)


@dataclass(frozen=True)
class LeftObject:
    """An object the plan does not remove, and why."""

    name: str
    reason: str  # "unreachable" | "ungraspable" | "stuck"
    detail: str  # for people: which pose failed and how, the width, what holds it
    actions: Mapping[str, str] = field(default_factory=dict)  # "grasp"/"push dir1" -> why infeasible
    blockers: tuple[str, ...] = ()  # stuck: the objects left that hold it
    width_m: float | None = None  # ungraspable: measured width across the grasp


@dataclass(frozen=True, eq=False)
class Plan:
    actions: tuple[Action, ...]
    cost: int
    optimal: bool  # proven optimal by the search (for the model and the facts learnt)
    first: CheckedAction | None  # IK-checked first action (None when actions is empty)
    # Facts learnt by backtracking that hold in the recorded scene (ik_unfeasible_*, and
    # block_grasp/block_dir where the arm hits an object): the --problem file's additions.
    ik_facts: frozenset[Fact]
    unreachable: tuple[str, ...]  # objects dropped from the goal (all actions IK-infeasible)
    replans: int
    timings_s: Mapping[str, float] = field(default_factory=dict)
    # Extensions (plan stage): objects the goal left out for other reasons, and the trace.
    goal: tuple[str, ...] = ()  # the objects the plan removes
    ungraspable: tuple[str, ...] = ()  # too wide/narrow for the gripper: never in the goal
    stuck: tuple[str, ...] = ()  # reachable but no sequence of actions can free them
    search: str = ""  # Fast Downward configuration that produced the plan
    steps: tuple[BacktrackStep, ...] = ()
    T_base_camera: np.ndarray | None = None
    # One entry per action: its joint solutions, or None where the mode did not check it.
    checked: tuple[CheckedAction | None, ...] = ()
    check: str = "whole"  # "whole": every action checked; "first": the thesis's first only
    deadline: bool = False  # the time limit ended the search; the plan is the best found
    # Facts learnt in the scene as the first k actions leave it: (k, fact), k >= 1. Not
    # in the --problem file (they do not hold in the recorded scene; see backtrack.py).
    learnt_later: tuple[tuple[int, Fact], ...] = ()
    left: tuple[LeftObject, ...] = ()  # every object not removed, with the reason
    # The bound on the rounds of planning and IK checking ([plan] max_backtracks): the
    # loop ends with a plan, a proof that none exists, or an error at this bound.
    max_backtracks: int = 0
    # A closed loop's probing push (clearcli/planning/probe.py): the object pushed to see
    # whether it is two merged objects; "" for a plan of the model's own.
    probe: str = ""

    @property
    def status(self) -> PlanStatus:
        """complete: every object removed; partial: some left; no_plan: nothing to do."""
        if not self.left:
            return PlanStatus.COMPLETE
        return PlanStatus.PARTIAL if self.actions and self.goal else PlanStatus.NO_PLAN
