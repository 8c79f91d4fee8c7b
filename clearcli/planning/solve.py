"""One Fast Downward plan for the symbolic state (optimal A* + LM-cut, else LAMA within
the time left), and the domain's effects on facts (`progress`), for the backtracking loop
of `clearcli.planning.backtrack`."""

from __future__ import annotations

import functools
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

from clearcli.errors import PlannerError, SettingsError
from clearcli.planning import downward
from clearcli.planning.compile import CompiledTask, compile_strips
from clearcli.planning.sas import SasTask, compile_sas
from clearcli.planning.types import Action
from clearcli.predicates.grasps import kind as grasp_kind
from clearcli.predicates.grasps import kinds as grasp_kinds
from clearcli.predicates.state import DIRECTIONS, Fact


@dataclass(frozen=True)
class Solved:
    actions: tuple[Action, ...]
    cost: int
    optimal: bool
    config: str
    time_s: float
    deadline: bool = False  # the overall time limit cut the anytime search short


def deadline_error(time_limit_s: float) -> PlannerError:
    return PlannerError(
        f"no plan with every action checked within the time limit of {time_limit_s:g} s "
        "(--time-limit, [plan] time_limit_s): raise it"
    )


def solve(
    objects: Sequence[str],
    facts: Iterable[Fact],
    goal: Sequence[str],
    push_costs: Mapping[tuple[str, str], int] | None,
    *,
    time_limit_s: float,
    optimal_max_objects: int,
    optimal_time_s: float,
    anytime_time_s: float,
    formulation: str,
    deadline_at: float | None = None,
) -> Solved | None:
    """One Fast Downward plan for removing ``goal`` (None when proven impossible).

    Optimal A* + LM-cut up to ``optimal_max_objects`` goal objects, for at most
    ``optimal_time_s``; beyond that, or when the optimal search runs out of time, LAMA
    (anytime) within ``anytime_time_s``. Both end by ``deadline_at`` (perf_counter
    seconds; default now + ``time_limit_s``): LAMA stopped by it returns its best plan
    so far with ``deadline=True``.
    """
    if formulation not in ("positive", "negative"):
        raise SettingsError(f'settings: [plan] formulation must be "positive" or "negative", got {formulation!r}')
    if not goal:
        return Solved((), 0, True, "", 0.0)
    if deadline_at is None:
        deadline_at = time.perf_counter() + time_limit_s
    run, task = _task(objects, facts, goal, push_costs, formulation)
    result = None
    remaining = deadline_at - time.perf_counter()
    if remaining <= 0:
        raise deadline_error(time_limit_s)
    if len(goal) <= optimal_max_objects:
        # Leave LAMA half of what is left when the deadline is the tighter bound.
        limit = min(optimal_time_s, remaining if remaining > optimal_time_s + anytime_time_s else remaining / 2)
        try:
            result = run(search=downward.OPTIMAL, time_limit_s=limit)
        except PlannerError as exc:
            if "timed out" not in str(exc):
                raise
            result = None
    deadline = False
    if result is None:
        remaining = deadline_at - time.perf_counter()
        if remaining <= 0.05:
            raise deadline_error(time_limit_s)
        limit = min(anytime_time_s, remaining)
        try:
            result = run(alias=downward.ANYTIME_ALIAS, time_limit_s=limit)
        except PlannerError as exc:
            if "timed out" in str(exc) and limit < anytime_time_s:
                raise deadline_error(time_limit_s) from None
            raise
        deadline = bool(getattr(result, "timed_out", False)) and limit < anytime_time_s
    if result.unsolvable:
        return None
    actions: list[Action] = []
    removed: set[str] = set()
    cost = result.cost
    costs = push_costs or {}
    for step in result.steps:
        if step[0] not in task.actions:
            raise PlannerError(f"Fast Downward returned an unknown action {step[0]!r}")
        action = task.actions[step[0]]
        if action.obj in removed:
            # The grounded form leaves out the lifted domain's (not (removed ?o)): acting
            # on a removed object changes nothing that matters, so an anytime plan that
            # does it is the same plan without that step.
            cost -= action_cost(action, costs)
            continue
        if action.kind == "grasp":
            removed.add(action.obj)
        actions.append(action)
    return Solved(tuple(actions), cost, result.optimal and not deadline, result.config, result.time_s, deadline)


class _Run(Protocol):
    """`downward.run_sas` or `downward.run_downward` with its task given."""

    def __call__(
        self,
        *,
        search: str | None = ...,
        alias: str | None = ...,
        time_limit_s: float = ...,
        optimal: bool | None = ...,
    ) -> downward.DownwardResult: ...


def _task(
    objects: Sequence[str],
    facts: Iterable[Fact],
    goal: Sequence[str],
    push_costs: Mapping[tuple[str, str], int] | None,
    formulation: str,
) -> tuple[_Run, SasTask | CompiledTask]:
    """The grounded task and a function running Fast Downward on it. The positive form
    goes as SAS+ straight into the search component (the translator would only ground
    again what is grounded already); the negative one, which needs the translator to
    compile its negative preconditions away, as PDDL through the driver."""
    if formulation == "positive":
        sas = compile_sas(objects, facts, goal, push_costs)
        return functools.partial(downward.run_sas, sas.text), sas
    task = compile_strips(objects, facts, goal, push_costs, positive=False)
    return functools.partial(downward.run_downward, task.domain, task.problem), task


def action_cost(action: Action, push_costs: Mapping[tuple[str, str], int]) -> int:
    if action.kind == "grasp":
        return grasp_kind(action.grasp_kind).facts.cost
    return int(push_costs.get((action.obj, str(action.direction)), 1))


def action_space(state_facts: frozenset[Fact], obj: str, directions: Sequence[str] = DIRECTIONS) -> list[Action]:
    """The actions the model allows for ``obj`` at all (static facts excluded)."""
    out = []
    for k in grasp_kinds():  # in preference order, the thesis's pinch first
        if k.facts.offered_in(state_facts, obj):
            out.append(Action("grasp", obj, None, k.name))
    for d in directions:
        if ("push_off_table", obj, d) not in state_facts:
            out.append(Action("push", obj, d))
    return out


def progress(facts: frozenset[Fact], action: Action) -> frozenset[Fact]:
    """The facts after ``action``, by the lifted domain's effects (pddl/domain.pddl and
    pddl.with_grasp_kinds: a push deletes of each grasp kind what the kind's flags say)."""
    o = action.obj
    if action.kind == "grasp":
        # o is gone: every fact that names it goes with it (what the domain deletes, plus
        # facts of others about o, which no action can consult any more)
        return frozenset(f for f in facts if o not in f[1:])
    kinds = grasp_kinds()
    # blocking facts o takes part in that stay: what blocks its own grasp of a kind whose
    # poses do not move with it (a slide's); every other one goes, as do the IK facts of
    # the kinds whose poses move with it
    blocks = {"block_dir"} | {k.facts.block for k in kinds}
    kept = {k.facts.block for k in kinds if not k.push_clears_blocks}
    ik_pushed = {k.facts.ik for k in kinds if k.push_clears_ik}
    return frozenset(
        f
        for f in facts
        if not (f[0] in blocks and o in f[1:3] and not (f[0] in kept and f[2] == o))
        and not (f[0] in ik_pushed and f[1:] == (o,))
    )
