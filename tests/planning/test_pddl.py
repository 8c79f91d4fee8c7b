"""Tests of clearcli/planning/pddl.py."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from clearcli.planning.pddl import domain_for, domain_text, write_problem
from clearcli.predicates.state import SymbolicState
from clearcli.predicates.state_builder import compute_state
from clearcli.predicates.synthetic import Box, make_scene
from clearcli.settings import Settings, settings_from_dict

REPO = Path(__file__).resolve().parents[2]


BOX = (0.10, 0.05, 0.05)


def state_of(boxes: list[Box], settings: Settings | None = None) -> SymbolicState:
    frame, seg = make_scene(boxes)
    return compute_state(frame, seg, settings or Settings())


SCENES = {
    "empty": [],
    "lone": [Box((0.0, 0.0), BOX)],
    "side_by_side": [Box((0.0, -0.03), BOX), Box((0.0, 0.03), BOX)],
    "stack": [Box((0.0, 0.0), (0.12, 0.06, 0.05)), Box((0.01, 0.0), (0.08, 0.04, 0.03), base_z=0.05)],
    "row": [Box((0.0, -0.06), BOX), Box((0.0, 0.0), BOX), Box((0.0, 0.06), BOX)],
}


def write(tmp_path: Path, domain: str, problem: str) -> tuple[Path, Path]:
    d, p = tmp_path / "domain.pddl", tmp_path / "problem.pddl"
    d.write_text(domain)
    p.write_text(problem)
    return d, p


def parse_both(d: Path, p: Path, with_pddl_package: bool = True) -> None:
    from unified_planning.io import PDDLReader

    PDDLReader().parse_problem(str(d), str(p))
    if with_pddl_package:
        from pddl import parse_domain, parse_problem

        parse_domain(d)
        parse_problem(p)


def test_top_level_domain_file_is_the_packaged_one() -> None:
    top = REPO / "pddl" / "domain.pddl"
    assert top.read_text(encoding="utf-8") == domain_text()
    assert "(define (domain table-clearing)" in domain_text()


def test_domain_parses_and_has_the_thesis_actions() -> None:
    from pddl import parse_domain

    dom = parse_domain(REPO / "pddl" / "domain.pddl")
    assert {a.name for a in dom.actions} == {"grasp", "push"}
    names = {p.name for p in dom.predicates}
    assert names == {
        "on",
        "block_grasp",
        "block_dir",
        "removed",
        "ik_unfeasible_grasp",
        "ik_unfeasible_dir",
        "ungraspable",
        "push_off_table",
    }


@pytest.mark.parametrize("scene", sorted(SCENES))
def test_problems_parse(scene: str, tmp_path: Path) -> None:
    state = state_of(SCENES[scene])
    parse_both(*write(tmp_path, domain_text(), write_problem(state)))


def test_problem_text_names_goal_and_extra_facts(tmp_path: Path) -> None:
    state = state_of(SCENES["row"])
    text = write_problem(
        state,
        goal_objects=["o0", "o2"],
        extra_facts=[("ik_unfeasible_grasp", "o1"), ("ik_unfeasible_dir", "o0", "dir3")],
    )
    assert "(:objects o0 o1 o2 - obj)" in text
    for obj in state.objects:
        c = obj.centroid
        assert f";   {obj.name}: ({c[0]:+.3f}, {c[1]:+.3f}, {c[2]:+.3f})" in text
    assert "(:goal (and (removed o0) (removed o2)))" in text
    assert "(ik_unfeasible_grasp o1)" in text and "(ik_unfeasible_dir o0 dir3)" in text
    assert "push-cost" not in text  # unit costs
    parse_both(*write(tmp_path, domain_text(), text))
    with pytest.raises(ValueError):
        write_problem(state, goal_objects=["o7"])
    with pytest.raises(ValueError):
        write_problem(state, extra_facts=[("ik_unfeasible_dir", "o0")])
    with pytest.raises(ValueError):
        write_problem(state, extra_facts=[("on", "o0", "o9")])


def test_empty_problem_goal_is_already_true() -> None:
    text = write_problem(state_of([]))
    assert "(:objects)" in text and "(:goal (and))" in text


def test_clearance_cost_variant_parses(tmp_path: Path) -> None:
    cfg = settings_from_dict({"predicates": {"clearance_cost": True}})
    state = state_of(SCENES["side_by_side"], cfg)
    text = write_problem(state)
    assert text.count("(= (push-cost ") == 8
    domain = domain_for(state)
    assert "(increase (total-cost) (push-cost ?o ?d))" in domain
    parse_both(*write(tmp_path, domain, text), with_pddl_package=False)  # static cost fn: not in `pddl`
    assert domain_for(state_of(SCENES["lone"])) == domain_text()


# ------------------------------------------------------------------------------ Fast Downward
def _fd_driver() -> Path:
    try:
        import up_fast_downward
    except ImportError:
        pytest.skip("up-fast-downward is not installed")
    path = Path(up_fast_downward.__file__).parent / "downward" / "fast-downward.py"
    if not path.is_file():
        pytest.skip("Fast Downward driver not found in up-fast-downward")
    return path


def solve(tmp_path: Path, domain: str, problem: str) -> list[str] | None:
    """Fast Downward's plan (action strings), or None when proven unsolvable."""
    d, p = write(tmp_path, domain, problem)
    plan = tmp_path / "plan"
    res = subprocess.run(
        [sys.executable, str(_fd_driver()), "--plan-file", str(plan), str(d), str(p), "--search", "astar(blind())"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=120,
    )
    if res.returncode == 11:  # proven unsolvable
        return None
    assert res.returncode == 0, res.stdout[-2000:] + res.stderr[-2000:]
    return [ln.strip() for ln in plan.read_text().splitlines() if ln.startswith("(")]


def test_fast_downward_plans(tmp_path: Path) -> None:
    stack = state_of(SCENES["stack"])
    names = {o.segment_index: o.name for o in stack.objects}
    assert solve(tmp_path, domain_text(), write_problem(stack)) == [f"(grasp {names[1]})", f"(grasp {names[0]})"]
    assert solve(tmp_path, domain_text(), write_problem(state_of([]))) == []
    # side by side 1 cm: each blocks the other's grasp; pushing along the long axis
    # frees one, then both can be grasped: 3 actions
    plan = solve(tmp_path, domain_text(), write_problem(state_of(SCENES["side_by_side"])))
    assert plan is not None and len(plan) == 3 and plan[0].startswith("(push ")
    assert plan[0].split()[2].rstrip(")") in ("dir1", "dir2")
    # the IK facts the planner adds take effect
    lone = state_of(SCENES["lone"])
    assert solve(tmp_path, domain_text(), write_problem(lone, extra_facts=[("ik_unfeasible_grasp", "o0")])) is not None
    everything = [("ik_unfeasible_grasp", "o0")] + [
        ("ik_unfeasible_dir", "o0", d) for d in ("dir1", "dir2", "dir3", "dir4")
    ]
    assert solve(tmp_path, domain_text(), write_problem(lone, extra_facts=everything)) is None


def test_fast_downward_push_then_grasp_after_ik_failure(tmp_path: Path) -> None:
    lone = state_of(SCENES["lone"])
    plan = solve(tmp_path, domain_text(), write_problem(lone, extra_facts=[("ik_unfeasible_grasp", "o0")]))
    assert plan is not None and len(plan) == 2 and plan[0].startswith("(push o0") and plan[1] == "(grasp o0)"


@pytest.mark.skipif(os.environ.get("CLEAR_SKIP_SLOW") == "1", reason="slow")
def test_fast_downward_on_a_cluttered_real_frame(tmp_path: Path) -> None:
    from helpers import shared_path

    from clearcli.io.read import read_frame
    from clearcli.predicates.synthetic import segmentation_from_labels

    frame = read_frame(shared_path("mosd/test/test55.pcd"))
    state = compute_state(frame, segmentation_from_labels(frame), Settings())
    graspable = [n for n in state.names() if ("ungraspable", n) not in state.facts]
    plan = solve(tmp_path, domain_text(), write_problem(state, goal_objects=graspable))
    assert plan is not None and sum(a.startswith("(grasp") for a in plan) == len(graspable)
