"""Tests of clearcli/predicates/state_builder.py."""

from __future__ import annotations

import logging

import numpy as np
import pytest
from helpers import shared_path
from helpers.predicates import BOX, by_segment, state_of

from clearcli.perception.types import Segmentation, SegmentedObject
from clearcli.predicates.state import SymbolicState
from clearcli.predicates.state_builder import compute_state
from clearcli.predicates.synthetic import Box, make_scene, segmentation_from_labels
from clearcli.settings import Settings


# ------------------------------------------------------------------------------ bad input
def _seg_with(frame, seg: Segmentation, extra: np.ndarray) -> tuple:
    from clearcli.io.frames import Frame

    points = np.vstack([frame.points, extra.astype(np.float32)])
    idx = np.arange(len(frame.points), len(points))
    bad = SegmentedObject(
        indices=idx,
        centroid=extra.mean(axis=0),
        obb_center=extra.mean(axis=0),
        obb_axes=np.eye(3),
        obb_extents=np.zeros(3),
        principal_axes=np.eye(3),
    )
    seg2 = Segmentation(
        n_points=len(points),
        table=seg.table,
        table_polygon=seg.table_polygon,
        table_indices=seg.table_indices,
        objects=seg.objects + (bad,),
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
