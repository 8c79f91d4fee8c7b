"""Predicates on self-made scenes with hand-derived answers, and on real mOSD stacks.

Synthetic scenes (clearcli.predicates.synthetic): boxes sampled every 5 mm on the faces a
camera 0.6 m above the table sees; world x points away from the camera, so dir1 (the sign
rule: away from the camera) is world +x for a box whose long side is along x, and dir3
(dir1 turned +90 deg about the table normal) is world +y.

Default gripper (parameters.md): opening 0.07, closing 0.03, fingers 0.01 thick and 0.03
wide, closing-region 0.045, so at a grasp the open fingers occupy 0.035..0.045 m either side
of the closing point across the closing direction and reach 0.045 m below the top.
"""

from __future__ import annotations

import json
import logging

import numpy as np
import pytest

from clearcli.perception.types import Segmentation, SegmentedObject
from clearcli.predicates.state import SymbolicState
from clearcli.predicates.state_builder import compute_state
from clearcli.predicates.synthetic import Box, make_scene, segmentation_from_labels
from clearcli.settings import Settings, settings_from_dict
from utils import shared_path

BOX = (0.10, 0.05, 0.05)  # graspable: 5 cm across its closing direction


def state_of(boxes: list[Box], settings: Settings | None = None, **kw) -> SymbolicState:
    frame, seg = make_scene(boxes, **kw)
    return compute_state(frame, seg, settings or Settings())


def by_segment(state: SymbolicState) -> dict[int, str]:
    """segment index (= position in the boxes list) -> object name."""
    return {o.segment_index: o.name for o in state.objects}


def facts_of(state: SymbolicState, kind: str) -> set[tuple[str, ...]]:
    return {f for f in state.facts if f[0] == kind}


# ------------------------------------------------------------------------------ scenes
def test_lone_box_gives_no_facts() -> None:
    state = state_of([Box((0.0, 0.0), BOX)])
    assert len(state.objects) == 1
    assert state.facts == frozenset()
    assert state.objects[0].name == "o0"


def test_empty_scene_is_empty_state() -> None:
    state = state_of([])
    assert state.objects == ()
    assert state.facts == frozenset()


def test_side_by_side_1cm_block_grasp_when_closing_points_at_the_other() -> None:
    # long sides facing each other, 1 cm apart: the closing direction (across the long
    # axis) points at the neighbour; an open finger (0.035..0.045 m from the centre) sits
    # inside the neighbour, which starts 0.025 + 0.01 = 0.035 m from the centre
    state = state_of([Box((0.0, -0.03), BOX), Box((0.0, 0.03), BOX)])
    n = by_segment(state)
    a, b = n[0], n[1]
    assert facts_of(state, "block_grasp") == {("block_grasp", a, b), ("block_grasp", b, a)}
    assert facts_of(state, "on") == set()


def test_end_to_end_1cm_no_block_grasp() -> None:
    # short sides facing each other, 1 cm apart: the closing direction is across the
    # long axis, parallel to the gap; the fingers (0.015 m half width along the long
    # axis) stay 0.035 m clear of the neighbour and the base is above both boxes
    state = state_of([Box((-0.055, 0.0), BOX), Box((0.055, 0.0), BOX)])
    assert facts_of(state, "block_grasp") == set()
    assert facts_of(state, "on") == set()


def test_side_by_side_push_towards_each_other_blocked_sideways_free() -> None:
    # boxes at y = -0.03 (a) and +0.03 (b): towards each other is a: dir3 (+y), b: dir4.
    state = state_of([Box((0.0, -0.03), BOX), Box((0.0, 0.03), BOX)])
    n = by_segment(state)
    a, b = n[0], n[1]
    blocks = facts_of(state, "block_dir")
    # swept volume: a pushed 0.05 m towards b runs into it, and vice versa
    assert ("block_dir", b, a, "dir3") in blocks
    assert ("block_dir", a, b, "dir4") in blocks
    # along the long axis (dir1/dir2) both are free
    assert not {f for f in blocks if f[3] in ("dir1", "dir2")}
    # pushing away from the neighbour puts the closed gripper 0.03 m behind the object,
    # i.e. inside the neighbour 1 cm away: blocked by the gripper check
    assert ("block_dir", b, a, "dir4") in blocks
    assert ("block_dir", a, b, "dir3") in blocks
    assert len(blocks) == 4


def test_push_towards_each_other_only_when_the_gripper_fits() -> None:
    # end to end with a 9 cm gap: a pushed along +x by its length (0.10 m) reaches b;
    # pushed along -x, the closed fingers (0.025 m half size along the push, 0.03 m behind
    # the object) end 1 cm short of b, and the base (0.07 m up) passes over b (0.05 m)
    state = state_of([Box((-0.095, 0.0), BOX), Box((0.095, 0.0), BOX)])
    n = by_segment(state)
    a, b = n[0], n[1]
    assert a == "o0" and b == "o1"  # nearer the camera first
    assert facts_of(state, "block_dir") == {("block_dir", b, a, "dir1"), ("block_dir", a, b, "dir2")}
    assert facts_of(state, "block_grasp") == set()


def test_box_between_two_others_only_sideways() -> None:
    boxes = [Box((0.0, -0.06), BOX), Box((0.0, 0.0), BOX), Box((0.0, 0.06), BOX)]
    state = state_of(boxes)
    mid = by_segment(state)[1]
    blocked = {f[3] for f in facts_of(state, "block_dir") if f[2] == mid}
    assert blocked == {"dir3", "dir4"}  # across the row: blocked; along it: free


def test_box_on_box_gives_exactly_on() -> None:
    bottom = Box((0.0, 0.0), (0.12, 0.06, 0.05))
    top = Box((0.01, 0.0), (0.08, 0.04, 0.03), base_z=0.05)
    state = state_of([bottom, top])
    n = by_segment(state)
    assert state.facts == frozenset({("on", n[1], n[0])})


def test_box_on_book_is_on_it_and_side_by_side_is_not() -> None:
    book = Box((0.0, 0.0), (0.25, 0.18, 0.03))
    box = Box((0.02, 0.01), BOX, yaw_deg=20.0, base_z=0.03)
    state = state_of([book, box])
    n = by_segment(state)
    assert facts_of(state, "on") == {("on", n[1], n[0])}
    beside = state_of([Box((0.0, 0.0), (0.25, 0.18, 0.03)), Box((0.0, 0.125), BOX)])
    assert facts_of(beside, "on") == set()


def test_three_stack_is_on_the_one_below_only() -> None:
    boxes = [
        Box((0.0, 0.0), (0.20, 0.15, 0.03)),
        Box((0.0, 0.0), (0.14, 0.10, 0.03), base_z=0.03),
        Box((0.0, 0.0), (0.08, 0.05, 0.03), base_z=0.06),
    ]
    state = state_of(boxes)
    n = by_segment(state)
    assert facts_of(state, "on") == {("on", n[1], n[0]), ("on", n[2], n[1])}


def test_ungraspable_wide_and_narrow() -> None:
    wide = Box((0.0, -0.1), (0.15, 0.09, 0.04))  # 9 cm > 7 cm opening
    narrow = Box((0.0, 0.1), (0.10, 0.02, 0.04))  # 2 cm < 3 cm closing width
    ok = Box((0.2, 0.0), BOX)
    state = state_of([wide, narrow, ok])
    n = by_segment(state)
    assert facts_of(state, "ungraspable") == {("ungraspable", n[0]), ("ungraspable", n[1])}


def test_push_off_table_only_towards_the_edge() -> None:
    # table half size 0.4 (x) by 0.5 (y); the box's centre 0.04 m from the +x edge: a
    # push of 0.10 m along +x (dir1) ends off the table, the others stay on it
    state = state_of([Box((0.36, 0.0), BOX)])
    assert facts_of(state, "push_off_table") == {("push_off_table", "o0", "dir1")}


def test_clearance_cost_grows_near_neighbours() -> None:
    # 3 cm gap across the row: pushes of a get the original code's cost
    cfg = settings_from_dict({"predicates": {"clearance_cost": True}})
    state = state_of([Box((0.0, -0.04), BOX), Box((0.0, 0.04), BOX), Box((0.5, 0.5), BOX)], settings=cfg)
    n = by_segment(state)
    costs = state.push_costs
    assert len(costs) == 12
    lone = n[2]
    assert all(costs[(lone, d)] == 1 for d in ("dir1", "dir2", "dir3", "dir4"))
    # towards the neighbour: collision (d = 0): ceil(exp(100 * 0.05)) = 149
    assert costs[(n[0], "dir3")] == int(np.ceil(np.exp(5.0)))
    assert costs[(n[0], "dir1")] > 1  # sliding past at 3 cm: closer than 5 cm


# ------------------------------------------------------------------------------ bad input
def _seg_with(frame, seg: Segmentation, extra: np.ndarray) -> tuple:
    from clearcli.io.frames import Frame

    points = np.vstack([frame.points, extra.astype(np.float32)])
    idx = np.arange(len(frame.points), len(points))
    bad = SegmentedObject(
        indices=idx, centroid=extra.mean(axis=0), obb_center=extra.mean(axis=0), obb_axes=np.eye(3),
        obb_extents=np.zeros(3), principal_axes=np.eye(3),
    )
    seg2 = Segmentation(
        n_points=len(points), table=seg.table, table_polygon=seg.table_polygon,
        table_indices=seg.table_indices, objects=seg.objects + (bad,),
    )
    return Frame(points=points), seg2


def test_degenerate_objects_are_left_out_with_a_warning(caplog: pytest.LogCaptureFixture) -> None:
    frame, seg = make_scene([Box((0.0, 0.0), BOX)])
    # a line of points 5 cm above the table, in the sensor frame
    line_world = np.column_stack([np.linspace(0.1, 0.2, 30), np.full(30, 0.2), np.full(30, 0.05)])
    from clearcli.predicates.synthetic import camera_pose

    Twc = camera_pose()
    line = (line_world - Twc[:3, 3]) @ Twc[:3, :3]
    frame2, seg2 = _seg_with(frame, seg, line)
    with caplog.at_level(logging.WARNING, logger="clearcli.predicates"):
        state = compute_state(frame2, seg2, Settings())
    assert len(state.objects) == 1
    assert [i for i, _ in state.skipped] == [1]
    assert "line" in state.skipped[0][1]
    assert any("left out" in r.message for r in caplog.records)
    # a handful of points
    frame3, seg3 = _seg_with(frame, seg, line[:4])
    state3 = compute_state(frame3, seg3, Settings())
    assert [i for i, _ in state3.skipped] == [1]


def test_flat_object_gets_a_model() -> None:
    # a sheet lying on the table (all points at table height) still gets a solid
    sheet = Box((0.0, 0.0), (0.10, 0.05, 0.0005))
    state = state_of([sheet])
    assert len(state.objects) == 1 and not state.skipped
    assert state.objects[0].height_m >= 0.004


# ------------------------------------------------------------------------------ naming
def test_names_by_position_not_segmentation_order() -> None:
    boxes = [Box((0.2, 0.1), BOX), Box((-0.1, 0.0), BOX), Box((0.05, -0.2), BOX)]
    s1 = state_of(boxes)
    s2 = state_of(boxes[::-1])
    c1 = {o.name: np.round(o.centroid, 4).tolist() for o in s1.objects}
    c2 = {o.name: np.round(o.centroid, 4).tolist() for o in s2.objects}
    assert c1 == c2
    assert by_segment(s1) == {1: "o0", 2: "o1", 0: "o2"}  # nearest the camera first


# ------------------------------------------------------------------------------ real frames
# `on` facts read off each frame's picture (clear predicates --ground-truth --png, and
# the RGB image); objects from the ground-truth labels, so the names are stable.
REAL_ON = {
    "learn/learn17.pcd": ({("o1", "o0")}, set()),
    "learn/learn18.pcd": ({("o0", "o1")}, set()),
    "learn/learn19.pcd": ({("o1", "o0")}, set()),
    "learn/learn20.pcd": ({("o1", "o0")}, set()),
    "learn/learn21.pcd": ({("o0", "o1"), ("o2", "o1")}, set()),
    "learn/learn22.pcd": ({("o1", "o0"), ("o2", "o1")}, set()),
    "learn/learn23.pcd": ({("o2", "o0"), ("o1", "o2")}, set()),
    "learn/learn24.pcd": ({("o2", "o1")}, set()),
}
# cluttered frames: the stacks that are clear in the picture must be found; objects
# plainly standing on the table must be on nothing (others are left open)
CLUTTER_ON = {
    "test/test55.pcd": ({("o0", "o2"), ("o2", "o4"), ("o10", "o9")}, {"o1", "o6", "o11", "o12", "o13"}),
    "test/test57.pcd": (
        {("o5", "o4"), ("o14", "o12"), ("o2", "o1"), ("o10", "o11"), ("o13", "o11"), ("o8", "o7"), ("o3", "o2")},
        {"o11", "o12", "o15"},
    ),
}


def _real_state(rel: str) -> SymbolicState:
    from clearcli.io.read import read_frame

    frame = read_frame(shared_path("mosd/" + rel))
    return compute_state(frame, segmentation_from_labels(frame), Settings())


@pytest.mark.parametrize("rel", sorted(REAL_ON))
def test_real_stacks_on_facts(rel: str) -> None:
    expected, _ = REAL_ON[rel]
    state = _real_state(rel)
    found = {(f[1], f[2]) for f in state.facts if f[0] == "on"}
    assert found == expected


@pytest.mark.parametrize("rel", sorted(CLUTTER_ON))
def test_real_clutter_on_facts(rel: str) -> None:
    required, on_table = CLUTTER_ON[rel]
    state = _real_state(rel)
    found = {(f[1], f[2]) for f in state.facts if f[0] == "on"}
    assert required <= found
    assert not {a for a, _ in found} & on_table


# ------------------------------------------------------------------------------ CLI
def test_cli_predicates_json_problem_png_and_domain(tmp_path) -> None:
    from typer.testing import CliRunner

    from clearcli.cli import app
    from clearcli.planning.pddl import domain_text

    pcd = shared_path("mosd/learn/learn17.pcd")
    runner = CliRunner()
    out = tmp_path / "p.pddl"
    png = tmp_path / "p.png"
    res = runner.invoke(app, ["predicates", str(pcd), "--ground-truth", "--json", "-o", str(out), "--png", str(png)])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout.strip().splitlines()[-1])
    assert doc["schema"] == "clear.predicates" and doc["version"] == 1
    assert "(on o1 o0)" in doc["facts"]
    obj = doc["objects"][0]
    assert set(obj["directions"]) == {"dir1", "dir2", "dir3", "dir4"}
    assert np.allclose(np.linalg.norm(obj["directions"]["dir1"]), 1.0, atol=1e-5)
    # the two half-turns, then IK fallbacks (another yaw, off-centre grasps)
    assert len(obj["grasp_poses"]) >= 2 and len(obj["grasp_poses"]) % 2 == 0
    assert np.array(obj["grasp_poses"][0]).shape == (4, 4)
    assert "(on o1 o0)" in out.read_text()
    assert png.read_bytes()[:4] == b"\x89PNG"
    # no clobbering without --force
    res2 = runner.invoke(app, ["predicates", str(pcd), "--ground-truth", "-o", str(out)])
    from clearcli.errors import OutputError

    assert isinstance(res2.exception, OutputError)  # main() maps it to exit code 8
    res3 = runner.invoke(app, ["domain"])
    assert res3.exit_code == 0 and res3.stdout == domain_text()
# Tests for tests/test_predicates.py (uses its state_of/by_segment/facts_of helpers).


def test_grasp_turns_the_gripper_away_from_a_tall_neighbour() -> None:
    # a 6 x 5 cm box, its 6 cm side 1 cm from a tall box: closing across the 5 cm width
    # puts a finger inside the neighbour; turned a quarter turn (across the 6 cm length,
    # within the 7 cm opening) the fingers and the base stay clear of it
    small = Box((0.0, -0.03), (0.06, 0.05, 0.05))
    tall = Box((0.0, 0.03), (0.10, 0.05, 0.15))
    state = state_of([small, tall])
    n = by_segment(state)
    assert ("block_grasp", n[1], n[0]) not in facts_of(state, "block_grasp")
    assert 0.055 < state.by_name(n[0]).grasp_width_m < 0.066  # closing across the length
    assert facts_of(state, "ungraspable") == set()


def test_square_box_seen_corner_on_is_graspable_across_its_side() -> None:
    # a 6 cm square turned 45 degrees: the principal directions of a square footprint
    # point anywhere (here along the diagonals: 8.5 cm across, "too wide"); the
    # narrowest width is its side
    state = state_of([Box((0.0, 0.0), (0.060, 0.060, 0.08), yaw_deg=45.0)])
    (obj,) = state.objects
    assert abs(obj.grasp_width_m - 0.060) < 0.004 and facts_of(state, "ungraspable") == set()


def test_min_width_direction_of_a_turned_rectangle() -> None:
    from clearcli.geometry.poses import min_width_direction

    c, s = np.cos(0.3), np.sin(0.3)
    rect = np.array([[0.05, 0.02], [-0.05, 0.02], [-0.05, -0.02], [0.05, -0.02]]) @ np.array([[c, s], [-s, c]])
    e1, e2 = rect[1] - rect[0], rect[2] - rect[1]
    rect = rect[::-1] if e1[0] * e2[1] - e1[1] * e2[0] < 0 else rect
    d = min_width_direction(rect)
    assert abs(abs(d @ np.array([-s, c])) - 1.0) < 1e-9  # across the 4 cm side


def test_least_blocked_option_keeps_its_facts_and_gets_the_others_as_ik_fallbacks() -> None:
    """Options 0-3 of one push: 0 blocked by objects {1}, 1 by {1, 2}, 2 by {}, 3 by {}.
    The least blocked (2, the first of the two free ones) stands for the push; 3 (blocked
    by nothing 2 is not) follows as a fallback; 0 and 1 (blocked by more) do not."""
    import dataclasses

    from clearcli.predicates.relations import _with_fallbacks

    @dataclasses.dataclass(frozen=True)
    class Option:
        candidates: tuple

    options = [Option((f"o{k}a", f"o{k}b")) for k in range(4)]
    hits = [(0, 1), (1, 1), (1, 2)]
    chosen = _with_fallbacks(options, hits)
    assert chosen.candidates == ("o2a", "o2b", "o3a", "o3b")
    # a blocked best: fallbacks are the options blocked by a subset of its blockers
    chosen = _with_fallbacks(options[:2], [(0, 1), (1, 1), (1, 2)])
    assert chosen.candidates == ("o0a", "o0b")
    chosen = _with_fallbacks(options[:2], [(0, 1), (1, 1)])
    assert chosen.candidates == ("o0a", "o0b", "o1a", "o1b")
