"""`Plan`: the result of `plan`, for one frame."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from clearcli.predicates.state import Fact


@dataclass(frozen=True)
class Action:
    """A grounded action: ("grasp", "o2") or ("push", "o0", "dir1")."""

    kind: str  # "grasp" | "push"
    obj: str
    direction: str | None = None

    def pddl(self) -> str:
        if self.kind == "grasp":
            return f"(grasp {self.obj})"
        return f"(push {self.obj} {self.direction})"

    def ik_fact(self) -> Fact:
        """The fact backtracking adds when this action has no IK solution."""
        if self.kind == "grasp":
            return ("ik_unfeasible_grasp", self.obj)
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
    """One round of Algorithm 1: the plan found and what the IK check of its first
    action said."""

    plan: tuple[Action, ...]
    cost: int
    optimal: bool
    feasible: bool  # the first action has an IK solution
    reason: str = ""  # why not ("no IK solution", "beyond reach", ...)


@dataclass(frozen=True, eq=False)
class Plan:
    actions: tuple[Action, ...]
    cost: int
    optimal: bool  # proven optimal by the search
    first: CheckedAction | None  # IK-checked first action (None when actions is empty)
    ik_facts: frozenset[Fact]  # ik_unfeasible_* facts added by backtracking
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
