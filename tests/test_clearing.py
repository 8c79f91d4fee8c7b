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
from clearcli.settings.geometry import GripperSettings, PushSettings
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
    from clearcli.sim.truth import truth_segment

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
        from clearcli.sim.truth import truth_segment

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
    from clearcli.sim.truth import truth_segment

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
    from clearcli.sim.episode import Episode
    from clearcli.sim.truth import truth_segment

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
    # the closed loop may push each of them to see whether it is two objects merged (at
    # most once along each of its two axes: [plan] probe_max_width_m), then stops with
    # "no plan" and the reason, well before the action budget; the world agrees that
    # nothing there fits the gripper, so the session counts as cleared
    episode = Episode(world, Session(Pipeline(settings, segment_fn=truth_segment), ReplayOptions()), seed=0, max_actions=40)
    frames = sum(1 for _ in episode)
    result = episode.result
    assert result is not None and result.end == "no_plan" and "too wide" in result.reason
    assert frames == result.actions + 1 and result.actions < 40 // 2
    probes = [r["plan"]["probe"] for r in episode.reports if r["plan"] and r["plan"]["probe"] is not None]
    assert probes and max(probes.count(p) for p in set(probes)) <= 2  # per track
    # a grasp the world refuses (the box behind, half hidden, looks narrower than it is)
    # is tried at most [plan] max_failed_grasps times in a row
    run = longest = 0
    previous = ""
    for step in result.steps:
        run = run + 1 if step.action.startswith("(grasp") and step.action == previous else 1
        previous = step.action
        if step.action.startswith("(grasp"):
            longest = max(longest, run)
    assert longest <= settings.plan.max_failed_grasps
    # without probing: no action at all
    no_probe = dataclasses.replace(settings, plan=dataclasses.replace(settings.plan, probe_max_width_m=0.0))
    episode = Episode(world, Session(Pipeline(no_probe, segment_fn=truth_segment), ReplayOptions()), seed=0, max_actions=40)
    assert sum(1 for _ in episode) == 1 and episode.result is not None and episode.result.actions == 0
    assert set(result.truly_ungraspable) == {0, 1, 2, 3, 4} and result.cleared_truly


# --- the world's contacts and the gripper's opening ------------------------------------------------


def test_push_contacts_by_hand() -> None:
    from clearcli.sim.physics import push_contacts

    # two 4 cm boxes side by side along x (faces at x = -0.04, 0, 0.04), 6 cm long along y
    a = S.Box(0, 0.04, 0.06, 0.08, x_m=-0.02, y_m=0.0)
    b = S.Box(1, 0.04, 0.06, 0.08, x_m=0.02, y_m=0.0)
    c = S.Box(2, 0.04, 0.04, 0.08, x_m=0.0, y_m=0.2)  # far ahead
    scene = S.make_scene("pair", [a, b, c])
    up = np.array([0.0, 1.0])
    # fingers 1.5 cm to either side of x = -0.02, 3 cm behind the rear faces (y = -0.03)
    assert push_contacts(scene, np.array([-0.02, -0.06]), up, 0.015, 0.1) == [0]
    assert push_contacts(scene, np.array([0.02, -0.06]), up, 0.015, 0.1) == [1]
    # centred on the seam: both, the one overlapped more (equal here: the first) first
    assert sorted(push_contacts(scene, np.array([0.0, -0.06]), up, 0.015, 0.1)) == [0, 1]
    # 4 mm over the seam onto b: b alone (a overlapped by less than 5 mm)
    assert push_contacts(scene, np.array([0.019, -0.06]), up, 0.015, 0.1) == [1]
    # beside both: nothing; and c only within reach
    assert push_contacts(scene, np.array([0.2, -0.06]), up, 0.015, 0.1) == []
    assert push_contacts(scene, np.array([0.0, 0.1]), up, 0.015, 0.2) == [2]
    assert push_contacts(scene, np.array([0.0, 0.1]), up, 0.015, 0.05) == []


def test_grasp_contacts_and_opening_by_hand() -> None:
    from clearcli.geometry.gripper import gripper_model
    from clearcli.predicates.relations import grasp_opening_m
    from clearcli.sim.physics import grasp_contacts

    g = gripper_model(GripperSettings())  # opens to 7 cm, closes to 3 cm
    assert grasp_opening_m(0.04, g, 0.01) == pytest.approx(0.06)  # 4 + 2 x 1 cm
    assert grasp_opening_m(0.041, g, 0.01) == pytest.approx(0.065)  # rounded up to 5 mm
    assert grasp_opening_m(0.055, g, 0.01) == pytest.approx(0.07)  # at most the opening
    assert grasp_opening_m(0.005, g, 0.01) == pytest.approx(0.03)  # at least the closing width
    assert grasp_opening_m(0.04, g, 0.0) == pytest.approx(0.07)  # 0: fully
    # a 4 cm box and a neighbour whose face is at x = 0.040 (2 cm from the box)
    box = S.Box(0, 0.04, 0.04, 0.08, x_m=0.0, y_m=0.0)
    near = S.Box(1, 0.04, 0.04, 0.08, x_m=0.060, y_m=0.0)
    scene = S.make_scene("near", [box, near])
    tcp = np.array([0.0, 0.0, 0.0575])
    tips = 0.0575 - 0.0225
    x = np.array([1.0, 0.0, 0.0])
    # fully open, a finger spans x = 0.035-0.045: it comes down on the neighbour (by
    # 5 mm, more than the 3 mm a finger nudges aside)
    assert grasp_contacts(scene, tcp, x, 0.07, 0.03, tips) == [0, 1]
    # opened to 6 cm (finger at 0.030-0.040): only the box
    assert grasp_contacts(scene, tcp, x, 0.06, 0.03, tips) == [0]
    # a neighbour 2 mm into the finger's path is nudged aside (face at 0.043)
    nudged = S.make_scene("nudged", [box, S.Box(1, 0.04, 0.04, 0.08, x_m=0.063, y_m=0.0)])
    assert grasp_contacts(nudged, tcp, x, 0.07, 0.03, tips) == [0]
    # a neighbour reaching in between the fingers (face at 0.03) is squeezed too
    inside = S.make_scene("inside", [box, S.Box(1, 0.04, 0.04, 0.08, x_m=0.05, y_m=0.0)])
    assert grasp_contacts(inside, tcp, x, 0.07, 0.03, tips) == [0, 1]
    # closing along y: the neighbour is beside the fingers, not under or between them
    assert grasp_contacts(scene, tcp, np.array([0.0, 1.0, 0.0]), 0.07, 0.03, tips) == [0]
    # a neighbour lower than the fingertips is not touched
    low = S.make_scene("low", [box, S.Box(1, 0.04, 0.04, 0.03, x_m=0.05, y_m=0.0)])
    assert grasp_contacts(low, tcp, x, 0.07, 0.03, tips) == [0]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_block_grasp_follows_the_opening(seed: int) -> None:
    """A 3 cm box (o0, nearer the camera) and, 3.2 cm from its side across its width, a
    4 cm box as tall (o1). The model's hulls come out 3-4 mm wider each side than the
    boxes. Fully open, the near finger spans 3.5-4.5 cm from o0's middle and comes down
    on o1 (its hull from ~4.3 cm); opened to the modelled width (~3.8 cm) + 2 x 1 cm,
    rounded up to 6 cm, it spans 3.0-4.0 cm and fits."""
    box = S.Box(0, 0.08, 0.03, 0.08, x_m=0.0, y_m=0.05)
    near = S.Box(1, 0.08, 0.04, 0.08, x_m=0.0, y_m=0.05 + 0.067)
    world = S.make_scene("gap", [box, near])

    def blocked(clearance: float) -> bool:
        s = Settings()
        s = dataclasses.replace(
            s, predicates=dataclasses.replace(s.predicates, grasp_opening_clearance_m=clearance, grasp_offcentre_fraction=0.0)
        )
        _, state = _state(world, s, seed)
        return ("block_grasp", "o1", "o0") in state.facts

    assert blocked(0.0)
    assert not blocked(0.01)


# --- probing a segment that may be two objects --------------------------------------------------------


def _merged_pair() -> S.Scene:
    yaw = 0.4
    a = S.Box(0, 0.12, 0.045, 0.065, x_m=0.0, y_m=0.05, yaw_rad=yaw)
    b = S.Box(1, 0.12, 0.05, 0.065, x_m=-math.sin(yaw) * 0.0476, y_m=0.05 + math.cos(yaw) * 0.0476, yaw_rad=yaw)
    return S.make_scene("merged_pair", [a, b])


@pytest.mark.parametrize("seed", [0, 1])
def test_probe_push_separates_a_merged_pair_and_the_session_clears(seed: int) -> None:
    from clearcli.pipeline import Pipeline
    from clearcli.replay.session import ReplayOptions, Session
    from clearcli.sim.episode import Episode

    # two 6.5 cm-tall boxes touching along their long sides: one 9.5 cm-wide segment
    settings = _settings()
    episode = Episode(_merged_pair(), Session(Pipeline(settings), ReplayOptions()), seed=seed, max_actions=12)
    for _ in episode:
        pass
    result = episode.result
    assert result is not None and result.end == "cleared" and result.cleared_truly
    probes = [r["plan"]["probe"] for r in episode.reports if r["plan"] and r["plan"]["probe"] is not None]
    assert 1 <= len(probes) <= 2 and all(s.action.startswith("(push") for s in result.steps[: len(probes)])
    # without probing the same session ends at once: "too wide"
    off = dataclasses.replace(settings, plan=dataclasses.replace(settings.plan, probe_max_width_m=0.0))
    episode = Episode(_merged_pair(), Session(Pipeline(off), ReplayOptions()), seed=seed, max_actions=12)
    for _ in episode:
        pass
    assert episode.result is not None and episode.result.end == "no_plan" and episode.result.actions == 0
    assert "too wide" in episode.result.reason and not episode.result.cleared_truly


def test_probe_candidates_exclude_what_fits_and_what_is_far_too_wide() -> None:
    from clearcli.planning.probe import probe_candidates
    from clearcli.planning.types import Plan

    _, state = _state(S.make_scene("three", [
        S.Box(0, 0.05, 0.05, 0.08, x_m=-0.15, y_m=0.05),  # fits the gripper
        S.Box(1, 0.10, 0.10, 0.08, x_m=0.0, y_m=0.05),  # 10 cm: may be two
        S.Box(2, 0.20, 0.20, 0.05, x_m=0.2, y_m=0.05),  # 20 cm: more than two of the widest
    ]), _settings())
    by_width = sorted(state.objects, key=lambda o: o.grasp_width_m)
    plan = Plan(actions=(), cost=0, optimal=True, first=None, ik_facts=frozenset(), unreachable=(), replans=0,
                ungraspable=tuple(o.name for o in by_width))
    assert probe_candidates(state, plan, 0.07, 0.14) == [by_width[1].name]


def test_off_seam_moves_the_push_contact_towards_either_end_of_the_face() -> None:
    from clearcli.planning.probe import off_seam

    _, state = _state(S.make_scene("wide", [S.Box(0, 0.12, 0.10, 0.06, x_m=0.0, y_m=0.05)]), _settings())
    obj = state.objects[0]
    gripper = GripperSettings()
    for d in ("dir1", "dir3"):
        moved = off_seam(state, obj.name, d, gripper).by_name(obj.name).pushes[d]
        push = obj.pushes[d]
        assert len(moved.candidates) == 2 * len(push.candidates)
        across = float(obj.extents_m[1] if d == "dir1" else obj.extents_m[0])
        for k, seq in enumerate(push.candidates):
            closing = np.asarray(seq[1])[:3, 0]
            along = abs(float(closing @ np.asarray(push.unit_vector))) >= 0.7
            contact_half = 0.015 if along else 0.025  # a finger's width, or the closed pair
            reach = across / 2 - contact_half - 0.005
            for sign, shifted in zip((1.0, -1.0), moved.candidates[2 * k : 2 * k + 2]):
                offset = np.asarray(shifted[1])[:3, 3] - np.asarray(seq[1])[:3, 3]
                # across the push, in the table plane, by the reach
                assert abs(float(offset @ np.asarray(push.unit_vector))) < 1e-9
                assert abs(float(offset @ state.table.normal)) < 1e-9
                assert float(np.linalg.norm(offset)) == pytest.approx(reach, abs=1e-9)
    # a face too narrow to move the contact by 1 cm: unchanged
    _, narrow = _state(S.make_scene("narrow", [S.Box(0, 0.12, 0.04, 0.06, x_m=0.0, y_m=0.05)]), _settings())
    o = narrow.objects[0]
    assert off_seam(narrow, o.name, "dir1", gripper).by_name(o.name).pushes["dir1"].candidates == o.pushes["dir1"].candidates


def test_off_centre_first_tries_either_end_of_the_object_after_a_failed_grasp() -> None:
    """A 12 cm box (4 cm wide): its off-centre grasps (30 % of the length, 3.6 cm from
    the middle) come first, one end after an odd number of failures, the other after an
    even one; the centred grasps follow. A box too short to move the grasp by 1 cm keeps
    its order."""
    from clearcli.planning.probe import off_centre_first

    _, state = _state(S.make_scene("long", [S.Box(0, 0.12, 0.04, 0.06, x_m=0.0, y_m=0.05)]), _settings())
    obj = state.objects[0]
    pos = lambda seq: np.asarray(seq[1])[:3, 3]  # noqa: E731
    centre = pos(obj.grasp_candidates[0])
    ends = []
    for failures in (1, 2):
        moved = off_centre_first(state, obj.name, failures).by_name(obj.name).grasp_candidates
        assert len(moved) == len(obj.grasp_candidates)
        offset = pos(moved[0]) - centre
        assert float(np.linalg.norm(offset)) == pytest.approx(0.3 * 0.12, abs=2e-3)
        ends.append(offset)
        # the centred grasp is still there, after every off-centre one
        k = next(i for i, seq in enumerate(moved) if np.linalg.norm(pos(seq) - centre) < 1e-9)
        assert all(np.linalg.norm(pos(seq) - centre) >= 0.01 for seq in moved[:k])
    assert float(ends[0] @ ends[1]) < 0  # the two ends
    _, short = _state(S.make_scene("short", [S.Box(0, 0.04, 0.035, 0.06, x_m=0.0, y_m=0.05)]), _settings())
    o = short.objects[0]
    assert off_centre_first(short, o.name, 1).by_name(o.name).grasp_candidates == o.grasp_candidates


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_two_boxes_merged_end_to_end_are_taken_after_one_failed_grasp(seed: int) -> None:
    """Two boxes of one height (4.7 cm) touching end to end are one segment (no depth cue
    splits them): the centred grasp closes on both at their seam and takes nothing. The
    next grasp tries an end first ([plan] regrasp_off_centre) and takes one box: three
    actions. Without it the same grasp is retried until it counts as infeasible, then
    pushed and retried (10 or more actions, or the budget)."""
    from clearcli.pipeline import Pipeline
    from clearcli.replay.session import ReplayOptions, Session
    from clearcli.sim.episode import Episode

    world = S.make_scene("end to end", [
        S.Box(0, 0.055, 0.044, 0.047, x_m=-0.0275, y_m=0.05),
        S.Box(1, 0.065, 0.044, 0.047, x_m=0.0325, y_m=0.05),
    ])
    settings = Settings()
    results = {}
    for on in (True, False):
        plan = dataclasses.replace(settings.plan, regrasp_off_centre=on)
        episode = Episode(world, Session(Pipeline(dataclasses.replace(settings, plan=plan)), ReplayOptions(push_memory=True)),
                          seed=seed, max_actions=12)
        for _ in episode:
            pass
        assert episode.result is not None
        results[on] = episode.result
    on, off = results[True], results[False]
    assert "at once" in on.steps[0].outcome  # the segmenter merged them
    assert on.cleared_truly and on.actions == 3
    assert off.actions >= 10


def test_budget_spent_on_the_last_object_counts_as_cleared() -> None:
    from clearcli.pipeline import Pipeline
    from clearcli.replay.session import ReplayOptions, Session
    from clearcli.sim.episode import Episode
    from clearcli.sim.truth import truth_segment

    world = S.make_scene("one", [S.Box(0, 0.05, 0.04, 0.08, x_m=0.0, y_m=0.05)])
    episode = Episode(world, Session(Pipeline(_settings(), segment_fn=truth_segment), ReplayOptions()), seed=3, max_actions=1)
    for _ in episode:
        pass
    result = episode.result
    # (4 cm across: far from the 7 cm opening, a grasp of it never slips)
    assert result is not None and result.actions == 1 and result.remaining == ()
    assert result.end == "cleared" and result.cleared_truly
