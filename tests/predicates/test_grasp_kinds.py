"""Grasp kinds beyond the thesis's pinch (clearcli/predicates/grasps): rims of open
containers and slides to a seen table edge, on rendered scenes whose sizes are known."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from clearcli.sim import scene as S

# the sim's table is 0.80 x 0.60 m centred on the origin: its right edge at x = +0.40
BOWL = S.Cylinder(0, 0.07, 0.06, -0.10, 0.05, wall_m=0.005)
MUG = S.Cylinder(1, 0.04, 0.095, 0.12, 0.0, wall_m=0.004, handle_m=0.02)
CAN = S.Cylinder(2, 0.04, 0.10, 0.0, -0.15)
FLAT = S.Box(3, 0.20, 0.14, 0.03, 0.25, 0.15)  # right face at x = 0.35


def _settings(robot: str = "panda", grasps: str | None = None):  # type: ignore[no-untyped-def]
    from clearcli.settings.tree import load_settings

    sets = [f"robot.name={robot}"] + ([f'plan.grasps="{grasps}"'] if grasps else [])
    return load_settings(None, sets)


def _state(scene: S.Scene, settings, seed: int = 0):  # type: ignore[no-untyped-def]
    from clearcli.perception.segment import segment
    from clearcli.predicates.state_builder import compute_state
    from clearcli.sim.camera import render

    frame = render(scene, seed=seed)
    seg = segment(frame, settings.segment)
    return frame, seg, compute_state(frame, seg, settings)


def _by_position(state, scene: S.Scene, obj: S.SceneObject):  # type: ignore[no-untyped-def]
    """The state's object nearest to a world object (table frame x, y)."""
    T = scene.T_camera_table
    want = T[:3, :3] @ np.array([obj.x_m, obj.y_m, 0.0]) + T[:3, 3]
    return min(
        state.objects,
        key=lambda o: float(np.linalg.norm((o.centroid - want)[[0]])) + 0.3 * float(np.linalg.norm(o.centroid - want)),
    )


def test_rim_offered_on_a_bowl_and_a_mug_with_their_walls_not_on_a_can() -> None:
    scene = S.make_scene("rims", [BOWL, MUG, CAN])
    _, _, state = _state(scene, _settings())
    for world, wall in ((BOWL, 0.005), (MUG, 0.004)):
        obj = _by_position(state, scene, world)
        assert ("rim_graspable", obj.name) in state.facts, obj.kind_refusals
        detail = obj.kind_details["rim"]
        assert abs(detail["wall_m"] - wall) <= 0.002  # the render's wall, within 2 mm
        assert abs(detail["radius_m"] - (world.radius_m - wall / 2)) <= 0.004
        assert len(obj.kind_candidates["rim"]) >= 1
    can = _by_position(state, scene, CAN)
    assert ("rim_graspable", can.name) not in state.facts
    assert "closed" in can.kind_refusals["rim"]


def test_the_wams_gripper_cannot_close_on_a_wall() -> None:
    # the IRI gripper's fingers stop 3 cm apart (parameters.md): a 5 mm wall slips
    scene = S.make_scene("bowl", [BOWL])
    _, _, state = _state(scene, _settings("wam"))
    (obj,) = state.objects
    assert ("rim_graspable", obj.name) not in state.facts
    assert "thinner than the gripper closes (0.030 m)" in obj.kind_refusals["rim"]


def test_a_rim_grasp_is_planned_ik_checked_and_lands_on_its_pose() -> None:
    from clearcli.planning.backtrack import make_plan
    from clearcli.robot.profiles import kinematics_from_settings

    scene = S.make_scene("bowl", [BOWL])
    settings = _settings("panda")
    _, _, state = _state(scene, settings)
    plan = make_plan(state, settings)
    assert [a.pddl() for a in plan.actions] == ["(grasp_rim o0)"]
    checked = plan.checked[0]
    assert checked is not None and checked.action.grasp_kind == "rim"
    kin = kinematics_from_settings(settings.robot)
    for q, T in zip(checked.joint_solutions, checked.T_base_gripper):
        assert np.linalg.norm(kin.fk(q)[:3, 3] - T[:3, 3]) < 1e-3
    # the grasp pose: approach straight down, closing across the wall (radial)
    T_grasp = np.linalg.inv(plan.T_base_camera) @ checked.T_base_gripper[1]
    T_table = np.linalg.inv(scene.T_camera_table) @ T_grasp
    assert T_table[2, 2] < -0.99
    radial = T_table[:2, 3] - np.array([BOWL.x_m, BOWL.y_m])
    assert abs(np.linalg.norm(radial) - (BOWL.radius_m - 0.0025)) < 0.004
    assert abs(abs(T_table[:2, 0] @ (radial / np.linalg.norm(radial))) - 1.0) < 0.02


def test_pinch_alone_leaves_the_bowl_as_the_thesis_would() -> None:
    from clearcli.errors import NoPlanError
    from clearcli.planning.backtrack import make_plan

    scene = S.make_scene("bowl", [BOWL])
    settings = _settings("panda", "pinch")
    _, _, state = _state(scene, settings)
    with pytest.raises(NoPlanError) as err:
        make_plan(state, settings)
    (left,) = err.value.plan.left  # type: ignore[attr-defined]
    assert left.reason == "ungraspable" and "rim" not in left.detail


def test_slide_to_the_nearest_seen_edge_by_hand() -> None:
    scene = S.make_scene("flat", [FLAT])
    _, seg, state = _state(scene, _settings())
    (obj,) = state.objects
    assert ("ungraspable", obj.name) in state.facts and ("slidable", obj.name) in state.facts
    detail = obj.kind_details["slide"]
    # towards +x of the table (its right edge, 5 cm from the box's face): 0.05 m to the
    # edge plus the 0.035 m overhang
    d_table = np.linalg.inv(scene.T_camera_table)[:3, :3] @ np.asarray(detail["direction"])
    assert d_table[0] > 0.99
    assert abs(detail["slide_m"] - (0.40 - 0.35 + 0.035)) < 0.006
    assert abs(detail["thickness_m"] - 0.03) < 0.004
    # the edges segmentation saw: the table's sides end in the sim (nothing beyond)
    assert any(e.seen for e in seg.table_edges)


def test_a_thicker_slab_is_pinched_from_a_lower_tilt_as_far_as_20_deg() -> None:
    from clearcli.planning.backtrack import make_plan
    from clearcli.predicates.grasps.slide import pinch_tilt_deg

    # by hand, the Panda's 8 cm less 5 mm either side leaves 7 cm: a 3 cm slab from 45 deg
    # (4.2 cm across the fingers), a 6 cm one from acos(6 / 7) = 31.0 deg, a 6.6 cm one
    # from no tilt of 20 deg or more (6.6 > 7 cos 20 = 6.58)
    assert pinch_tilt_deg(0.03, 0.08) == 45.0
    assert pinch_tilt_deg(0.06, 0.08) == pytest.approx(31.0, abs=0.11)
    assert pinch_tilt_deg(0.066, 0.08) is None
    settings = _settings("panda")
    slab = dataclasses.replace(FLAT, size_z_m=0.055)
    _, _, state = _state(S.make_scene("slab", [slab]), settings)
    (obj,) = state.objects
    detail = obj.kind_details["slide"]
    assert ("slidable", obj.name) in state.facts
    # the modelled thickness is the top's height, the sensor's noise on top of 5.5 cm
    assert 0.054 < detail["thickness_m"] < 0.062
    assert detail["tilt_deg"] == pytest.approx(np.degrees(np.arccos(detail["thickness_m"] / 0.07)), abs=0.11)
    assert detail["tilt_deg"] < 45.0
    plan = make_plan(state, settings)
    assert [a.pddl() for a in plan.actions] == [f"(slide_grasp {obj.name})"]
    # the edge pose the arm was checked at comes down at that tilt (robot base frame: z up)
    z = np.asarray(plan.first.T_base_gripper[-2])[:3, 2]
    assert np.degrees(np.arcsin(-z[2])) == pytest.approx(detail["tilt_deg"], abs=1.5)
    # 7 cm thick: not offered, and the reason gives the least tilt and the opening
    _, _, state = _state(S.make_scene("slab", [dataclasses.replace(FLAT, size_z_m=0.07)]), settings)
    (obj,) = state.objects
    assert ("slidable", obj.name) not in state.facts
    assert "even from 20 deg" in obj.kind_refusals["slide"] and "opens to 0.080 m" in obj.kind_refusals["slide"]


def _only_right_edge_seen(scene: S.Scene, seg):  # type: ignore[no-untyped-def]
    """The segmentation with only the table's right side (x = +0.40) seen to end."""
    T_table_camera = np.linalg.inv(scene.T_camera_table)

    def x_of(p: np.ndarray) -> float:
        return float((T_table_camera[:3, :3] @ p + T_table_camera[:3, 3])[0])

    edges = tuple(
        dataclasses.replace(e, seen=e.seen and min(x_of(e.start), x_of(e.end)) > 0.38) for e in seg.table_edges
    )
    assert sum(e.seen for e in edges) == 1
    return dataclasses.replace(seg, table_edges=edges)


def test_slide_blocked_by_what_stands_in_its_path_by_hand() -> None:
    from clearcli.predicates.state_builder import compute_state

    # The flat box spans x 0.12-0.32 and slides right (+x), the only side seen to end. A
    # small box between it and the right edge (x 0.355-0.395) is in its swept path; one
    # 2 cm behind its left face (x 0.06-0.10) is where the closed fingers push from (they
    # stand 3 cm behind the face, 2.5 cm deep): both block. One beside it (y 0.005-0.045,
    # the box's side at y 0.08) is in neither.
    in_path = S.Box(4, 0.04, 0.04, 0.06, 0.375, 0.15)
    behind = S.Box(5, 0.04, 0.04, 0.06, 0.08, 0.15)
    beside = S.Box(6, 0.04, 0.04, 0.06, 0.25, 0.025)
    flat = dataclasses.replace(FLAT, x_m=0.22)
    scene = S.make_scene("two", [flat, in_path, behind, beside])
    settings = _settings()
    frame, seg, _ = _state(scene, settings)
    state = compute_state(frame, _only_right_edge_seen(scene, seg), settings)
    f, p, b, c = (_by_position(state, scene, o) for o in (flat, in_path, behind, beside))
    assert len({f.name, p.name, b.name, c.name}) == 4
    assert ("slidable", f.name) in state.facts
    assert ("block_slide", p.name, f.name) in state.facts
    assert ("block_slide", b.name, f.name) in state.facts
    assert ("block_slide", c.name, f.name) not in state.facts
    # with the small box in the path alone and every side seen: the slide to the far
    # side (+y: from y 0.22 to the edge at 0.30 and 3.5 cm over it) is free, so it is
    # the one offered, and nothing blocks it
    scene = S.make_scene("one", [flat, in_path])
    _, _, state = _state(scene, settings)
    f = _by_position(state, scene, flat)
    assert ("slidable", f.name) in state.facts
    assert not any(x[0] == "block_slide" and x[2] == f.name for x in state.facts)
    detail = f.kind_details["slide"]
    d_table = np.linalg.inv(scene.T_camera_table)[:3, :3] @ np.asarray(detail["direction"])
    assert d_table[1] > 0.99 and abs(detail["slide_m"] - (0.30 - 0.22 + 0.035)) < 0.008


def test_no_slide_when_the_edge_is_only_the_image_border() -> None:
    # a table far larger than the view: every side of what is seen is the image's border
    scene = S.make_scene("big", [dataclasses.replace(FLAT, x_m=0.0, y_m=0.05)], table=S.Table(4.0, 4.0))
    _, seg, state = _state(scene, _settings())
    (obj,) = state.objects
    assert not any(e.seen for e in seg.table_edges)
    assert ("slidable", obj.name) not in state.facts
    assert "no side of the table is seen to end" in obj.kind_refusals["slide"]


def test_no_slide_when_the_edge_is_beyond_the_arms_reach() -> None:
    from clearcli.errors import NoPlanError
    from clearcli.planning.backtrack import make_plan

    scene = S.make_scene("flat", [FLAT])
    settings = _settings()
    _, _, state = _state(scene, settings)
    # the arm's base 1.5 m to the left of the table's centre: the right edge is beyond reach
    T_base_table = np.eye(4)
    T_base_table[:3, 3] = [1.5, 0.0, 0.0]
    T_base_camera = T_base_table @ np.linalg.inv(scene.T_camera_table)
    with pytest.raises(NoPlanError) as err:
        make_plan(state, settings, T_base_camera)
    (left,) = err.value.plan.left  # type: ignore[attr-defined]
    assert (
        "slide grasp: beyond the arm's reach" in left.detail
        or left.actions.get("slide grasp") == "beyond the arm's reach"
    )


# near the robot's side of the table (its base 0.25 m before the near edge, y = -0.3):
# the right edge, 8.5 cm of slide away, is within the Panda's reach
NEAR_FLAT = dataclasses.replace(FLAT, y_m=-0.15)


@pytest.mark.parametrize("world", [BOWL, NEAR_FLAT], ids=["grasp_rim", "slide_grasp"])
def test_plans_with_each_new_action_pass_two_independent_validators(world, tmp_path) -> None:  # type: ignore[no-untyped-def]
    from helpers.validate import second_verdict, validate_files, validate_files_second

    from clearcli.planning.backtrack import make_plan
    from clearcli.planning.pddl import domain_for, write_plan, write_problem
    from clearcli.predicates.grasps import kind

    scene = S.make_scene("one", [world, S.Box(9, 0.04, 0.04, 0.06, -0.25, -0.15)])
    settings = _settings()
    _, _, state = _state(scene, settings)
    plan = make_plan(state, settings)
    kinds = {a.grasp_kind for a in plan.actions if a.kind == "grasp"}
    assert len(plan.goal) == 2 and kinds - {"pinch"}, [a.pddl() for a in plan.actions]
    domain, problem, plan_file = tmp_path / "domain.pddl", tmp_path / "problem.pddl", tmp_path / "plan.txt"
    domain.write_text(domain_for(state))
    problem.write_text(write_problem(state, plan.goal, plan.ik_facts))
    plan_file.write_text(write_plan(plan.actions, plan.cost, unit_cost=False))
    assert kind(next(iter(kinds - {"pinch"}))).facts.action in domain.read_text()
    assert validate_files(domain, problem, plan_file)
    assert validate_files_second(domain, problem, plan_file), second_verdict(domain, problem, plan_file).reason
    # the same plan without the fact that offers the new kind: both refuse it
    offered = {kind(k).facts.offered for k in kinds}
    stripped = dataclasses.replace(state, facts=frozenset(f for f in state.facts if f[0] not in offered))
    problem.write_text(write_problem(stripped, plan.goal, plan.ik_facts))
    assert not validate_files(domain, problem, plan_file)
    assert not validate_files_second(domain, problem, plan_file)


def test_the_pinch_is_preferred_where_it_fits_and_the_left_say_what_was_tried() -> None:
    from clearcli.errors import NoPlanError
    from clearcli.planning.backtrack import make_plan

    # an open cup 6 cm across: the pinch (cost 1) fits the Panda's 8 cm, the rim (2) too
    cup = S.Cylinder(0, 0.03, 0.09, -0.10, -0.05, wall_m=0.004)
    settings = _settings("panda")
    _, _, state = _state(S.make_scene("cup", [cup]), settings)
    assert ("rim_graspable", "o0") in state.facts and ("ungraspable", "o0") not in state.facts
    assert [a.pddl() for a in make_plan(state, settings).actions] == ["(grasp o0)"]
    # a can 12 cm across (closed): no kind takes it, and its reason says why each failed
    can = S.Cylinder(0, 0.06, 0.12, -0.10, -0.05)
    _, _, state = _state(S.make_scene("can", [can]), settings)
    with pytest.raises(NoPlanError) as err:
        make_plan(state, settings)
    (left,) = err.value.plan.left  # type: ignore[attr-defined]
    assert left.reason == "ungraspable"
    assert "opens to 0.080 m" in left.detail and "rim grasp: no rim: closed" in left.detail
    assert "slide grasp: 0.12" in left.detail and "too thick" in left.detail


def test_what_stands_in_a_bowl_goes_first() -> None:
    from clearcli.planning.backtrack import make_plan

    bowl = S.Cylinder(0, 0.08, 0.06, -0.10, -0.08, wall_m=0.005)
    inside = S.Box(1, 0.03, 0.03, 0.05, -0.10, -0.08, base_z_m=0.005)
    settings = _settings("panda")
    _, _, state = _state(S.make_scene("bowl with a box", [bowl, inside]), settings)
    b = _by_position(state, S.make_scene("x", [bowl]), bowl)
    names = [a.obj for a in make_plan(state, settings).actions if a.kind == "grasp"]
    kinds = {a.obj: a.grasp_kind for a in make_plan(state, settings).actions if a.kind == "grasp"}
    assert len(names) == 2 and names[-1] == b.name and kinds[b.name] == "rim", (names, kinds)


def test_a_wall_beyond_the_edge_is_no_edge_to_slide_to() -> None:
    # a wall 1 cm beyond the table's right side (x = +0.40), as tall as the camera: the
    # camera sees no drop there, so that side is not an edge, and the flat box beside it
    # is slid elsewhere (or not at all)
    wall = S.Box(9, 0.02, 0.70, 0.30, 0.42, 0.0)
    scene = S.make_scene("wall", [FLAT, wall])
    _, seg, state = _state(scene, _settings())
    T_table_camera = np.linalg.inv(scene.T_camera_table)

    def x_of(p: np.ndarray) -> float:
        return float((T_table_camera[:3, :3] @ p + T_table_camera[:3, 3])[0])

    right = [e for e in seg.table_edges if min(x_of(e.start), x_of(e.end)) > 0.3]
    assert right and not any(e.seen for e in right)
    assert any(e.why == "something stands beyond it" for e in right), [e.why for e in right]
    flat = _by_position(state, scene, FLAT)
    slides = flat.kind_details.get("slide", {}).get("slides", [])
    for c in slides:  # none of them to the right
        assert (T_table_camera[:3, :3] @ np.asarray(c["direction"]))[0] < 0.9


def test_the_clearance_cost_domain_with_the_kinds_validates(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from helpers.validate import validate_files, validate_files_second

    from clearcli.planning.backtrack import make_plan
    from clearcli.planning.pddl import domain_for, unit_cost, write_plan, write_problem

    settings = _settings()
    settings = dataclasses.replace(settings, predicates=dataclasses.replace(settings.predicates, clearance_cost=True))
    scene = S.make_scene("costs", [BOWL, NEAR_FLAT, S.Box(9, 0.04, 0.04, 0.06, -0.25, -0.15)])
    _, _, state = _state(scene, settings)
    assert state.push_costs and not unit_cost(state)
    plan = make_plan(state, settings)
    assert {a.grasp_kind for a in plan.actions if a.kind == "grasp"} >= {"rim"}
    files = [tmp_path / "domain.pddl", tmp_path / "problem.pddl", tmp_path / "plan.txt"]
    files[0].write_text(domain_for(state))
    files[1].write_text(write_problem(state, plan.goal, plan.ik_facts))
    files[2].write_text(write_plan(plan.actions, plan.cost, unit_cost=False))
    assert "push-cost" in files[0].read_text() and "grasp_rim" in files[0].read_text()
    assert validate_files(*files) and validate_files_second(*files)
