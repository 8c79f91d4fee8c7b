"""The PDDL domain (a package data file) and the problem writer.

The canonical domain is ``clearcli/data/domain.pddl`` (installed with the package as
package data); ``pddl/domain.pddl`` at the top of the source tree is a symbolic link to it,
so the two cannot drift apart. `domain_text()` reads it with importlib.resources, which
works from a source checkout and from an installed wheel alike.

Problem files: objects o0..oN-1 (the `SymbolicState` names, stable by position) with a
comment per object giving its centroid; the initial state holds the state's facts, any
extra facts (the planner's ik_unfeasible_* facts), and, when the state carries clearance
costs, (= (push-cost o d) c) for every object and direction (use `domain_for(state)` as
the domain then); the goal is every goal
object removed, (and) when there is none (already true).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from functools import lru_cache

from clearcli.errors import InputError
from clearcli.planning.types import Action
from clearcli.predicates.grasps import kind as grasp_kind
from clearcli.predicates.grasps import kinds as grasp_kinds
from clearcli.predicates.state import DIRECTIONS, Fact, SymbolicState

DOMAIN_NAME = "table-clearing"
DOMAIN_RESOURCE = "data/domain.pddl"

# name -> arity (with the direction where it has one), for checking facts before writing:
# the shipped domain's (the thesis's pinch), then `fact_arity` adds the other kinds'
FACT_ARITY: dict[str, int] = {
    "on": 2,
    "block_grasp": 2,
    "block_dir": 3,
    "removed": 1,
    "ik_unfeasible_grasp": 1,
    "ik_unfeasible_dir": 2,
    "ungraspable": 1,
    "push_off_table": 2,
}


def fact_arity() -> dict[str, int]:
    """`FACT_ARITY` and, per grasp kind beyond the thesis's (clearcli/predicates/grasps),
    in preference order, its offered, blocking and IK facts (the problem file's order)."""
    out = dict(FACT_ARITY)
    for k in grasp_kinds():
        if not k.thesis:
            out.update({k.facts.offered: 1, k.facts.block: 2, k.facts.ik: 1})
    return out


_FUNCTIONS_UNIT = "  (:functions\n    (total-cost) - number)"
_FUNCTIONS_COST = "  (:functions\n    (total-cost) - number\n    (push-cost ?o - obj ?d - direction) - number)"
_PUSH_COST_UNIT = "      (not (ik_unfeasible_grasp ?o))\n      (increase (total-cost) 1)))"
_PUSH_COST_VAR = "      (not (ik_unfeasible_grasp ?o))\n      (increase (total-cost) (push-cost ?o ?d))))"


@lru_cache(maxsize=1)
def _domain_file() -> str:
    # importlib.resources only here: a plan compiles its SAS task without the domain's
    # text, which only --domain, --problem and `clear domain` read (issue 39)
    from importlib import resources  # noqa: PLC0415

    try:
        return (resources.files("clearcli") / DOMAIN_RESOURCE).read_text(encoding="utf-8")
    except (FileNotFoundError, OSError) as exc:  # a broken installation
        raise InputError(f"the PDDL domain (clearcli/{DOMAIN_RESOURCE}) is missing: reinstall clear ({exc})") from None


def domain_text(clearance_costs: bool = False, kinds: Sequence[str] = ("pinch",)) -> str:
    """The domain: the file as shipped (unit costs, the thesis's pinch grasp alone), or
    with ``clearance_costs`` the variant whose push costs (push-cost ?o ?d) come from the
    problem, and with ``kinds`` beyond the thesis's pinch (whose grasp the file holds)
    the actions of those grasp kinds (`with_grasp_kinds`). The unit-cost file uses only
    standard :action-costs (every PDDL parser takes it); the variant's static cost
    function is accepted by Fast Downward and unified-planning."""
    text = _domain_file()
    if clearance_costs:  # first: the grasp kinds add effects between the anchors
        if _FUNCTIONS_UNIT not in text or _PUSH_COST_UNIT not in text:
            raise InputError(f"clearcli/{DOMAIN_RESOURCE}: edited so that the push cost cannot be swapped in")
        text = text.replace(_FUNCTIONS_UNIT, _FUNCTIONS_COST).replace(_PUSH_COST_UNIT, _PUSH_COST_VAR)
    extra = [k for k in kinds if not grasp_kind(k).thesis]
    return with_grasp_kinds(text, extra) if extra else text


_PREDICATES_END = "    (push_off_table ?o - obj ?d - direction))"
_GRASP_EFFECT_END = "             (not (block_dir ?o ?x ?e))))\n      (increase (total-cost) 1)))"
_PUSH_EFFECT_END = "             (not (block_grasp ?x ?o))))\n      (not (ik_unfeasible_grasp ?o))"


def with_grasp_kinds(text: str, kinds: Sequence[str]) -> str:
    """The domain with one action per grasp kind in ``kinds`` (beyond the thesis's pinch,
    in preference order), each the kind's own text (`GraspKind.pddl_action`: offered by
    a static fact, blocked by its own blocking predicate, ruled out by its own IK fact,
    its cost its own: the planner prefers the cheapest, the surest). The grasps delete
    the new blocking facts as they delete the thesis's. A push deletes, per kind, what
    the kind's flags say (clearcli/predicates/grasps/base.py): the object's blocking of
    the others' grasps always (it moves out of their way), what blocks its own grasp of
    that kind and its IK fact when the kind's poses move with it (``push_clears_blocks``,
    ``push_clears_ik``; a slide's do not: it is made for where the object stands)."""
    for piece in (_PREDICATES_END, _GRASP_EFFECT_END, _PUSH_EFFECT_END):
        if piece not in text:
            raise InputError(f"clearcli/{DOMAIN_RESOURCE}: edited so that the grasp kinds cannot be added")
    chosen = [grasp_kind(k) for k in kinds]
    blocks = [k.facts.block for k in chosen]
    preds, grasp_dels, push_dels, push_ik, actions = [], [], [], [], []
    for k in chosen:
        f = k.facts
        preds += [f"    ({f.offered} ?o - obj)", f"    ({f.block} ?a - obj ?b - obj)", f"    ({f.ik} ?o - obj)"]
        grasp_dels.append(f"\n             (not ({f.block} ?o ?x))")
        push_dels.append(
            f"\n             (not ({f.block} ?o ?x))"
            + (f"\n             (not ({f.block} ?x ?o))" if k.push_clears_blocks else "")
        )
        if k.push_clears_ik:
            push_ik.append(f"\n      (not ({f.ik} ?o))")
        actions.append(k.pddl_action(blocks))
    text = text.replace(_PREDICATES_END, _PREDICATES_END[:-1] + "\n" + "\n".join(preds) + ")")
    text = text.replace(
        _GRASP_EFFECT_END,
        "             (not (block_dir ?o ?x ?e))" + "".join(grasp_dels) + "))\n      (increase (total-cost) 1)))",
    )
    text = text.replace(
        _PUSH_EFFECT_END,
        "             (not (block_grasp ?x ?o))"
        + "".join(push_dels)
        + "))\n      (not (ik_unfeasible_grasp ?o))"
        + "".join(push_ik),
    )
    body = text.rstrip()
    assert body.endswith(")")
    return body[:-1].rstrip() + "\n" + "".join(actions) + ")\n"


def domain_for(state: SymbolicState) -> str:
    """The domain that goes with `write_problem(state)`: with clearance costs when the
    state carries push costs, with the actions of the grasp kinds its facts offer."""
    offered = {f[0] for f in state.facts}
    chosen = [k.name for k in grasp_kinds() if k.thesis or k.facts.offered in offered]
    return domain_text(clearance_costs=bool(state.push_costs), kinds=chosen)


def unit_cost(state: SymbolicState) -> bool:
    """Every action of `domain_for(state)` costs 1: no push costs, no grasp kind that
    costs more offered (a rim grasp costs 2, a slide 3)."""
    offered = {f for k in grasp_kinds() if k.facts.cost != 1 for f in k.facts.static()}
    return not state.push_costs and not any(f[0] in offered for f in state.facts)


def fact_to_pddl(fact: Fact) -> str:
    """("block_dir", "o1", "o0", "dir3") -> "(block_dir o1 o0 dir3)"."""
    return "(" + " ".join(fact) + ")"


def _check_fact(fact: Fact, names: set[str]) -> None:
    arity = fact_arity()
    if not fact or fact[0] not in arity or len(fact) != arity[fact[0]] + 1:
        raise ValueError(f"not a fact of the domain: {fact!r}")
    for arg in fact[1:]:
        if arg not in names and arg not in DIRECTIONS:
            raise ValueError(f"fact {fact!r} names {arg!r}, which is not an object of the state")


def write_problem(
    state: SymbolicState,
    goal_objects: Iterable[str] | None = None,
    extra_facts: Iterable[Fact] = (),
    problem_name: str = "clear-table",
) -> str:
    """The PDDL problem for ``state``: goal = every object in ``goal_objects`` (default:
    all) removed; ``extra_facts`` are added to the initial state (e.g. ik_unfeasible_*)."""
    names = list(state.names())
    known = set(names)
    goal: Sequence[str] = names if goal_objects is None else list(goal_objects)
    for g in goal:
        if g not in known:
            raise ValueError(f"goal object {g!r} is not an object of the state")
    facts = set(state.facts) | set(tuple(f) for f in extra_facts)
    for f in facts:
        _check_fact(f, known)

    lines = [f"; {state.source}" if state.source else "; clear: table-clearing problem"]
    lines.append("; objects by position (sensor frame centroid, m):")
    for obj in state.objects:
        c = obj.centroid
        lines.append(f";   {obj.name}: ({c[0]:+.3f}, {c[1]:+.3f}, {c[2]:+.3f})")
    lines.append(f"(define (problem {problem_name})")
    lines.append(f"  (:domain {DOMAIN_NAME})")
    lines.append("  (:objects" + ("".join(f" {n}" for n in names) + " - obj" if names else "") + ")")
    lines.append("  (:init")
    order = {k: i for i, k in enumerate(fact_arity())}

    def sort_key(f: Fact) -> tuple[int | tuple[int, str], ...]:
        return (order[f[0]], *(_name_key(a) for a in f[1:]))

    for f in sorted(facts, key=sort_key):
        lines.append("    " + fact_to_pddl(f))
    if state.push_costs:  # the clearance-cost domain (see domain_for)
        for name in names:
            for d in DIRECTIONS:
                cost = int(state.push_costs.get((name, d), 1))
                if cost < 1:
                    raise ValueError(f"push cost of ({name}, {d}) must be a positive integer, got {cost}")
                lines.append(f"    (= (push-cost {name} {d}) {cost})")
    lines.append("    (= (total-cost) 0))")
    if goal:
        lines.append("  (:goal (and" + "".join(f" (removed {g})" for g in goal) + "))")
    else:
        lines.append("  (:goal (and))")
    lines.append("  (:metric minimize (total-cost)))")
    return "\n".join(lines) + "\n"


def _name_key(name: str) -> tuple[int, str]:
    # o10 after o9
    if name[:1] == "o" and name[1:].isdigit():
        return (int(name[1:]), "")
    return (1 << 30, name)


def write_plan(actions: Sequence[Action], cost: int, unit_cost: bool) -> str:
    """A plan in Fast Downward's plan-file format, in the lifted domain's terms: one
    ``(action args)`` per line, then ``; cost = N (unit cost)`` or ``(general cost)``."""
    lines = [a.pddl() for a in actions]
    lines.append(f"; cost = {int(cost)} ({'unit' if unit_cost else 'general'} cost)")
    return "\n".join(lines) + "\n"
