"""Tests of clearcli/planning/sas.py."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
from helpers.downward import _names

from clearcli.errors import PlannerError
from clearcli.planning import downward
from clearcli.planning.compile import (
    compile_strips,
    ground_actions,
    random_facts,
    removable_objects,
)
from clearcli.planning.downward import run_downward, run_sas
from clearcli.planning.sas import compile_sas
from clearcli.predicates.state import DIRECTIONS


def _push_costs(names: list[str], seed: int) -> dict[tuple[str, str], int]:
    rng = np.random.default_rng(1000 + seed)
    return {(o, d): int(rng.integers(1, 6)) for o in names for d in DIRECTIONS}


def _replay(names, facts, goal, costs, steps) -> int:
    """Check a plan against the model itself (not Fast Downward's view of it): every
    step's preconditions hold, the goal objects end up removed. Returns its cost."""
    ground = {a.name: a for a in ground_actions(names, facts, costs)}
    false: set = set()
    removed: set[str] = set()
    total = 0
    for step in steps:
        assert len(step) == 1 and step[0] in ground, step
        a = ground[step[0]]
        assert all(p in false for p in a.pre), f"{a.name}: precondition does not hold"
        false.update(a.deletes)
        if a.action.kind == "grasp":
            removed.add(a.action.obj)
        total += a.cost
    assert set(goal) <= removed
    return total


def _sas_operators(text: str) -> dict[str, tuple[list[tuple[int, int]], list[tuple[int, int, int]], int]]:
    """name -> (prevail, [(var, pre, post)], cost), parsed from SAS+ text."""
    lines = text.splitlines()
    ops = {}
    i = 0
    while i < len(lines):
        if lines[i] == "begin_operator":
            name = lines[i + 1]
            n_prev = int(lines[i + 2])
            prevail = [tuple(map(int, lines[i + 3 + k].split())) for k in range(n_prev)]
            j = i + 3 + n_prev
            n_eff = int(lines[j])
            effs = []
            for k in range(n_eff):
                parts = list(map(int, lines[j + 1 + k].split()))
                assert parts[0] == 0  # no effect conditions
                effs.append(tuple(parts[1:]))
            cost = int(lines[j + 1 + n_eff])
            assert lines[j + 2 + n_eff] == "end_operator"
            ops[name] = (prevail, effs, cost)
            i = j + 3 + n_eff
        else:
            i += 1
    return ops


@pytest.mark.parametrize("n,seed", [(4, 0), (5, 1), (6, 2), (8, 3), (8, 4), (10, 5), (12, 6), (16, 7), (16, 8)])
@pytest.mark.parametrize("with_costs", [False, True])
def test_sas_search_matches_pddl_route(n: int, seed: int, with_costs: bool) -> None:
    names = _names(n)
    facts = random_facts(n, seed, density=2.0 if n <= 8 else 1.0)
    costs = _push_costs(names, seed) if with_costs else None
    goal = sorted(removable_objects(names, facts, costs))
    assert goal
    sas = compile_sas(names, facts, goal, costs)
    strips = compile_strips(names, facts, goal, costs, positive=True)
    assert sas.unit_cost == strips.unit_cost == (not with_costs)
    assert ("begin_metric\n1\n" in sas.text) == with_costs
    assert set(sas.actions) <= set(strips.actions)
    assert all(sas.actions[k] == strips.actions[k] for k in sas.actions)
    res = run_sas(sas.text, time_limit_s=30)
    ref = run_downward(strips.domain, strips.problem, time_limit_s=60)
    assert res.solved and ref.solved and res.optimal and ref.optimal and not res.timed_out
    assert res.cost == ref.cost
    assert _replay(names, facts, goal, costs, res.steps) == res.cost
    assert all(s[0] in sas.actions for s in res.steps)


def test_sas_operator_encoding() -> None:
    # o1 blocks pushing o0 along dir1, and no action on o0 is needed otherwise: the push
    # both requires free-block_dir-o1-o0-dir1 and sets it (it deletes every block_dir
    # of o0), so the variable is in the effect with pre-value 0, not in the prevail list.
    facts = {("block_dir", "o1", "o0", "dir1"), ("block_grasp", "o1", "o0")}
    sas = compile_sas(_names(2), facts, ["o0"])
    assert sas.text.startswith("begin_version\n3\nend_version\nbegin_metric\n0\nend_metric\n")
    ops = _sas_operators(sas.text)
    assert len(ops) == sas.n_actions == len(sas.actions)
    for prevail, effs, cost in ops.values():
        assert cost == 1 and effs
        assert not {v for v, _ in prevail} & {v for v, _, _ in effs}
    prevail, effs, _ = ops["push_o0_dir1"]
    assert prevail == [] and len(effs) == 2 and any(pre == 0 and post == 0 for _, pre, post in effs)
    # pushing o0 along dir2 needs nothing: both its deletes become effects from "any"
    assert ops["push_o0_dir2"][0] == [] and all(pre == -1 for _, pre, _ in ops["push_o0_dir2"][1])
    # grasping o0 needs block_grasp(o1, o0) gone: a prevail condition
    assert len(ops["grasp_o0"][0]) == 1
    # o1's pushes make its block_* facts false: kept, with those effects
    assert "push_o1_dir1" in ops and len(ops["push_o1_dir1"][1]) == 2
    # a push with no effect at all is left out (nothing around o0 here)
    lone = compile_sas(_names(1), set(), ["o0"])
    assert set(lone.actions) == {"grasp_o0"} and lone.n_actions == 1
    with pytest.raises(ValueError):
        compile_sas(_names(1), set(), ["o7"])


def test_sas_costs_and_empty_goal() -> None:
    facts = {("block_grasp", "o0", "o1"), ("block_grasp", "o1", "o0")}
    costs = {("o0", d): 5 for d in DIRECTIONS}
    costs.update({("o1", d): 9 for d in ("dir1", "dir2", "dir4")})
    costs[("o1", "dir3")] = 2
    sas = compile_sas(_names(2), facts, _names(2), costs)
    assert not sas.unit_cost
    res = run_sas(sas.text, time_limit_s=10)
    assert res.cost == 4 and res.steps[0] == ("push_o1_dir3",) and res.optimal
    empty = run_sas(compile_sas(_names(2), facts, []).text, time_limit_s=10)
    assert empty.solved and empty.steps == () and empty.cost == 0


def test_sas_unsolvable() -> None:
    # stuck (see test_removable_matches_planner_on_unsolvable), and ungraspable
    for facts in ({("on", "o1", "o0"), ("block_grasp", "o0", "o1")}, {("ungraspable", "o1")}):
        assert "o1" not in removable_objects(_names(2), facts)
        res = run_sas(compile_sas(_names(2), facts, _names(2)).text, time_limit_s=10)
        assert res.unsolvable and not res.solved and not res.timed_out
        lama = run_sas(compile_sas(_names(2), facts, _names(2)).text, alias=downward.ANYTIME_ALIAS, time_limit_s=10)
        assert lama.unsolvable and not lama.solved


@pytest.mark.parametrize("with_costs", [False, True])
def test_sas_lama_via_driver(with_costs: bool) -> None:
    names = _names(8)
    facts = random_facts(8, 5)
    costs = _push_costs(names, 5) if with_costs else None
    goal = sorted(removable_objects(names, facts, costs))
    sas = compile_sas(names, facts, goal, costs)
    opt = run_sas(sas.text, time_limit_s=30)
    lama = run_sas(sas.text, alias=downward.ANYTIME_ALIAS, time_limit_s=10)
    assert lama.solved and not lama.optimal and lama.config == downward.ANYTIME_ALIAS
    assert lama.cost >= opt.cost
    assert _replay(names, facts, goal, costs, lama.steps) == lama.cost


def _recording_popen(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    pids: list[int] = []
    real = subprocess.Popen

    class Recording(real):  # type: ignore[misc, valid-type]
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            pids.append(self.pid)

    monkeypatch.setattr(downward.subprocess, "Popen", Recording)
    return pids


def _group_gone(pgid: int, wait_s: float = 1.0) -> bool:
    """No live process left in the process group (within ``wait_s``: a process SIGKILLed
    closes its pipe before it is quite dead). A killed driver's search child is
    reparented to init and stays a zombie until init reaps it (which a container's
    pid 1 may never do): dead, so it does not count."""
    deadline = time.perf_counter() + wait_s
    while not _no_live_member(pgid):
        if time.perf_counter() > deadline:
            return False
        time.sleep(0.01)
    return True


def _no_live_member(pgid: int) -> bool:
    proc = Path("/proc")
    if not proc.is_dir():
        try:
            os.killpg(pgid, 0)
        except ProcessLookupError:
            return True
        return False
    for stat in proc.glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue  # exited meanwhile
        state, pgrp = fields[0], int(fields[2])
        if pgrp == pgid and state not in ("Z", "X"):
            return False
    return True


def test_sas_wall_clock_time_out(monkeypatch: pytest.MonkeyPatch) -> None:
    # Blind search on 24 objects runs for minutes; 0.3 s of wall-clock time it gets.
    names = _names(24)
    facts = random_facts(24, 2)
    sas = compile_sas(names, facts, sorted(removable_objects(names, facts)))
    pids = _recording_popen(monkeypatch)
    t0 = time.perf_counter()
    with pytest.raises(PlannerError, match="timed out"):
        run_sas(sas.text, search=downward.BLIND, time_limit_s=0.3)
    assert time.perf_counter() - t0 < 1.0
    assert len(pids) == 1 and _group_gone(pids[0])


def test_sas_anytime_time_out_returns_best_plan(monkeypatch: pytest.MonkeyPatch) -> None:
    # LAMA does not finish its iterations on 40 objects within 1.5 s but has a plan
    # (optimum 23, see test_optimal_time_out_falls_back_to_anytime); driver and search
    # are both gone afterwards.
    names = _names(40)
    facts = random_facts(40, 0)
    goal = sorted(removable_objects(names, facts))
    sas = compile_sas(names, facts, goal)
    pids = _recording_popen(monkeypatch)
    t0 = time.perf_counter()
    res = run_sas(sas.text, alias=downward.ANYTIME_ALIAS, time_limit_s=1.5)
    assert time.perf_counter() - t0 < 2.2  # killed on time, the search child too
    assert res.solved and res.timed_out and not res.optimal and res.cost >= 23
    assert _replay(names, facts, goal, None, res.steps) == res.cost
    assert len(pids) == 1 and _group_gone(pids[0])
    # run_downward: the same wall-clock behaviour (translation included)
    strips = compile_strips(names, facts, goal)
    t0 = time.perf_counter()
    res = run_downward(strips.domain, strips.problem, alias=downward.ANYTIME_ALIAS, time_limit_s=2.0)
    assert time.perf_counter() - t0 < 2.7
    assert res.solved and res.timed_out and not res.optimal and res.cost >= 23
    assert len(pids) == 2 and _group_gone(pids[1])


def test_sas_planner_errors(monkeypatch: pytest.MonkeyPatch) -> None:
    sas = compile_sas(_names(2), set(), _names(2))
    with pytest.raises(PlannerError, match="exit code"):
        run_sas(sas.text, search="astar(nosuchheuristic())", time_limit_s=20)
    with pytest.raises(PlannerError, match="exit code"):
        run_sas("begin_version\n3\nend_version\nnonsense\n", time_limit_s=20)
    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "up_fast_downward" else real(name, *a)
    )
    with pytest.raises(PlannerError, match="pip install up-fast-downward"):
        run_sas(sas.text, time_limit_s=20)
    with pytest.raises(PlannerError, match="pip install up-fast-downward"):
        run_sas(sas.text, alias=downward.ANYTIME_ALIAS, time_limit_s=20)
