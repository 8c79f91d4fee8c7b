"""Tests of clearcli/planning/backtrack.py."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import plan_scenes as ps
from helpers.clearing import _settings as _world_settings
from helpers.clearing import _state
from helpers.planning import FakeIK

from clearcli.errors import NoPlanError
from clearcli.planning.backtrack import Search, make_plan
from clearcli.planning.feasibility import IKActionChecker, Infeasible
from clearcli.planning.types import Action, CheckedAction, Plan
from clearcli.predicates.state import DIRECTIONS, Fact
from clearcli.settings import Settings
from clearcli.settings.geometry import GripperSettings, PushSettings
from clearcli.sim import scene as S


def _settings(**plan: object) -> Settings:
    s = Settings()
    return dataclasses.replace(s, plan=dataclasses.replace(s.plan, **plan))


def replay(state_facts: frozenset[Fact], names: tuple[str, ...], actions: tuple[Action, ...]) -> set[str]:
    """An independent replay of the thesis's action semantics; returns removed objects."""
    facts = set(state_facts)
    removed: set[str] = set()
    for a in actions:
        o = a.obj
        if a.kind == "grasp":
            assert ("ungraspable", o) not in facts and ("ik_unfeasible_grasp", o) not in facts
            assert not any(f[0] in ("on", "block_grasp") and f[2] == o for f in facts), a
            removed.add(o)
            facts = {f for f in facts if not (f[0] in ("on", "block_grasp", "block_dir") and f[1] == o)}
        else:
            assert ("push_off_table", o, a.direction) not in facts
            assert ("ik_unfeasible_dir", o, a.direction) not in facts
            assert not any(f[0] == "block_dir" and f[2] == o and f[3] == a.direction for f in facts), a
            assert not any(f[0] == "on" and o in f[1:] for f in facts), a
            facts = {
                f
                for f in facts
                if not (f[0] in ("block_dir", "block_grasp") and o in f[1:3]) and f != ("ik_unfeasible_grasp", o)
            }
    return removed


def check_plan(state, plan: Plan) -> None:  # type: ignore[no-untyped-def]
    """Every plan: validated by unified-planning on the lifted model and replayed here;
    it removes every goal object."""
    facts = frozenset(state.facts) | plan.ik_facts
    domain, problem, _which = ps.lifted_pddl(state.names(), facts, plan.goal, state.push_costs, state)
    assert ps.validate(domain, problem, plan.actions)
    assert replay(facts, state.names(), plan.actions) >= set(plan.goal)


def test_figure_3_1_backtracking_sequence() -> None:
    state = ps.figure_3_1()
    # No reach pre-check: walk the thesis's sequence through the real IK check.
    with pytest.raises(NoPlanError) as info:
        make_plan(state, _settings(reach_precheck=False), ps.T_BASE_CAMERA)
    plan = info.value.plan  # type: ignore[attr-defined]
    steps = plan.steps
    # first plan: grasp the cup o2 (it blocks everything), then the boxes (thesis: cost 4)
    assert steps[0].plan[0] == Action("grasp", "o2") and steps[0].cost == 4
    assert {a.pddl() for a in steps[0].plan[1:]} == {"(push o0 dir1)", "(grasp o0)", "(grasp o1)"}
    # then: push o2 in some direction and grasp it (cost 5), each push infeasible in turn
    pushed = []
    for s in steps[1:]:
        assert s.cost == 5 and s.plan[0].kind == "push" and s.plan[0].obj == "o2"
        assert Action("grasp", "o2") in s.plan[1:]  # equally short orders tie
        assert s.failed_step == 0 and s.learnt == (s.plan[0].ik_fact(),)
        pushed.append(s.plan[0].direction)
    assert sorted(pushed) == list(DIRECTIONS)
    assert all(not s.feasible and "reach" in s.reason for s in steps)
    assert plan.unreachable == ("o2",)
    assert set(plan.stuck) == {"o0", "o1"}
    assert plan.ik_facts == frozenset(
        {("ik_unfeasible_grasp", "o2")} | {("ik_unfeasible_dir", "o2", d) for d in DIRECTIONS}
    )
    assert "o2" in str(info.value) and "reach" in str(info.value)
    # each intermediate plan is valid for the state it was made for
    facts = set(state.facts)
    for s in steps:
        domain, problem, _ = ps.lifted_pddl(state.names(), frozenset(facts), ["o0", "o1", "o2"], None, state)
        assert ps.validate(domain, problem, s.plan)
        facts.add(s.plan[0].ik_fact())


def test_figure_3_1_with_reach_precheck_needs_no_replans() -> None:
    with pytest.raises(NoPlanError) as info:
        make_plan(ps.figure_3_1(), Settings(), ps.T_BASE_CAMERA)
    plan = info.value.plan  # type: ignore[attr-defined]
    assert plan.unreachable == ("o2",) and plan.replans == 0


def test_far_object_dropped_rest_planned() -> None:
    state = ps.clutter(6, far=True)  # o6 is 2 m away and blocks nothing
    plan = make_plan(state, Settings(), ps.T_BASE_CAMERA)
    assert plan.unreachable == ("o6",)
    assert set(plan.goal) == {f"o{i}" for i in range(6)}
    assert plan.cost == len(plan.actions) == 6 and plan.optimal
    # the stack o2-on-o1 and the grasp-block chain o(i+1) -> o(i) fix the order
    order = [a.obj for a in plan.actions]
    assert order.index("o2") < order.index("o1")
    assert all(order.index(f"o{i + 1}") < order.index(f"o{i}") for i in range(5))
    first = plan.first
    assert first is not None and first.action == plan.actions[0]
    assert len(first.joint_solutions) == len(first.T_base_gripper) == 3
    # FK of each joint solution is the pose it was solved for
    from clearcli.robot.wam_kinematics import WamKinematics

    kin = WamKinematics()
    for q, T in zip(first.joint_solutions, first.T_base_gripper):
        np.testing.assert_allclose(kin.fk(q)[:3, 3], T[:3, 3], atol=0.0011)
    check_plan(state, plan)


def test_nothing_reachable_is_no_plan() -> None:
    state = ps.scene({"o0": ps.Box(2.0, 0.0), "o1": ps.Box(2.2, 0.3)})
    with pytest.raises(NoPlanError, match="reach"):
        make_plan(state, Settings(), ps.T_BASE_CAMERA)


def test_empty_table_is_an_empty_plan() -> None:
    plan = make_plan(ps.scene({}), Settings(), ps.T_BASE_CAMERA)
    assert plan.actions == () and plan.cost == 0 and plan.first is None


def test_grasp_infeasible_push_then_grasp() -> None:
    # The thesis: a push makes an IK-infeasible grasp possible again.
    state = ps.dummy_state(["o0", "o1"], frozenset())
    ik = FakeIK({Action("grasp", "o0"), Action("grasp", "o1")})
    plan = Search(state, ik, _settings().plan).run()
    assert plan.cost == 4 and plan.actions[0].kind == "push"
    assert ("ik_unfeasible_grasp", "o0") in plan.ik_facts or ("ik_unfeasible_grasp", "o1") in plan.ik_facts
    check_plan(state, plan)


def test_unreachable_blocker_leaves_others_stuck_but_plans_the_rest() -> None:
    # o0 is out of reach and blocks grasping/pushing o1, and grasping o2 (o2 can be pushed).
    facts = frozenset(
        {("block_grasp", "o0", "o1"), ("block_grasp", "o0", "o2")} | {("block_dir", "o0", "o1", d) for d in DIRECTIONS}
    )
    state = ps.dummy_state(["o0", "o1", "o2"], facts)
    everything_o0 = {Action("grasp", "o0")} | {Action("push", "o0", d) for d in DIRECTIONS}
    plan = Search(state, FakeIK(everything_o0), _settings().plan).run()
    assert plan.unreachable == ("o0",) and plan.stuck == ("o1",)
    assert plan.goal == ("o2",) and plan.cost == 2 and plan.replans == 6
    assert plan.actions[0].pddl().startswith("(push o2") and plan.actions[1].pddl() == "(grasp o2)"
    check_plan(state, plan)


def test_ungraspable_not_in_goal_but_pushed_out_of_the_way() -> None:
    facts = frozenset({("ungraspable", "o0"), ("block_grasp", "o0", "o1")})
    state = ps.dummy_state(["o0", "o1"], facts)
    plan = Search(state, FakeIK(set()), _settings().plan).run()
    assert plan.ungraspable == ("o0",) and plan.goal == ("o1",)
    assert plan.cost == 2 and plan.actions[0].kind == "push"
    check_plan(state, plan)


@pytest.mark.parametrize("seed", [0, 1])
def test_random_states_with_random_ik_failures(seed: int) -> None:
    from clearcli.planning.compile import random_facts

    rng = np.random.default_rng(seed)
    names = [f"o{i}" for i in range(6)]
    facts = random_facts(6, seed + 10, density=1.5)
    state = ps.dummy_state(names, facts)
    all_actions = [Action("grasp", o) for o in names] + [Action("push", o, d) for o in names for d in DIRECTIONS]
    infeasible = {a for a in all_actions if rng.random() < 0.3}
    ik = FakeIK(infeasible)
    try:
        plan = Search(state, ik, _settings().plan, mode="first").run()
    except NoPlanError:
        return
    assert plan.actions[0] not in infeasible
    # only first actions are checked, one check per plan
    assert len(ik.calls) == plan.replans
    check_plan(state, plan)
    # the whole-plan check: no action of the plan is infeasible
    whole = Search(state, FakeIK(infeasible), _settings().plan).run()
    for k, a in enumerate(whole.actions):  # infeasible as recorded: only after a push of it
        assert a not in infeasible or any(p.obj == a.obj for p in whole.actions[:k]), (k, a)
    assert all(c is not None for c in whole.checked) and len(whole.checked) == len(whole.actions)
    check_plan(state, whole)


def test_ik_checker_on_scene_grasp_and_push() -> None:
    state = ps.clutter(3)
    from clearcli.robot.collision import make_obstacles
    from clearcli.robot.wam_kinematics import WamKinematics

    kin = WamKinematics()
    checker = IKActionChecker(state, ps.T_BASE_CAMERA, kin, make_obstacles(state, ps.T_BASE_CAMERA))
    for action in (Action("grasp", "o0"), Action("push", "o1", "dir3")):
        checked = checker(action)
        assert isinstance(checked, CheckedAction), checked
        n = len(checked.T_base_gripper)
        assert n == len(checked.joint_solutions) and n >= 3
        for q in checked.joint_solutions:
            a, b, r = kin.capsules(q)
            # arm above the table (z = -0.346 in the base frame) by its radius
            assert np.all(np.minimum(a[:, 2], b[:, 2]) - r > -0.346)
    # an arm-collision: a tall object standing between the robot and o0 blocks the arm
    tall = ps.scene({"o0": ps.Box(0.75, 0.0), "o1": ps.Box(0.40, 0.0, (0.30, 0.30, 0.6))})
    checker = IKActionChecker(tall, ps.T_BASE_CAMERA, kin, make_obstacles(tall, ps.T_BASE_CAMERA))
    failed = checker(Action("grasp", "o0"))
    assert isinstance(failed, Infeasible) and "collides with o1" in failed.reason
    assert failed.kind == "collision" and failed.colliders == ("o1",)
    assert failed.facts(Action("grasp", "o0")) == (("block_grasp", "o1", "o0"),)


def _clear(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "clearcli.cli", *args], capture_output=True, text=True, timeout=300)


def test_cli_plan_on_a_real_frame() -> None:
    import json

    from helpers import shared_path

    pcd = shared_path("mosd/test/test57.pcd")
    res = _clear("plan", str(pcd), "--json")
    assert res.returncode == 10, res.stderr  # partial: test57 has boxes too wide to grasp
    doc = json.loads(res.stdout)
    assert doc["schema"] == "clear.plan" and doc["version"] == 5
    assert doc["cost"] == len(doc["actions"]) >= 1
    assert isinstance(doc["optimal"], bool) and doc["camera_pose_source"] == "default from table"
    first = doc["first_action"]
    assert first["action"] == doc["actions"][0]
    assert len(first["joints_rad"]) == len(first["T_base_gripper"]) and len(first["joints_rad"][0]) == 7
    # a camera pose that is not one: exit 3 with the reason
    bad = _clear("plan", str(pcd), "--camera-pose", "1 2 3")
    assert bad.returncode == 3 and "camera pose" in bad.stderr


@pytest.mark.parametrize("x, lookahead_ok", [(0.22, False), (0.30, True)])
def test_push_lookahead_rejects_a_push_that_leaves_the_object_out_of_reach(x: float, lookahead_ok: bool) -> None:
    """A 10 cm box pushed 10 cm towards the robot (dir2, -x): from 0.32 m before the
    shoulder's axis it ends at 0.22 m, where the WAM folded past its limits has no
    top-down grasp; from 0.40 m it ends at 0.30 m and stays graspable. The push itself
    has arm motions either way."""
    from clearcli.robot.collision import make_obstacles
    from clearcli.robot.wam_kinematics import WamKinematics

    state = ps.scene({"o0": ps.Box(x, 0.0, size=(0.10, 0.05, 0.08))})
    kin = WamKinematics()
    obstacles = make_obstacles(state, ps.T_BASE_CAMERA)
    push = Action("push", "o0", "dir2")
    plain = IKActionChecker(state, ps.T_BASE_CAMERA, kin, obstacles)
    assert isinstance(plain(push), CheckedAction)
    assert isinstance(plain(Action("grasp", "o0")), CheckedAction)  # graspable where it stands
    ahead = IKActionChecker(state, ps.T_BASE_CAMERA, kin, obstacles, push_lookahead=True)
    checked = ahead(push)
    assert isinstance(checked, CheckedAction) == lookahead_ok
    if not lookahead_ok:
        assert isinstance(checked, Infeasible) and checked.kind == "lookahead"
        assert checked.reason.startswith("the push leaves o0 where it cannot be grasped (no IK solution")


def _plan_any(state, check: str = "whole") -> Plan:  # type: ignore[no-untyped-def]
    try:
        return make_plan(state, Settings(), ps.T_BASE_CAMERA, check=check)
    except NoPlanError as err:
        return err.plan  # type: ignore[attr-defined]


def _assert_checked_by_fk(plan: Plan) -> None:
    from clearcli.robot.wam_kinematics import WamKinematics

    kin = WamKinematics()
    assert len(plan.checked) == len(plan.actions)
    for c in plan.checked:
        assert c is not None
        for q, T in zip(c.joint_solutions, c.T_base_gripper):
            assert np.all(q >= kin.lower - 1e-9) and np.all(q <= kin.upper + 1e-9)
            np.testing.assert_allclose(kin.fk(q)[:3, 3], T[:3, 3], atol=0.0011)


def test_later_action_without_ik_found_by_whole_check_only() -> None:
    """o0 blocks grasping o1, so o0 goes first and its grasp is feasible; o1 stands
    0.22 m from the shoulder's axis, within reach but where no top-down pose has IK.
    --first-only accepts the plan; the whole check finds the second action infeasible,
    relearns through every push of o1 (none has an arm motion either) and ends."""
    state = ps.scene({"o0": ps.Box(0.45, 0.0), "o1": ps.Box(0.12, 0.0)}, {("block_grasp", "o0", "o1")})
    first = _plan_any(state, "first")
    assert [a.pddl() for a in first.actions] == ["(grasp o0)", "(grasp o1)"] and first.status == "complete"
    assert first.checked[0] is not None and first.checked[1] is None
    whole = _plan_any(state)
    assert [a.pddl() for a in whole.actions] == ["(grasp o0)"] and whole.status == "partial"
    (left,) = whole.left
    assert left.name == "o1" and left.reason == "unreachable"
    assert "no IK solution" in left.actions["grasp"] and set(left.actions) == {
        "grasp",
        "push dir1",
        "push dir2",
        "push dir3",
        "push dir4",
    }
    failed = [s for s in whole.steps if not s.feasible]
    assert failed[0].failed_step == 1 and failed[0].learnt == (("ik_unfeasible_grasp", "o1"),)
    assert len(whole.steps) == 6 and whole.steps[-1].feasible  # relearnt 5 times, then ended
    _assert_checked_by_fk(whole)
    check_plan(state, whole)


def _walled_scene(wall_movable: bool):  # type: ignore[no-untyped-def]
    # o2: a 0.6 m tall, 0.20 m wide box between the robot and o1, too wide to grasp
    boxes = {"o0": ps.Box(0.45, -0.30), "o1": ps.Box(0.65, 0.0), "o2": ps.Box(0.35, 0.0, (0.20, 0.20, 0.6))}
    # o1 stands in o2's way along dir1 (+x), o0 along dir4 (-y)
    facts = {
        ("block_grasp", "o0", "o1"),
        ("ungraspable", "o2"),
        ("block_dir", "o1", "o2", "dir1"),
        ("block_dir", "o0", "o2", "dir4"),
    }
    if not wall_movable:
        facts |= {("push_off_table", "o2", d) for d in DIRECTIONS}
    return ps.scene(boxes, facts)


def test_arm_collision_learnt_as_blocking_fact() -> None:
    """The arm reaching o1 hits the wall o2 (no gripper pose touches it, so no
    block_grasp fact says so). The whole check learns block_grasp/block_dir o2 o1: o1 is
    stuck behind o2 when o2 cannot move; --first-only does not notice."""
    state = _walled_scene(wall_movable=False)
    first = _plan_any(state, "first")
    assert [a.pddl() for a in first.actions] == ["(grasp o0)", "(grasp o1)"]
    whole = _plan_any(state)
    assert [a.pddl() for a in whole.actions] == ["(grasp o0)"]
    reasons = {x.name: x for x in whole.left}
    assert reasons["o1"].reason == "stuck" and reasons["o1"].blockers == ("o2",)
    assert "arm collides with o2" in reasons["o1"].actions["grasp"]
    assert ("block_grasp", "o2", "o1") in whole.ik_facts
    assert {("block_dir", "o2", "o1", d) for d in DIRECTIONS} <= whole.ik_facts
    check_plan(state, whole)


def test_relearning_loop_ends_with_a_fixed_prefix() -> None:
    """When the wall can be pushed, the plan pushes it out of the arm's way. The first
    push leaves it where it still stands in the arm's way to o1: that failure holds
    only in the scene the push leaves, so the checked actions before it are fixed and
    the rest is planned from there (learnt_later). The loop ends with every action
    checked, and the plan solves the problem written from the recorded scene."""
    state = _walled_scene(wall_movable=True)
    plan = _plan_any(state)
    kinds = [(a.kind, a.obj) for a in plan.actions]
    assert kinds[0] == ("grasp", "o0") and kinds[-1] == ("grasp", "o1")
    assert all(k == ("push", "o2") for k in kinds[1:-1]) and len(kinds) >= 3
    assert plan.status == "partial" and [x.name for x in plan.left] == ["o2"]  # o2 too wide
    assert plan.learnt_later and any(s.prefix > 0 for s in plan.steps)
    assert not plan.optimal  # a fixed prefix: optimal only for the rest
    assert plan.replans <= Settings().plan.max_backtracks
    _assert_checked_by_fk(plan)
    check_plan(state, plan)


def _many_objects(n: int) -> SymbolicState:  # type: ignore[name-defined]  # noqa: F821
    from clearcli.planning.compile import random_facts

    return ps.dummy_state([f"o{i}" for i in range(n)], random_facts(n, 3, density=0.5))


def test_deadline_returns_the_checked_plan_found_so_far() -> None:
    """80 objects: more goal objects than the optimal search takes, so LAMA runs; the
    whole planning's time limit ends it, and its best plan, every action checked, is the
    answer, marked deadline and not optimal."""
    state = _many_objects(80)
    plan = Search(state, FakeIK(set()), _settings(time_limit_s=1.5, anytime_time_s=30.0).plan).run()
    assert plan.deadline and not plan.optimal and plan.search == "seq-sat-lama-2011"
    assert plan.goal and all(c is not None for c in plan.checked)
    assert plan.timings_s["total_s"] < 1.5 + 1.0  # the limit bounds the whole planning
    # (the independent replay: unified-planning takes long to ground 80 objects)
    assert replay(frozenset(state.facts) | plan.ik_facts, state.names(), plan.actions) >= set(plan.goal)


def test_deadline_without_a_checked_plan_is_a_planner_error() -> None:
    from clearcli.errors import PlannerError

    # (the least [plan] time_limit_s allows)
    with pytest.raises(PlannerError, match="time limit of 0.1 s"):
        Search(_many_objects(120), FakeIK(set()), _settings(time_limit_s=0.1).plan).run()


@pytest.mark.parametrize("replay_check", ["first", "whole"])
def test_replay_and_simulate_check_what_the_setting_says(replay_check: str) -> None:
    """The pipeline `replay` and `simulate` run passes [plan] replay_check (default
    "first": the robot replans after every action) to the planner."""
    from clearcli.pipeline import Pipeline

    s = _settings(replay_check=replay_check)
    seen: list[str] = []

    def spy(state, settings, T_base_camera=None, check="whole"):  # type: ignore[no-untyped-def]
        seen.append(check)
        return make_plan(state, settings, ps.T_BASE_CAMERA, check=check)

    state = ps.scene({"o0": ps.Box(0.45, 0.0), "o1": ps.Box(0.12, 0.0)}, {("block_grasp", "o0", "o1")})
    plan = Pipeline(s, plan_fn=spy).plan(state)
    assert seen == [replay_check] and plan.check == replay_check
    assert Settings().plan.replay_check == "first" and Settings().plan.check == "whole"
    # first: the unreachable second grasp goes unnoticed; whole: it is found
    assert len(plan.actions) == (2 if replay_check == "first" else 1)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_deadlock_row_has_no_plan_in_the_thesis_model_and_one_with_raised_pushes(seed: int, tmp_path: Path) -> None:
    from helpers.validate import validate_files

    from clearcli.planning.pddl import domain_for, write_plan, write_problem

    world = S.deadlock_row()
    # today's model (no raised contacts): every object stuck
    pipeline, state = _state(world, _world_settings(raised=()), seed)
    with pytest.raises(NoPlanError, match="blocked by objects that cannot be moved") as err:
        pipeline.plan(state)
    plan0 = err.value.plan  # type: ignore[attr-defined]
    assert plan0.stuck and not plan0.actions
    # ...because the arm hits the neighbour on the pushes along the row
    reasons = " ".join(r for left in plan0.left for r in left.actions.values())
    assert "arm collides" in reasons

    pipeline, state = _state(world, _world_settings(), seed)
    plan = pipeline.plan(state)
    assert plan.check == "whole" and plan.stuck == () and plan.unreachable == ()
    # the two graspable boxes are taken (the 9 cm one is too wide: out of the goal)
    wide = state.objects[int(np.argmax([o.grasp_width_m for o in state.objects]))].name
    assert plan.ungraspable == (wide,)
    assert sorted(plan.goal) == sorted(o.name for o in state.objects if o.name != wide)
    assert any(a.kind == "push" for a in plan.actions)
    # every action has joint solutions, and some push among them runs raised: its
    # start pose is above the standard fingertip height
    assert all(c is not None for c in plan.checked)
    standard_tcp_z = PushSettings().fingertips_above_table_m + GripperSettings().closing_region_height_m / 2
    raised_used = False
    for action, checked in zip(plan.actions, plan.checked):
        if action.kind == "push":
            T_camera_start = np.linalg.inv(plan.T_base_camera) @ checked.T_base_gripper[1]
            height = float(state.table.height_of(T_camera_start[:3, 3][None])[0])
            raised_used |= height > standard_tcp_z + 0.015
    assert raised_used
    # the plan is valid in the domain it ran on, with the facts learnt while planning
    domain = tmp_path / "domain.pddl"
    problem = tmp_path / "problem.pddl"
    out = tmp_path / "plan.txt"
    domain.write_text(domain_for(state))
    problem.write_text(write_problem(state, goal_objects=plan.goal, extra_facts=plan.ik_facts))
    out.write_text(write_plan(plan.actions, plan.cost, unit_cost=not state.push_costs))
    assert validate_files(domain, problem, out)
