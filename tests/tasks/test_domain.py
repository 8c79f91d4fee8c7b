"""Tests of clearcli/tasks/domain.py: the lifted PDDL domain `clear domain` prints.

Read back by two PDDL readers that share no code with clear: the `pddl` package (for the
unit-cost domain: standard :action-costs) and unified-planning (which also takes the
clearance-cost variant's static cost function)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from helpers import REPO

from clearcli.errors import SettingsError
from clearcli.tasks.domain import domain_text

# settings/plan.py: the kinds' action costs, cheapest and surest first
COSTS = {"grasp": "1", "grasp_rim": "2", "slide_grasp": "3"}


def _code(text: str) -> str:
    """The domain without its comments."""
    return "\n".join(line.split(";", 1)[0] for line in text.splitlines())


def _parsed(tmp_path: Path, text: str):  # type: ignore[no-untyped-def]
    from pddl import parse_domain

    path = tmp_path / "domain.pddl"
    path.write_text(text)
    return parse_domain(path)


def _up_problem(tmp_path: Path, text: str):  # type: ignore[no-untyped-def]
    """unified-planning's reading of the domain, with a one-object problem."""
    from unified_planning.io import PDDLReader

    domain = tmp_path / "domain.pddl"
    domain.write_text(text)
    costs = "".join(f" (= (push-cost o0 dir{k}) {k})" for k in range(1, 5)) if "push-cost" in _code(text) else ""
    problem = tmp_path / "problem.pddl"
    problem.write_text(
        "(define (problem p) (:domain table-clearing) (:objects o0 - obj)\n"
        f" (:init{costs} (= (total-cost) 0))\n"
        " (:goal (and (removed o0))) (:metric minimize (total-cost)))\n"
    )
    return PDDLReader().parse_problem(str(domain), str(problem))


def test_the_default_domain_is_the_shipped_file_with_the_thesis_actions(tmp_path: Path) -> None:
    text = domain_text()
    assert text == (REPO / "pddl" / "domain.pddl").read_text(encoding="utf-8")
    dom = _parsed(tmp_path, text)
    assert str(dom.name) == "table-clearing"
    assert {a.name for a in dom.actions} == {"grasp", "push"}
    assert {str(c) for c in dom.constants} == {"dir1", "dir2", "dir3", "dir4"}
    assert {str(t) for t in dom.types} == {"obj", "direction"}


def test_every_grasp_kind_adds_its_action_and_facts(tmp_path: Path) -> None:
    dom = _parsed(tmp_path, domain_text(grasps="pinch,rim,slide"))
    assert {a.name for a in dom.actions} == {"grasp", "push", "grasp_rim", "slide_grasp"}
    predicates = {p.name for p in dom.predicates}
    assert {"rim_graspable", "block_rim", "ik_unfeasible_rim", "slidable", "block_slide"} <= predicates
    only_rim = _parsed(tmp_path, domain_text(grasps="pinch,rim"))
    assert {a.name for a in only_rim.actions} == {"grasp", "push", "grasp_rim"}
    assert not any("slide" in p.name for p in only_rim.predicates)


def test_the_kinds_are_a_set_in_any_order() -> None:
    assert domain_text(grasps="rim, pinch") == domain_text(grasps="pinch,rim")
    assert domain_text(grasps="slide,rim,pinch") == domain_text(grasps="pinch,rim,slide")
    assert domain_text(grasps="pinch") == domain_text()


def test_each_kind_costs_what_its_action_says(tmp_path: Path) -> None:
    dom = _parsed(tmp_path, domain_text(grasps="pinch,rim,slide"))
    costs = {}
    for action in dom.actions:
        increases = [str(e) for e in action.effect.operands if type(e).__name__ == "Increase"]
        assert len(increases) == 1, action.name
        costs[action.name] = re.fullmatch(r"\(increase \(total-cost\) (\d+)\)", increases[0]).group(1)  # type: ignore[union-attr]
    assert costs == {**COSTS, "push": "1"}


def test_clearance_costs_take_each_push_cost_from_the_problem(tmp_path: Path) -> None:
    text = domain_text(clearance_costs=True)
    assert "(push-cost ?o - obj ?d - direction) - number" in _code(text)
    problem = _up_problem(tmp_path, text)
    (metric,) = problem.quality_metrics
    costs = {a.name: str(c) for a, c in metric.costs.items()}
    assert costs["grasp"] == "1"
    assert re.fullmatch(r"push-cost\(o, d\)", costs["push"])
    # the unit-cost domain keeps the standard :action-costs only (the pddl package reads it)
    assert "push-cost" not in _code(domain_text())


@pytest.mark.parametrize("bad", ["rim", "", "pinch,pinch", "pinch,twist", "pinch,,rim"])
def test_a_bad_list_of_kinds_is_a_settings_error(bad: str) -> None:
    with pytest.raises(SettingsError) as info:
        domain_text(grasps=bad)
    assert "[plan] grasps" in str(info.value) and info.value.exit_code == 3
    assert "pinch, rim, slide, suction" in str(info.value)
