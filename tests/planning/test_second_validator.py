"""The second plan validator (VAL, `helpers.validate.validate_files_second`) beside the
first (unified-planning, `validate_files`): both on the plan `clear` finds for a small
state, on broken plans, on the clearance-cost domain, and on a hand-made domain with the
grasp kinds to come (grasp_rim, slide_grasp: a positive static precondition, predicates
of their own, costs 2 and 3)."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers.downward import solve
from helpers.plan_scenes import dummy_state
from helpers.validate import second_verdict, validate_files, validate_files_second

from clearcli.planning.pddl import domain_for, domain_text, write_plan, write_problem
from clearcli.planning.types import Action
from clearcli.predicates.state import DIRECTIONS, Fact

NAMES = ["o0", "o1", "o2", "o3"]
# o0 and o1 block each other's grasp; o1 cannot be pushed at all, o0 only along dir4
# (o1 blocks dir1 and dir2, dir3 would push it off the table); o2 stands on o3.
FACTS: frozenset[Fact] = frozenset(
    {
        ("block_grasp", "o0", "o1"),
        ("block_grasp", "o1", "o0"),
        ("block_dir", "o1", "o0", "dir1"),
        ("block_dir", "o1", "o0", "dir2"),
        ("push_off_table", "o0", "dir3"),
        ("on", "o2", "o3"),
        *(("block_dir", "o0", "o1", d) for d in DIRECTIONS),
    }
)
# The only optimal plans: push o0 along dir4, then the four grasps (o2 before o3).
HAND = ["(push o0 dir4)", "(grasp o0)", "(grasp o1)", "(grasp o2)", "(grasp o3)"]


def files(tmp_path: Path, domain: str, problem: str, sub: str = "") -> tuple[Path, Path]:
    where = tmp_path / sub
    where.mkdir(parents=True, exist_ok=True)
    d, p = where / "domain.pddl", where / "problem.pddl"
    d.write_text(domain, encoding="utf-8")
    p.write_text(problem, encoding="utf-8")
    return d, p


def plan_file(tmp_path: Path, name: str, steps: list[str], cost: int, unit: bool = True) -> Path:
    """A plan in Fast Downward's format, as write_plan writes it."""
    path = tmp_path / name
    path.write_text("".join(s + "\n" for s in steps) + f"; cost = {cost} ({'unit' if unit else 'general'} cost)\n")
    return path


def both(d: Path, p: Path, plan: Path) -> tuple[bool, bool]:
    return validate_files(d, p, plan), validate_files_second(d, p, plan)


# --------------------------------------------------------------- (a) the plan clear finds
def test_plan_from_clear_is_accepted_by_both(tmp_path: Path) -> None:
    state = dummy_state(NAMES, FACTS)
    d, p = files(tmp_path, domain_text(), write_problem(state))
    solved = solve(NAMES, FACTS, NAMES, None)
    assert solved is not None and solved.cost == 5
    assert sorted(a.pddl() for a in solved.actions) == sorted(HAND)
    plan = tmp_path / "clear.plan"
    plan.write_text(write_plan(solved.actions, solved.cost, unit_cost=True))
    assert both(d, p, plan) == (True, True)
    verdict = second_verdict(d, p, plan)
    assert (verdict.value, verdict.stated_cost, verdict.reason) == (5, 5, "")
    # the hand-ordered plan the broken ones below are edits of
    assert both(d, p, plan_file(tmp_path, "hand.plan", HAND, 5)) == (True, True)


# ------------------------------------------------------------------- (b) broken plans
@pytest.mark.parametrize(
    "steps, cost, why",
    [
        # grasp o3 while o2 still stands on it (every other precondition holds)
        pytest.param(HAND[:3] + ["(grasp o3)", "(grasp o2)"], 5, "(on o2 o3)", id="grasp-under-a-stack"),
        # o3 is never grasped
        pytest.param(HAND[:-1], 4, "(removed o3)", id="goal-not-reached"),
        # o1 blocks pushing o0 along dir1
        pytest.param(["(push o0 dir1)"] + HAND[1:], 5, "(block_dir o1 o0 dir1)", id="blocked-push"),
    ],
)
def test_broken_plans_are_rejected_by_both(tmp_path: Path, steps: list[str], cost: int, why: str) -> None:
    d, p = files(tmp_path, domain_text(), write_problem(dummy_state(NAMES, FACTS)))
    plan = plan_file(tmp_path, "broken.plan", steps, cost)
    assert both(d, p, plan) == (False, False)
    assert why in second_verdict(d, p, plan).reason  # VAL names the fact at fault


def test_a_wrong_stated_cost_is_rejected(tmp_path: Path) -> None:
    d, p = files(tmp_path, domain_text(), write_problem(dummy_state(NAMES, FACTS)))
    plan = plan_file(tmp_path, "cost.plan", HAND, 4)
    # unified-planning does not read the cost line; VAL's value of the plan is 5
    assert both(d, p, plan) == (True, False)
    assert "VAL's value of it is 5" in second_verdict(d, p, plan).reason


@pytest.mark.parametrize(
    "step, exit_zero",
    [("(fly o0)", True), ("(grasp o0 dir1)", False)],  # unknown action; a grasp with two arguments
    ids=["unknown-action", "wrong-arity"],
)
def test_plans_val_cannot_read_are_rejected(tmp_path: Path, step: str, exit_zero: bool) -> None:
    # VAL exits 0 on an unknown action ("Bad plan description!") and crashes on a wrong
    # arity: the verdict must come from what it reports, not from its exit code alone
    d, p = files(tmp_path, domain_text(), write_problem(dummy_state(NAMES, FACTS)))
    plan = plan_file(tmp_path, "unreadable.plan", [step] + HAND, 6)
    verdict = second_verdict(d, p, plan)
    assert not verdict.valid and verdict.reason
    if exit_zero:
        assert "Bad plan description" in verdict.reason


# --------------------------------------------------------- (c) the clearance-cost domain
def test_clearance_cost_domain(tmp_path: Path) -> None:
    costs = {("o0", "dir4"): 3, ("o1", "dir1"): 2}
    state = dummy_state(NAMES, FACTS, costs)
    domain = domain_for(state)
    assert "(increase (total-cost) (push-cost ?o ?d))" in domain
    d, p = files(tmp_path, domain, write_problem(state))
    solved = solve(NAMES, FACTS, NAMES, costs)
    assert solved is not None and solved.cost == 7  # the push along dir4 costs 3
    plan = tmp_path / "clear.plan"
    plan.write_text(write_plan(solved.actions, solved.cost, unit_cost=False))
    assert both(d, p, plan) == (True, True)
    assert second_verdict(d, p, plan).value == 7
    # the same actions claiming the unit-cost count: VAL reads the push's cost 3
    unit = plan_file(tmp_path, "unit.plan", [a.pddl() for a in solved.actions], 5, unit=False)
    assert validate_files_second(d, p, unit) is False
    assert "VAL's value of it is 7" in second_verdict(d, p, unit).reason
    blocked = plan_file(tmp_path, "blocked.plan", ["(push o0 dir1)"] + HAND[1:], 5, unit=False)
    assert both(d, p, blocked) == (False, False)
    # a plan clear writes with Action values, cost from the function
    acts = (Action("push", "o0", "dir4"), *(Action("grasp", o) for o in ("o0", "o1", "o2", "o3")))
    written = tmp_path / "written.plan"
    written.write_text(write_plan(acts, 7, unit_cost=False))
    assert both(d, p, written) == (True, True)


# ------------------------------------------ (d) grasp_rim and slide_grasp, hand-made domain
RIM_DOMAIN = """(define (domain table-clearing-kinds)
  ; The thesis's domain (pddl/domain.pddl) with two more grasp kinds of the same form:
  ; grasp_rim and slide_grasp, each with a positive static precondition, a blocking and an
  ; IK predicate of its own, the grasp's effects, and costs 2 and 3.
  (:requirements :typing :negative-preconditions :existential-preconditions
                 :conditional-effects :action-costs)
  (:types obj direction)
  (:constants dir1 dir2 dir3 dir4 - direction)
  (:predicates
    (on ?a - obj ?b - obj)
    (block_grasp ?a - obj ?b - obj)
    (block_rim ?a - obj ?b - obj)
    (block_slide ?a - obj ?b - obj)
    (block_dir ?a - obj ?b - obj ?d - direction)
    (removed ?o - obj)
    (ik_unfeasible_grasp ?o - obj)
    (ik_unfeasible_rim ?o - obj)
    (ik_unfeasible_slide ?o - obj)
    (ik_unfeasible_dir ?o - obj ?d - direction)
    (ungraspable ?o - obj)
    (rim_graspable ?o - obj)
    (slidable ?o - obj)
    (push_off_table ?o - obj ?d - direction))
  (:functions
    (total-cost) - number)
{grasps}
  (:action push
    :parameters (?o - obj ?d - direction)
    :precondition (and
      (not (removed ?o))
      (not (ik_unfeasible_dir ?o ?d))
      (not (push_off_table ?o ?d))
      (not (exists (?x - obj) (block_dir ?x ?o ?d)))
      (not (exists (?x - obj) (on ?x ?o)))
      (not (exists (?x - obj) (on ?o ?x))))
    :effect (and
      (forall (?x - obj ?e - direction)
        (and (not (block_dir ?o ?x ?e))
             (not (block_dir ?x ?o ?e))
             (not (block_grasp ?o ?x))
             (not (block_grasp ?x ?o))
             (not (block_rim ?o ?x))
             (not (block_rim ?x ?o))
             (not (block_slide ?o ?x))
             (not (block_slide ?x ?o))))
      (not (ik_unfeasible_grasp ?o))
      (increase (total-cost) 1)))
)
"""

GRASP = """
  (:action {name}
    :parameters (?o - obj)
    :precondition (and{offered}
      (not (removed ?o))
      (not ({ik} ?o))
      (not (exists (?x - obj) (on ?x ?o)))
      (not (exists (?x - obj) ({block} ?x ?o))))
    :effect (and
      (removed ?o)
      (forall (?x - obj ?e - direction)
        (and (not (on ?o ?x))
             (not (block_grasp ?o ?x))
             (not (block_rim ?o ?x))
             (not (block_slide ?o ?x))
             (not (block_dir ?o ?x ?e))))
      (increase (total-cost) {cost})))
"""

KINDS = [  # name, offered (positive static), blocking, IK predicate, cost
    ("grasp", "(not (ungraspable ?o))", "block_grasp", "ik_unfeasible_grasp", 1),
    ("grasp_rim", "(rim_graspable ?o)", "block_rim", "ik_unfeasible_rim", 2),
    ("slide_grasp", "(slidable ?o)", "block_slide", "ik_unfeasible_slide", 3),
]


def kinds_domain() -> str:
    grasps = "".join(GRASP.format(name=n, offered="\n      " + o, block=b, ik=ik, cost=c) for n, o, b, ik, c in KINDS)
    return RIM_DOMAIN.replace("{grasps}", grasps)


def kinds_problem(extra: str = "") -> str:
    # o0: too wide for the pinch, its rim can be held; o1: too wide, can be slid off the
    # edge once o2 is out of the way; o2: an ordinary object; o3: not in the goal
    return f"""(define (problem kinds) (:domain table-clearing-kinds)
  (:objects o0 o1 o2 o3 - obj)
  (:init
    (ungraspable o0) (rim_graspable o0)
    (ungraspable o1) (slidable o1) (block_slide o2 o1)
    (ungraspable o3){extra}
    (= (total-cost) 0))
  (:goal (and (removed o0) (removed o1) (removed o2)))
  (:metric minimize (total-cost)))
"""


def test_kinds_domain_has_the_forms_it_is_for() -> None:
    text = kinds_domain()
    for form in (
        "(:action grasp_rim",
        "(:action slide_grasp",
        "(rim_graspable ?o)\n",
        "(slidable ?o)\n",
        "(not (exists (?x - obj) (block_rim ?x ?o)))",
        "(not (ik_unfeasible_slide ?o))",
        "(increase (total-cost) 2)",
        "(increase (total-cost) 3)",
        "(forall (?x - obj ?e - direction)",
    ):
        assert form in text, form


def test_grasp_kinds_valid_plan_is_accepted_by_both(tmp_path: Path) -> None:
    d, p = files(tmp_path, kinds_domain(), kinds_problem())
    steps = ["(grasp_rim o0)", "(grasp o2)", "(slide_grasp o1)"]
    plan = plan_file(tmp_path, "kinds.plan", steps, 6, unit=False)
    assert both(d, p, plan) == (True, True)
    assert second_verdict(d, p, plan).value == 6  # 2 + 1 + 3
    # the costs count: the same plan stating its length is rejected
    assert validate_files_second(d, p, plan_file(tmp_path, "len.plan", steps, 3)) is False


def test_grasp_rim_needs_rim_graspable(tmp_path: Path) -> None:
    steps = ["(grasp_rim o0)", "(grasp o2)", "(grasp_rim o1)"]  # o1 is not (rim_graspable o1)
    d, p = files(tmp_path, kinds_domain(), kinds_problem())
    plan = plan_file(tmp_path, "norim.plan", steps, 5, unit=False)
    assert both(d, p, plan) == (False, False)
    assert "(rim_graspable o1)" in second_verdict(d, p, plan).reason
    # control: with (rim_graspable o1) the very same plan is valid, so the static fact
    # alone made the difference
    d2, p2 = files(tmp_path, kinds_domain(), kinds_problem("\n    (rim_graspable o1)"), sub="with_rim")
    assert both(d2, p2, plan) == (True, True)


def test_slide_grasp_blocked_and_ik_facts(tmp_path: Path) -> None:
    d, p = files(tmp_path, kinds_domain(), kinds_problem())
    blocked = plan_file(tmp_path, "slide.plan", ["(grasp_rim o0)", "(slide_grasp o1)", "(grasp o2)"], 6, unit=False)
    assert both(d, p, blocked) == (False, False)
    assert "(block_slide o2 o1)" in second_verdict(d, p, blocked).reason
    # the kind's own IK fact stops it
    d2, p2 = files(tmp_path, kinds_domain(), kinds_problem("\n    (ik_unfeasible_rim o0)"), sub="ik")
    plan = plan_file(tmp_path, "kinds.plan", ["(grasp_rim o0)", "(grasp o2)", "(slide_grasp o1)"], 6, unit=False)
    assert both(d2, p2, plan) == (False, False)
    assert "(ik_unfeasible_rim o0)" in second_verdict(d2, p2, plan).reason
