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


@dataclass(frozen=True, eq=False)
class CheckedAction:
    """The first action with the joint solutions that make it feasible."""

    action: Action
    T_base_gripper: tuple[np.ndarray, ...]  # the poses checked, robot base frame
    joint_solutions: tuple[np.ndarray, ...]  # (7,) per pose


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
