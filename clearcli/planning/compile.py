"""Compile a symbolic state into grounded STRIPS PDDL for Fast Downward.

The lifted domain in ``pddl/domain.pddl`` documents the model (negated ``exists``
preconditions, ``forall``/``when`` effects, a ``forall`` goal). Fast Downward only runs
that with blind or h^max A*, and slowly; the same model written per problem as grounded
STRIPS lets A* + LM-cut prove optimality in well under a second (see benchmarks/plan.py).

Grounding uses one property of the model: no action ever *adds* an ``on``, ``block_*``
or ``ik_unfeasible_*`` fact; they are only deleted. So

* a negative precondition on a fact that is false initially always holds: dropped;
* a conditional delete ``(when X (not X))`` is an unconditional delete, and deleting a
  fact that is false initially is a no-op: dropped;
* with ``positive=True`` each remaining fact X is replaced by its complement ``free-X``
  (true when X is false): "not X" becomes the positive precondition ``free-X`` and
  "delete X" becomes "add free-X". The task is then delete-free, which makes plan
  existence a simple fixpoint (`removable_objects`) and LM-cut very well informed.

Static facts (``ungraspable``, ``push_off_table``) remove the action instead, and the
other grasp kinds' "offered" facts (``rim_graspable``, ``slidable``) add it. What a push
deletes of each grasp kind's facts is the kind's own say (its ``push_clears_*`` flags,
clearcli/predicates/grasps/base.py), as in the lifted domain (pddl.with_grasp_kinds).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from clearcli.planning.types import Action
from clearcli.predicates.grasps import kinds as grasp_kinds
from clearcli.predicates.state import DIRECTIONS, Fact

_NAME_OK = re.compile(r"^[a-z][a-z0-9_]*$")


@dataclass(frozen=True)
class GroundAction:
    name: str  # PDDL action name
    action: Action
    pre: tuple[Fact, ...]  # facts that must be FALSE (all dynamic, initially true)
    deletes: tuple[Fact, ...]  # facts made false (initially true ones only)
    cost: int


@dataclass(frozen=True)
class CompiledTask:
    domain: str
    problem: str
    actions: Mapping[str, Action]  # PDDL action name (lower case) -> Action
    unit_cost: bool
    n_actions: int


def _check_name(name: str) -> str:
    if not _NAME_OK.match(name):
        raise ValueError(f"object/direction name {name!r} is not a plain PDDL name")
    return name


def _atom(fact: Fact) -> str:
    return "-".join(fact)


def ground_actions(
    objects: Sequence[str],
    facts: Iterable[Fact],
    push_costs: Mapping[tuple[str, str], int] | None = None,
    directions: Sequence[str] = DIRECTIONS,
) -> list[GroundAction]:
    """The applicable-in-principle grounded actions with their pruned pre/deletes."""
    push_costs = push_costs or {}
    true = frozenset(facts)
    for name in objects:
        _check_name(name)
    for d in directions:
        _check_name(d)
    kinds = grasp_kinds()  # in preference order, the thesis's pinch first
    off_table = {(f[1], f[2]) for f in true if f[0] == "push_off_table"}
    static_names = {s for k in kinds for s in k.facts.static()}
    static = {f for f in true if f[0] in static_names}
    offered = {k.name: {o for o in objects if k.facts.offered_in(static, o)} for k in kinds}
    # Index the initially true dynamic facts by the objects they mention.
    on_over: dict[str, list[Fact]] = {o: [] for o in objects}  # on(x, o)
    on_under: dict[str, list[Fact]] = {o: [] for o in objects}  # on(o, x)
    bd_of: dict[tuple[str, str], list[Fact]] = {}  # block_dir(x, o, d)
    bd_any: dict[str, list[Fact]] = {o: [] for o in objects}  # block_dir with o either side
    bd_by: dict[str, list[Fact]] = {o: [] for o in objects}  # block_dir(o, x, d)
    # every grasp kind's blocking facts (block_grasp, block_rim, ...): of o, by o
    kb_of: dict[str, dict[str, list[Fact]]] = {k.name: {o: [] for o in objects} for k in kinds}
    kb_by: dict[str, dict[str, list[Fact]]] = {k.name: {o: [] for o in objects} for k in kinds}
    block_kind = {k.facts.block: k.name for k in kinds}
    thesis = [k for k in kinds if k.thesis]
    others = [k for k in kinds if not k.thesis]
    known = set(objects)
    for f in sorted(true):
        kind = f[0]
        if kind == "on" and f[1] in known and f[2] in known:
            on_over[f[2]].append(f)
            on_under[f[1]].append(f)
        elif kind == "block_dir" and f[1] in known and f[2] in known:
            bd_of.setdefault((f[2], f[3]), []).append(f)
            bd_by[f[1]].append(f)
            bd_any[f[1]].append(f)
            if f[2] != f[1]:
                bd_any[f[2]].append(f)
        elif kind in block_kind and f[1] in known and f[2] in known:
            kb_of[block_kind[kind]][f[2]].append(f)
            kb_by[block_kind[kind]][f[1]].append(f)
    out: list[GroundAction] = []
    for o in objects:
        # o gone: it stands on nothing and blocks nothing any more (any kind of grasp);
        # the thesis's facts in the thesis's order, then the other kinds'
        gone = list(on_under[o])
        gone += [f for k in thesis for f in kb_by[k.name][o]] + list(bd_by[o])
        gone += [f for k in others for f in kb_by[k.name][o]]
        for k in kinds:
            if o not in offered[k.name]:
                continue
            f_k = k.facts
            pre = list(on_over[o]) + list(kb_of[k.name][o])
            if k.on_table:  # slid along the table: nothing under it either
                pre += on_under[o]
            ikk = (f_k.ik, o)
            if ikk in true:
                pre.append(ikk)
            out.append(
                GroundAction(f"{f_k.action}_{o}", Action("grasp", o, None, k.name), tuple(pre), tuple(gone), f_k.cost)
            )
        for d in directions:
            if (o, d) in off_table:
                continue
            pre = list(bd_of.get((o, d), [])) + list(on_over[o]) + list(on_under[o])
            ikd = ("ik_unfeasible_dir", o, d)
            if ikd in true:
                pre.append(ikd)
            deletes = list(bd_any[o])
            for k in kinds:
                # a push moves o out of the others' way always; what blocks its own grasp
                # of a kind only when that kind's poses move with it (not a slide's, made
                # for where o stands)
                deletes += (kb_of[k.name][o] if k.push_clears_blocks else []) + kb_by[k.name][o]
            for k in kinds:
                if k.push_clears_ik and (k.facts.ik, o) in true:
                    deletes.append((k.facts.ik, o))
            cost = int(push_costs.get((o, d), 1))
            if cost < 1:
                raise ValueError(f"push cost of {o} {d} must be a positive integer, got {cost}")
            out.append(
                GroundAction(f"push_{o}_{d}", Action("push", o, d), tuple(pre), tuple(dict.fromkeys(deletes)), cost)
            )
    return out


def removable_objects(
    objects: Sequence[str],
    facts: Iterable[Fact],
    push_costs: Mapping[tuple[str, str], int] | None = None,
) -> set[str]:
    """Objects some plan can remove. Exact, because the model is monotone (facts only
    ever become false), so relaxed reachability is real reachability."""
    actions = ground_actions(objects, facts, push_costs)
    false: set[Fact] = set()  # facts made false so far
    removed: set[str] = set()
    changed = True
    while changed:
        changed = False
        for a in actions:
            if all(p in false for p in a.pre):
                new = [d for d in a.deletes if d not in false]
                if new:
                    false.update(new)
                    changed = True
                if a.action.kind == "grasp" and a.action.obj not in removed:
                    removed.add(a.action.obj)
                    changed = True
    return removed


def compile_strips(
    objects: Sequence[str],
    facts: Iterable[Fact],
    goal: Iterable[str],
    push_costs: Mapping[tuple[str, str], int] | None = None,
    positive: bool = True,
    name: str = "clear",
) -> CompiledTask:
    """Grounded STRIPS domain and problem text.

    positive=True: complement atoms (``free-...``), no negative preconditions at all.
    positive=False: the facts themselves with ``(not ...)`` preconditions
    (``:negative-preconditions``, which Fast Downward's translator compiles away).
    """
    facts = frozenset(facts)
    goal = tuple(goal)
    actions = ground_actions(objects, facts, push_costs)
    unit = all(a.cost == 1 for a in actions)
    used: dict[str, None] = {}
    for a in actions:
        for f in a.pre + a.deletes:
            used[_atom(f)] = None
    preds = [f"removed-{o}" for o in objects]
    preds += [("free-" + p) if positive else p for p in used]
    req = ":strips" + ("" if positive else " :negative-preconditions") + ("" if unit else " :action-costs")
    lines = [f"(define (domain {name}-grounded)", f"  (:requirements {req})", "  (:predicates"]
    lines += [f"    ({p})" for p in preds]
    lines.append("  )")
    if not unit:
        lines.append("  (:functions (total-cost) - number)")
    for a in actions:
        if positive:
            pre = [f"(free-{_atom(f)})" for f in a.pre]
            eff = [f"(free-{_atom(f)})" for f in a.deletes]
        else:
            pre = [f"(not ({_atom(f)}))" for f in a.pre]
            eff = [f"(not ({_atom(f)}))" for f in a.deletes]
        if a.action.kind == "grasp":
            eff.insert(0, f"(removed-{a.action.obj})")
        if not unit:
            eff.append(f"(increase (total-cost) {a.cost})")
        lines.append(f"  (:action {a.name}")
        lines.append("    :parameters ()")
        lines.append(f"    :precondition (and {' '.join(pre)})")
        lines.append(f"    :effect (and {' '.join(eff)}))")
    lines.append(")")
    domain = "\n".join(lines) + "\n"

    init = []
    if not positive:
        init = [f"({p})" for p in used]
    # positive form: every free-X starts false (X is true initially), nothing to list.
    if not unit:
        init.append("(= (total-cost) 0)")
    plines = [f"(define (problem {name}-problem)", f"  (:domain {name}-grounded)", "  (:init"]
    plines += [f"    {i}" for i in init]
    plines.append("  )")
    plines.append("  (:goal (and " + " ".join(f"(removed-{o})" for o in goal) + "))")
    if not unit:
        plines.append("  (:metric minimize (total-cost))")
    plines.append(")")
    problem = "\n".join(plines) + "\n"
    return CompiledTask(
        domain=domain,
        problem=problem,
        actions={a.name.lower(): a.action for a in actions},
        unit_cost=unit,
        n_actions=len(actions),
    )


def random_facts(n_objects: int, seed: int = 0, density: float = 1.0) -> frozenset[Fact]:
    """A random but plausible fact set for ``o0..o{n-1}`` (benchmarks and tests).

    Objects are dropped uniformly on a 0.6 m square; nearby pairs block each other's
    grasps, an object in the swept strip of a push blocks it, a few close pairs stack.
    ``density`` scales the interaction distances.
    """
    rng = np.random.default_rng(seed)
    pos = rng.uniform(0.0, 0.6, size=(n_objects, 2))
    names = [f"o{i}" for i in range(n_objects)]
    units = {"dir1": (1.0, 0.0), "dir2": (-1.0, 0.0), "dir3": (0.0, 1.0), "dir4": (0.0, -1.0)}
    facts: set[Fact] = set()
    for i in range(n_objects):
        for j in range(n_objects):
            if i == j:
                continue
            delta = pos[i] - pos[j]  # from j to i
            dist = float(np.hypot(*delta))
            if i < j and dist < 0.04 * density and rng.random() < 0.5:
                facts.add(("on", names[i], names[j]))
                continue
            if dist < 0.10 * density and rng.random() < 0.6:
                facts.add(("block_grasp", names[i], names[j]))
            for d, u in units.items():
                along = float(delta @ np.asarray(u))
                lateral = abs(float(delta @ np.asarray((-u[1], u[0]))))
                if (0 < along < 0.25 * density and lateral < 0.06 * density) or (
                    -0.08 * density < along < 0 and lateral < 0.05 * density
                ):
                    facts.add(("block_dir", names[i], names[j], d))
    return frozenset(facts)
