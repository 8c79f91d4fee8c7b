"""The backtracking search object (clearcli/planning/backtrack.py `Search`): its bounds are
the [plan] settings it is given, never the section's defaults; its state is its fields;
slides and the other grasp kinds are read from their kinds' flags."""

from __future__ import annotations

import dataclasses

import pytest
from helpers import plan_scenes as ps
from helpers.planning import FakeIK

from clearcli.errors import PlannerError
from clearcli.planning.backtrack import Search
from clearcli.planning.types import Action
from clearcli.settings.plan import PlanSettings


def _given(**values: object) -> PlanSettings:
    return dataclasses.replace(PlanSettings(), **values)


def _no_defaults(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """From here on PlanSettings() itself fails: whatever the search reads, it reads from
    what it is given (built before this)."""

    def refuse(*args: object, **kw: object) -> None:
        raise AssertionError("the search built [plan]'s defaults")

    monkeypatch.setattr(PlanSettings, "__init__", refuse)


def test_the_search_reads_the_settings_it_is_given(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    state = ps.dummy_state(["o0", "o1"], frozenset())
    first = _given(check="first", max_backtracks=7)
    _no_defaults(monkeypatch)
    plan = Search(state, FakeIK(set()), first).run()
    assert plan.check == "first" and plan.max_backtracks == 7
    assert plan.checked[0] is not None and all(c is None for c in plan.checked[1:])
    assert Search(state, FakeIK(set()), first, mode="whole").run().check == "whole"


def test_max_backtracks_is_the_given_one(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # both grasps fail where the objects stand: each round learns one IK fact, so one or
    # two rounds end at the bound; the third finds the plan (push, grasp, push, grasp)
    state = ps.dummy_state(["o0", "o1"], frozenset())
    ik = {Action("grasp", "o0"), Action("grasp", "o1")}
    bounds = {n: _given(max_backtracks=n) for n in (1, 2, 3)}
    _no_defaults(monkeypatch)
    for bound in (1, 2):
        with pytest.raises(PlannerError, match=f"gave up after {bound} replans"):
            Search(state, FakeIK(ik), bounds[bound]).run()
    plan = Search(state, FakeIK(ik), bounds[3]).run()
    assert plan.replans == 3 and plan.max_backtracks == 3 and plan.cost == 4


def test_a_bad_mode_is_a_settings_error() -> None:
    from clearcli.errors import SettingsError

    with pytest.raises(SettingsError, match="check must be one of whole, first"):
        Search(ps.dummy_state(["o0"], frozenset()), FakeIK(set()), _given(), mode="all")


def test_its_state_is_its_fields() -> None:
    state = ps.dummy_state(["o0", "o1", "o2"], frozenset({("ungraspable", "o2")}))
    ik = FakeIK({Action("grasp", "o0")})
    search = Search(state, ik, _given())
    assert search.ungraspable == ("o2",) and search.wanted == ["o0", "o1"] and not search.prefix
    search.refresh_goal()
    assert search.goal == ["o0", "o1"] and search.unreachable == [] and search.stuck == []
    # one round: the plan's first action, the grasp of o0 (or o1 first: then the second
    # round of a whole check), fails; what it teaches is a fact of the recorded scene
    while search.step() is None:
        pass
    assert search.learnt0 == {("ik_unfeasible_grasp", "o0")}
    assert search.why == {"o0": {"grasp": "no IK solution"}}
    assert search.known() >= {("ik_unfeasible_grasp", "o0")}
    assert [s.feasible for s in search.steps][-1] is True


def test_an_object_whose_only_grasp_is_a_slide_without_an_arm_motion_is_unreachable() -> None:
    # o0 too wide for the pinch, slidable; its slide fails where it stands. A push would
    # not make the slide known (the slide's flags: push_clears_ik False), so o0 is dropped
    # as unreachable; a rim grasp's IK fact a push clears, so o1 is pushed and grasped
    facts = frozenset({("ungraspable", "o0"), ("slidable", "o0"), ("ungraspable", "o1"), ("rim_graspable", "o1")})
    state = ps.dummy_state(["o0", "o1"], facts)
    slide, rim = Action("grasp", "o0", None, "slide"), Action("grasp", "o1", None, "rim")
    plan = Search(state, FakeIK({slide, rim}), _given()).run()
    assert plan.unreachable == ("o0",) and plan.goal == ("o1",)
    assert [a.pddl() for a in plan.actions][-1] == "(grasp_rim o1)" and plan.actions[0].kind == "push"
    left = {x.name: x for x in plan.left}
    assert left["o0"].actions == {"slide grasp": "no IK solution"}
