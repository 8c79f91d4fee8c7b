"""Helpers that several test modules share (from the tests of planning)."""

from __future__ import annotations

from clearcli.planning.feasibility import Infeasible, SceneContext
from clearcli.planning.types import Action, CheckedAction


class FakeIK:
    """IK oracle from a set of actions infeasible where their object stands as recorded
    (once it was pushed, everything about it is feasible: the thesis's assumption)."""

    def __init__(self, infeasible: set[Action]) -> None:
        self.infeasible = infeasible
        self.calls: list[Action] = []

    def __call__(self, action: Action, ctx: SceneContext = SceneContext()) -> CheckedAction | Infeasible:
        self.calls.append(action)
        if action in self.infeasible and not ctx.moved(action.obj):
            return Infeasible("no IK solution", "ik")
        return CheckedAction(action, (), ())
