"""Tests of clearcli/predicates/relations.py."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from helpers.clearing import _state
from helpers.predicates import BOX, by_segment, state_of

from clearcli.predicates.state import SymbolicState
from clearcli.predicates.synthetic import Box
from clearcli.settings import Settings, settings_from_dict
from clearcli.sim import scene as S


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
        geom = build_from_columns(cols[0], 0, settings.predicates)
        grasp = grasp_geometry(geom, gripper, settings.push, 30.0, 0.3)
        counts.append(len(grasp.alternatives))
        if size_x > 0.1:
            # the two off-centre grasps: 0.3 x 14 cm = 4.2 cm either way along the length
            shifts = sorted(float(np.linalg.norm(a.T_grasp[:3, 3] - grasp.T_grasp[:3, 3])) for a in grasp.alternatives)
            assert shifts == pytest.approx([0.042, 0.042], abs=0.004)
    # 5 x 5 cm: the quarter-turned grasp only (5 cm: 1.5 cm max < 5 mm past the finger's
    # half width); 14 x 5 cm: no quarter turn (14 cm > the opening), two off-centre
    assert counts == [1, 2]


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
            s,
            predicates=dataclasses.replace(
                s.predicates, grasp_opening_clearance_m=clearance, grasp_offcentre_fraction=0.0
            ),
        )
        _, state = _state(world, s, seed)
        return ("block_grasp", "o1", "o0") in state.facts

    assert blocked(0.0)
    assert not blocked(0.01)


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


def _least_blocked_one_push_at_a_time(objects, pushes, gripper, exclude):  # type: ignore[no-untyped-def]
    """relations.least_blocked_pushes as it was: one `_gripper_hits` call per push."""
    from clearcli.predicates import relations as R

    allowed = R._allowed(len(objects), exclude)
    out = []
    for b, by_dir in enumerate(pushes):
        chosen = {}
        for name, push in by_dir.items():
            options = (dataclasses.replace(push, alternatives=()), *push.alternatives)
            if len(options) > 1:
                poses = np.stack([p.T_start for p in options])
                rows = np.repeat(allowed[b : b + 1], len(options), axis=0)
                chosen[name] = R._with_fallbacks(options, R._gripper_hits(gripper, True, poses, objects, rows))
            else:
                chosen[name] = options[0]
        out.append(chosen)
    return out


def test_pushes_judged_together_choose_as_one_push_at_a_time() -> None:
    """least_blocked_pushes meets every push's options with the other objects in one
    query: each push keeps the option (and fallbacks) a query of its own chose, on a
    tight row of boxes where neighbours block some yaws and contact points."""
    from clearcli.geometry.gripper import gripper_model
    from clearcli.geometry.models import TableFrame, build_from_columns, object_columns
    from clearcli.geometry.poses import push_geometry
    from clearcli.predicates.relations import least_blocked_pushes
    from clearcli.sim.camera import render
    from clearcli.sim.truth import truth_segment

    settings = Settings()
    # a short box between two tall ones, each 2 cm off along x and 5 cm aside: beside a
    # tall neighbour one yaw of the gripper fits where the other does not
    world = S.make_scene(
        "row",
        [
            S.Box(0, 0.06, 0.06, 0.10, x_m=0.0, y_m=0.0),
            S.Box(1, 0.06, 0.06, 0.20, x_m=0.08, y_m=0.05),
            S.Box(2, 0.06, 0.06, 0.20, x_m=-0.08, y_m=-0.05),
        ],
    )
    frame = render(world, seed=2)
    seg = truth_segment(frame)
    tf = TableFrame.from_plane(seg.table)
    cols = object_columns(frame.points, [o.indices for o in seg.objects], tf, settings.predicates.model_cell_m)
    objects = [build_from_columns(c, k, settings.predicates) for k, c in enumerate(cols) if c is not None]
    gripper = gripper_model(settings.gripper)
    pushes = [push_geometry(o, gripper, settings.push) for o in objects]
    for exclude in (set(), {(0, 1), (1, 0)}):
        got = least_blocked_pushes(objects, pushes, gripper, exclude)
        want = _least_blocked_one_push_at_a_time(objects, pushes, gripper, exclude)
        assert len(got) == len(want) == 3
        moved = 0
        for b, (g, w) in enumerate(zip(got, want, strict=True)):
            assert list(g) == list(w)
            for name in g:
                g_starts = [seq[1].tobytes() for seq in g[name].candidates]
                assert g_starts == [seq[1].tobytes() for seq in w[name].candidates]
                moved += g[name].candidates[0][1].tobytes() != pushes[b][name].candidates[0][1].tobytes()
        assert moved > 0  # some push took another option than its first: the neighbours count
