"""Dense clutter: the ways out of mutual blocking, and the world's own judgment.

* Raised push contacts (`clearcli.geometry.poses.raised_contact_lifts`): which heights
  are allowed, worked out by hand; the hand-made deadlock (`scene.deadlock_row`) that
  the thesis's model cannot clear and the raised pushes can, its whole plan IK-checked
  and validated by unified-planning against the domain it ran on; a scene where a raised
  push must not be used (a narrow tall object would tip).
* The world's reachability (`clearcli.sim.reach`): a grasp it must accept (checked by
  forward kinematics) and ones it must reject.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from clearcli.errors import NoPlanError
from clearcli.geometry.poses import raised_contact_lifts
from clearcli.geometry.settings import GripperSettings, PushSettings
from clearcli.settings import Settings
from clearcli.sim import scene as S

REPO = Path(__file__).resolve().parent.parent
DOMAIN = REPO / "pddl" / "domain.pddl"


def _settings(raised: tuple[float, ...] | None = None) -> Settings:
    s = Settings()
    push = s.push if raised is None else dataclasses.replace(s.push, raised_fingertips_m=raised)
    plan = dataclasses.replace(s.plan, check="whole", replay_check="whole")
    return dataclasses.replace(s, push=push, plan=plan)


# --- raised push contacts ---------------------------------------------------------------


def test_raised_contact_heights_by_hand() -> None:
    push = PushSettings()  # fingertips at 0.01 m; raised at 0.03, 0.05, 0.07; friction 0.4
    closing = 0.045
    # 12 cm along the push, 12 cm tall. Fingertips at 0.07: the band 0.07-0.115 meets
    # 4.5 cm of the face; its middle 0.0925 m x 0.4 = 0.037 < 0.06 (half the length)
    assert raised_contact_lifts(push, closing, 0.12, 0.12) == pytest.approx([0.02, 0.04, 0.06])
    # 6 cm tall: at 0.05 the band 0.05-0.06 meets only 1 cm of the face (< 1.5 cm)
    assert raised_contact_lifts(push, closing, 0.12, 0.06) == pytest.approx([0.02])
    # 3 cm along the push, 14 cm tall: at 0.03 the middle 0.0525 x 0.4 = 0.021 > 0.015
    # (half of 3 cm): the object would tip over its front edge
    assert raised_contact_lifts(push, closing, 0.03, 0.14) == []
    # 8 cm along: 0.03 (0.021 <= 0.04) and 0.05 (0.0725 x 0.4 = 0.029) pass; 0.07
    # (0.0925 x 0.4 = 0.037 <= 0.04) too
    assert raised_contact_lifts(push, closing, 0.08, 0.14) == pytest.approx([0.02, 0.04, 0.06])
    assert raised_contact_lifts(push, closing, 0.07, 0.14) == pytest.approx([0.02, 0.04])
    # switched off
    assert raised_contact_lifts(dataclasses.replace(push, raised_fingertips_m=()), closing, 0.12, 0.12) == []


def _state(scene: S.Scene, settings: Settings, seed: int = 1):  # type: ignore[no-untyped-def]
    from clearcli.pipeline import Pipeline
    from clearcli.sim.camera import render
    from clearcli.sim.episode import truth_segment

    pipeline = Pipeline(settings, segment_fn=truth_segment)
    frame = render(scene, seed=seed)
    return pipeline, pipeline.state(frame, truth_segment(frame))


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_deadlock_row_has_no_plan_in_the_thesis_model_and_one_with_raised_pushes(seed: int, tmp_path: Path) -> None:
    from tests.test_plan_cli import validate_files

    from clearcli.planning.pddl import domain_for, write_plan, write_problem

    world = S.deadlock_row()
    # today's model (no raised contacts): every object stuck
    pipeline, state = _state(world, _settings(raised=()), seed)
    with pytest.raises(NoPlanError, match="blocked by objects that cannot be moved") as err:
        pipeline.plan(state)
    plan0 = err.value.plan  # type: ignore[attr-defined]
    assert plan0.stuck and not plan0.actions
    # ...because the arm hits the neighbour on the pushes along the row
    reasons = " ".join(r for left in plan0.left for r in left.actions.values())
    assert "arm collides" in reasons

    pipeline, state = _state(world, _settings(), seed)
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


def test_raised_push_not_offered_where_the_object_would_tip() -> None:
    from clearcli.geometry.gripper import gripper_model
    from clearcli.geometry.models import TableFrame
    from clearcli.geometry.poses import push_geometry

    settings = _settings()
    # a narrow tall box (3 x 3 x 14 cm): no raised contact in any direction
    narrow = S.make_scene("narrow", [S.Box(0, 0.03, 0.03, 0.14, x_m=0.0, y_m=0.05)])
    # a long box (12 x 5 x 12 cm): raised contacts along its length
    long_box = S.make_scene("long", [S.Box(0, 0.12, 0.05, 0.12, x_m=0.0, y_m=0.05)])
    gripper = gripper_model(settings.gripper)

    def n_options(world: S.Scene) -> dict[str, int]:
        from clearcli.geometry.models import build_from_columns, object_columns
        from clearcli.sim.camera import render
        from clearcli.sim.episode import truth_segment

        frame = render(world, seed=4)
        seg = truth_segment(frame)
        tf = TableFrame.from_plane(seg.table)
        cols = object_columns(frame.points, [o.indices for o in seg.objects], tf, settings.predicates.model_cell_m)
        geom = build_from_columns(cols[0], 0, cell_m=settings.predicates.model_cell_m)
        pushes = push_geometry(geom, gripper, settings.push)
        return {d: 1 + len(p.alternatives) for d, p in pushes.items()}

    # two yaws per direction, nothing raised
    assert n_options(narrow) == {"dir1": 2, "dir2": 2, "dir3": 2, "dir4": 2}
    # along the 12 cm length: 2 yaws x (standard + 3 raised); across the 5 cm width,
    # fingertips at 0.03 only (middle 0.0525 x 0.4 = 0.021 <= 0.025; at 0.05, 0.029)
    long_options = n_options(long_box)
    assert long_options["dir1"] == long_options["dir2"] == 8
    assert long_options["dir3"] == long_options["dir4"] == 4


# --- the world's own reachability ----------------------------------------------------------


def _reach():  # type: ignore[no-untyped-def]
    from clearcli.sim.reach import WorldReach

    # the robot's shoulder 0.55 m before the table's centre, 0.25 m above its top
    T_base_table = np.eye(4)
    T_base_table[:3, 3] = (0.55, 0.0, -0.25)
    return WorldReach(T_base_table, GripperSettings(), PushSettings())


def test_world_accepts_a_grasp_in_front_of_the_arm_and_fk_confirms_it() -> None:
    reach = _reach()
    box = S.Box(0, 0.05, 0.04, 0.08, x_m=0.05, y_m=0.1, yaw_rad=0.3)
    assert reach.why_not(box) == ""
    motion = reach.grasp_motion(box)
    assert motion is not None
    T_base_tcp, q = motion
    assert np.all(q >= reach.kin.lower - 1e-9) and np.all(q <= reach.kin.upper + 1e-9)
    T_fk = reach.kin.fk(q)
    assert np.linalg.norm(T_fk[:3, 3] - T_base_tcp[:3, 3]) < 0.002
    assert np.allclose(T_fk[:3, :3], T_base_tcp[:3, :3], atol=0.02)
    # the grasp point: the box's top centre, half the closing region down, in the base frame
    expected = reach.T_base_table @ np.array([0.05, 0.1, 0.08 - 0.0225, 1.0])
    assert np.allclose(T_base_tcp[:3, 3], expected[:3], atol=1e-9)
    # the gripper points down and closes across the 4 cm side (yaw 0.3 + 90 deg)
    assert T_base_tcp[2, 2] == pytest.approx(-1.0)
    closing = T_base_tcp[:2, 0]
    assert abs(float(closing @ np.array([-math.sin(0.3), math.cos(0.3)]))) == pytest.approx(1.0, abs=1e-9)


def test_world_rejects_what_the_arm_cannot_reach_or_the_gripper_cannot_hold() -> None:
    reach = _reach()
    # 1.0 m from the shoulder on the table: beyond the tool plate's 0.915 m
    far = S.Box(0, 0.05, 0.05, 0.08, x_m=0.45, y_m=0.0)
    assert reach.why_not(far) == "no arm motion reaches a top-down grasp of it"
    assert reach.grasp_motion(far) is None
    # 9 x 9 cm: wider than the 7 cm opening whichever way it closes
    wide = S.Box(0, 0.09, 0.09, 0.08, x_m=0.0, y_m=0.0)
    assert "cannot hold" in reach.why_not(wide)
    # and on a scene: one reachable, one not
    scene = S.make_scene("two", [S.Box(0, 0.05, 0.05, 0.08, x_m=0.0, y_m=0.0), far])
    assert reach.reachable(scene, 0) and not reach.reachable(scene, 1)


# --- off-centre grasps -----------------------------------------------------------------------


def _block_grasp(world: S.Scene, fraction: float, seed: int) -> set[tuple[str, str]]:
    s = Settings()
    s = dataclasses.replace(s, predicates=dataclasses.replace(s.predicates, grasp_offcentre_fraction=fraction))
    _, state = _state(world, s, seed)
    # the box under test: the lowest of those longer than 10 cm
    long_name = min((o for o in state.objects if o.extents_m[0] > 0.10), key=lambda o: o.height_m).name
    return {(f[1], f[2]) for f in state.facts if f[0] == "block_grasp" and f[2] == long_name}


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_offcentre_grasp_frees_a_long_box_with_a_short_neighbour_at_one_end(seed: int) -> None:
    # a 14 x 5 x 8 cm box along the table's x; a 4 cm can touching its side near one end
    box = S.Box(0, 0.14, 0.05, 0.08, x_m=0.0, y_m=0.05)
    can = S.Cylinder(1, 0.02, 0.10, x_m=0.025, y_m=0.05 - 0.025 - 0.0205)
    world = S.make_scene("long_and_can", [box, can])
    assert _block_grasp(world, 0.0, seed), "the centred grasp's finger must hit the can"
    # 0.3 x 14 cm = 4.2 cm towards the free end: the finger clears the can
    assert _block_grasp(world, 0.3, seed) == set()


@pytest.mark.parametrize("seed", [1, 2])
def test_offcentre_grasp_does_not_free_a_box_flanked_along_its_whole_side(seed: int) -> None:
    # the same box with a taller 14 cm box touching its whole far side: no grasp along
    # it is free
    box = S.Box(0, 0.14, 0.05, 0.08, x_m=0.0, y_m=0.05)
    other = S.Box(1, 0.14, 0.06, 0.10, x_m=0.0, y_m=0.05 + 0.055)
    world = S.make_scene("flanked", [box, other])
    assert _block_grasp(world, 0.3, seed)


def test_no_offcentre_alternatives_on_a_short_object() -> None:
    from clearcli.geometry.gripper import gripper_model
    from clearcli.geometry.models import TableFrame, build_from_columns, object_columns
    from clearcli.geometry.poses import grasp_geometry
    from clearcli.sim.camera import render
    from clearcli.sim.episode import truth_segment

    settings = Settings()
    gripper = gripper_model(settings.gripper)
    counts = []
    for size_x in (0.05, 0.14):
        frame = render(S.make_scene("one", [S.Box(0, size_x, 0.05, 0.08, x_m=0.0, y_m=0.05)]), seed=2)
        seg = truth_segment(frame)
        tf = TableFrame.from_plane(seg.table)
        cols = object_columns(frame.points, [o.indices for o in seg.objects], tf, settings.predicates.model_cell_m)
        geom = build_from_columns(cols[0], 0, cell_m=settings.predicates.model_cell_m)
        grasp = grasp_geometry(geom, gripper, settings.push, 30.0, 0.3)
        counts.append(len(grasp.alternatives))
        if size_x > 0.1:
            # the two off-centre grasps: 0.3 x 14 cm = 4.2 cm either way along the length
            shifts = sorted(float(np.linalg.norm(a.T_grasp[:3, 3] - grasp.T_grasp[:3, 3])) for a in grasp.alternatives)
            assert shifts == pytest.approx([0.042, 0.042], abs=0.004)
    # 5 x 5 cm: the quarter-turned grasp only (5 cm: 1.5 cm max < 5 mm past the finger's
    # half width); 14 x 5 cm: no quarter turn (14 cm > the opening), two off-centre
    assert counts == [1, 2]


# --- a scene that truly cannot be cleared --------------------------------------------------------


def test_hemmed_in_scene_ends_with_no_plan_and_the_reason_without_spinning() -> None:
    """A 9 cm box hemmed in on all four sides by boxes too wide for the gripper too (the
    middle one the tallest: lower, the front box would hide part of it from the camera)."""
    from clearcli.pipeline import Pipeline
    from clearcli.replay.session import ReplayOptions, Session
    from clearcli.sim.episode import Episode, truth_segment

    centre = S.Box(0, 0.09, 0.09, 0.12, x_m=0.0, y_m=0.05)
    ring = [
        S.Box(1, 0.09, 0.09, 0.06, x_m=0.0915, y_m=0.05),
        S.Box(2, 0.09, 0.09, 0.06, x_m=-0.0915, y_m=0.05),
        S.Box(3, 0.09, 0.09, 0.06, x_m=0.0, y_m=0.05 + 0.0915),
        S.Box(4, 0.09, 0.09, 0.06, x_m=0.0, y_m=0.05 - 0.0915),
    ]
    world = S.make_scene("hemmed_in", [centre, *ring])
    settings = _settings()
    pipeline, state = _state(world, settings)
    with pytest.raises(NoPlanError, match="too wide") as err:
        pipeline.plan(state)
    plan = err.value.plan  # type: ignore[attr-defined]
    # every object seen is left with its reason: too wide (the box behind the tall one
    # may be hidden from the camera altogether)
    assert not plan.actions and len(state.objects) >= 4
    assert len(plan.left) == len(state.objects) and {left.reason for left in plan.left} == {"ungraspable"}
    assert plan.replans <= plan.max_backtracks == settings.plan.max_backtracks
    # the closed loop stops at the first frame, "no plan", with the reason; the world
    # agrees that nothing there fits the gripper, so the session counts as cleared
    episode = Episode(world, Session(Pipeline(settings, segment_fn=truth_segment), ReplayOptions()), seed=0, max_actions=40)
    frames = sum(1 for _ in episode)
    result = episode.result
    assert result is not None and frames == 1 and result.end == "no_plan" and result.actions == 0
    assert "too wide" in result.reason
    assert set(result.truly_ungraspable) == {0, 1, 2, 3, 4} and result.cleared_truly
