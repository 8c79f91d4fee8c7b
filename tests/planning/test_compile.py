"""Tests of clearcli/planning/compile.py."""

from __future__ import annotations

import pytest
from helpers import plan_scenes as ps
from helpers.downward import _names, solve

from clearcli.planning import downward
from clearcli.planning.compile import compile_strips, random_facts, removable_objects
from clearcli.planning.downward import run_downward


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_compiled_forms_agree_with_lifted_domain(seed: int) -> None:
    n = 4 + seed % 2
    facts = random_facts(n, seed, density=2.0)
    goal = sorted(removable_objects(_names(n), facts))
    pos = solve(_names(n), facts, goal, None, formulation="positive")
    neg = solve(_names(n), facts, goal, None, formulation="negative")
    domain, problem, _which = ps.lifted_pddl(_names(n), facts, goal)
    lifted = run_downward(domain, problem, search=downward.BLIND, time_limit_s=60)
    assert pos is not None and neg is not None and lifted.solved
    assert pos.cost == neg.cost == lifted.cost
    assert pos.optimal and lifted.optimal
    assert ps.validate(domain, problem, pos.actions)


def test_removable_matches_planner_on_unsolvable() -> None:
    # o1 on o0, o0 blocks grasping o1 and nothing can be pushed (o1 is on o0): stuck.
    facts = {("on", "o1", "o0"), ("block_grasp", "o0", "o1")}
    assert removable_objects(_names(2), facts) == set()
    task = compile_strips(_names(2), facts, _names(2))
    res = run_downward(task.domain, task.problem, time_limit_s=20)
    assert res.unsolvable and not res.solved
    assert solve(_names(2), facts, _names(2), None) is None
