"""Write the grounded task as Fast Downward's SAS+ input, so only its search runs.

`compile.compile_strips` writes grounded PDDL that Fast Downward's Python translator then
parses, normalises and grounds all over again (>= 0.1 s per call even for one object).
The task is already grounded and, in the positive form, delete-free, so its SAS+ form is
immediate: one binary variable per atom of the positive form, values ``0 = Atom x()``
and ``1 = NegatedAtom x()`` (the translator's order for a binary variable),

* ``removed-o`` per object, false initially, goal: true for the goal objects;
* ``free-X`` per blocking/IK fact X any action mentions, false initially (X holds);
* per grounded action (same grounding and names as `compile_strips`, ``grasp_o1``,
  ``push_o0_dir1``): precondition ``free-X = 0`` for each fact it needs false, effect
  ``free-X := 0`` for each fact it makes false, plus ``removed-o := 0`` for a grasp.
  A variable both required and set goes into the effect's pre-value (``var 0 0``), not
  the prevail list: the search component assumes the two disjoint (the translator's
  ``SASOperator.validate`` asserts it) and misbehaves otherwise.

An empty goal gets one extra variable that holds initially (the search component
refuses a task without goal). No mutex groups, no axioms. Metric 0 (the search then
counts every action as 1) when all costs are 1, else metric 1 with the push costs.
Actions without any effect (a push that frees nothing) are left out, as the translator
leaves them out: they can never be part of a plan.

Format: https://www.fast-downward.org/TranslatorOutputFormat (version 3), as written by
the translator's ``sas_tasks.py``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from clearcli.planning.compile import _atom, ground_actions
from clearcli.planning.types import Action
from clearcli.predicates.state import Fact

SAS_FILE_VERSION = 3
_TRUE, _FALSE = 0, 1  # value indices of a binary variable: Atom, NegatedAtom


@dataclass(frozen=True)
class SasTask:
    text: str  # SAS+ task, Fast Downward translator-output format version 3
    actions: Mapping[str, Action]  # operator name (lower case) -> Action
    unit_cost: bool  # every action costs 1 (metric 0)
    n_actions: int  # operators in ``text``


def compile_sas(
    objects: Sequence[str],
    facts: Iterable[Fact],
    goal: Iterable[str],
    push_costs: Mapping[tuple[str, str], int] | None = None,
) -> SasTask:
    """SAS+ text of removing ``goal`` from the state ``facts`` (positive formulation)."""
    facts = frozenset(facts)
    goal = tuple(dict.fromkeys(goal))
    unknown = [o for o in goal if o not in set(objects)]
    if unknown:
        raise ValueError(f"goal objects {unknown} are not among the objects")
    ground = ground_actions(objects, facts, push_costs)
    unit = all(a.cost == 1 for a in ground)

    names: list[str] = [f"removed-{o}" for o in objects]
    index: dict[str, int] = {n: i for i, n in enumerate(names)}
    for a in ground:
        for f in a.pre + a.deletes:
            atom = "free-" + _atom(f)
            if atom not in index:
                index[atom] = len(names)
                names.append(atom)

    ops: list[str] = []
    actions: dict[str, Action] = {}
    for a in ground:
        pre = {index["free-" + _atom(f)] for f in a.pre}
        eff = {index["free-" + _atom(f)] for f in a.deletes}
        if a.action.kind == "grasp":
            eff.add(index[f"removed-{a.action.obj}"])
        if not eff:
            continue  # changes nothing: never useful
        prevail = sorted(pre - eff)  # a variable both required and set: in its effect
        lines = ["begin_operator", a.name.lower(), str(len(prevail))]
        lines += [f"{v} {_TRUE}" for v in prevail]
        lines.append(str(len(eff)))
        lines += [f"0 {v} {_TRUE if v in pre else -1} {_TRUE}" for v in sorted(eff)]
        lines += [str(a.cost), "end_operator"]
        ops.append("\n".join(lines))
        actions[a.name.lower()] = a.action

    init = [_FALSE] * len(names)
    goal_vars = sorted(index[f"removed-{o}"] for o in goal)
    if not goal_vars:
        # The search refuses an empty goal; like the translator, give it one that holds.
        goal_vars = [len(names)]
        names.append("goal-holds")
        init.append(_TRUE)

    out = ["begin_version", str(SAS_FILE_VERSION), "end_version"]
    out += ["begin_metric", "0" if unit else "1", "end_metric"]
    out.append(str(len(names)))
    for i, n in enumerate(names):
        out += ["begin_variable", f"var{i}", "-1", "2", f"Atom {n}()", f"NegatedAtom {n}()", "end_variable"]
    out.append("0")  # mutex groups
    out.append("begin_state")
    out += [str(v) for v in init]
    out.append("end_state")
    out += ["begin_goal", str(len(goal_vars))]
    out += [f"{v} {_TRUE}" for v in goal_vars]
    out.append("end_goal")
    out.append(str(len(ops)))
    out += ops
    out.append("0")  # axioms
    return SasTask(text="\n".join(out) + "\n", actions=actions, unit_cost=unit, n_actions=len(ops))
