"""Tests of clearcli/planning/downward.py."""

from __future__ import annotations

import importlib.util
from concurrent.futures import ThreadPoolExecutor

import pytest
from helpers import plan_scenes as ps
from helpers.downward import _names

from clearcli.errors import PlannerError
from clearcli.planning import downward
from clearcli.planning.compile import compile_strips, random_facts, removable_objects
from clearcli.planning.downward import run_downward


def test_planner_errors(monkeypatch: pytest.MonkeyPatch) -> None:
    task = compile_strips(_names(2), set(), _names(2))
    # crash: a search option Fast Downward does not know
    with pytest.raises(PlannerError, match="exit code"):
        run_downward(task.domain, task.problem, search="astar(nosuchheuristic())", time_limit_s=20)
    # missing binary: an install hint
    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "up_fast_downward" else real(name, *a)
    )
    with pytest.raises(PlannerError, match="pip install up-fast-downward"):
        run_downward(task.domain, task.problem)


def test_time_out_is_a_planner_error() -> None:
    # Blind search on the lifted form of a 24-object state cannot finish in 2 s.
    facts = random_facts(24, 2)
    goal = sorted(removable_objects(_names(24), facts))
    domain, problem = ps.own_lifted_pddl(_names(24), facts, goal)
    with pytest.raises(PlannerError, match="timed out"):
        run_downward(domain, problem, search=downward.BLIND, time_limit_s=2.0)


def test_parallel_runs_do_not_clash() -> None:
    tasks = []
    for seed in range(4):
        facts = random_facts(6, seed, density=2.0)
        goal = sorted(removable_objects(_names(6), facts))
        tasks.append((compile_strips(_names(6), facts, goal), len(goal)))
    with ThreadPoolExecutor(max_workers=4) as pool:
        results = list(pool.map(lambda t: run_downward(t[0].domain, t[0].problem, time_limit_s=30), tasks))
    for (task, n_goal), res in zip(tasks, results):
        assert res.solved
        grasps = [s for s in res.steps if s[0].startswith("grasp_")]
        assert len(grasps) == n_goal  # each plan is its own task's, not a neighbour's
        assert all(s[0] in task.actions for s in res.steps)
