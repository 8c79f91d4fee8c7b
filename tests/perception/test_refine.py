"""Tests of clearcli/perception/refine.py."""

from __future__ import annotations

import numpy as np
import pytest

from clearcli.io.frames import Frame
from clearcli.settings.segment import SegmentSettings


def test_refinement_stages_run_from_one_list() -> None:
    """The refinements after LCCP are one list, in order, one signature each; a stage that
    needs the pixel grid is skipped on an unorganized cloud, so the result there equals
    the result with that stage off."""
    from helpers import FIXTURES

    from clearcli.io.read import read_frame
    from clearcli.perception.refine import STAGES
    from clearcli.perception.segment import segment

    assert [s.name for s in STAGES] == [
        "stacks",
        "cuts",
        "occlusion",
        "colors",
        "steps",
        "rims",
        "rings",
        "vessels",
        "fragments",
        "seams",
        "learned",
        "boundary",
    ]
    assert [s.name for s in STAGES if s.needs_grid] == ["occlusion"]
    frame = read_frame(FIXTURES / "clutter10.pcd")
    seg = segment(frame, SegmentSettings())
    assert {"cuts", "occlusion", "steps", "rims", "merge"} <= set(seg.timings_s)
    finite = np.isfinite(frame.points).all(axis=1)
    flat = Frame(
        points=frame.points[finite],
        colors=None if frame.colors is None else frame.colors[finite],
        shape=None,
        fields={},
        source="unorganized",
    )
    unorganized = segment(flat, SegmentSettings(occlusion_merge=True))
    # colour is read there by the containers' walls only: the flat objects need the grid
    assert unorganized.color_used and unorganized.color_note == "read by: colour splits, containers' walls"
    on = unorganized.labels()
    off = segment(flat, SegmentSettings(occlusion_merge=False)).labels()
    assert np.array_equal(on, off) and len(np.unique(on[on >= 10])) >= 5
    # every stage off: LCCP's segments as they come
    bare = SegmentSettings(planar_cuts=False, occlusion_merge=False, step_split=False, rim_merge=False)
    assert segment(frame, bare).objects


def _tilted(deg: float) -> list[float]:
    """A unit normal ``deg`` degrees from the table's (0, 0.6, 0.8), turned about x."""
    a = np.arctan2(0.6, 0.8) + np.radians(deg)
    return [0.0, float(np.sin(a)), float(np.cos(a))]


def _context():  # type: ignore[no-untyped-def]
    """Five voxels in three supervoxels over the table 0.6 y + 0.8 z - 0.1 = 0 (heights
    0.6 y + 0.8 z - 0.1)."""
    from helpers.refine import hand_context

    from clearcli.perception.supervoxels import Supervoxels

    voxels = np.array([[0.0, 0.0, 0.5], [0.0, 1.0, 0.0], [0.3, 0.0, 0.5], [0.0, 0.3, 0.9], [0.0, 0.6, 1.3]])
    normals = np.array([_tilted(19.0), _tilted(21.0), [1.0, 0.0, 0.0]])
    sv = Supervoxels(
        voxel_label=np.array([2, 0, 0, 1, 2]),
        centroids=voxels[[1, 3, 0]],
        normals=normals,
        n_voxels=np.array([2, 1, 2]),
        edges=np.array([[0, 1], [1, 2]]),
    )
    return hand_context(voxels, sv, SegmentSettings(), normal=(0.0, 0.6, 0.8), offset=-0.1)


def test_the_context_derives_each_value_once_by_hand() -> None:
    ctx = _context()
    assert ctx.up == pytest.approx([0.0, 0.6, 0.8])
    # 0.6 y + 0.8 z - 0.1
    assert ctx.voxel_height == pytest.approx([0.3, 0.5, 0.3, 0.8, 1.3])
    assert ctx.sv_height == pytest.approx([0.5, 0.8, 0.3])
    # step_max_tilt_deg 20: 19 degrees off the table's normal is a top, 21 a wall, a
    # level normal a wall
    assert ctx.sv_is_top.tolist() == [True, False, False]
    assert ctx.sv_is_wall.tolist() == [False, True, True]
    assert ctx.voxel_is_top.tolist() == [False, True, True, False, False]
    # in the table plane: (0, 0, 0.5), (0, 0.3, 0.9) and (0, 0.6, 1.3) differ along the
    # normal only; (0.3, 0, 0.5) lies 0.3 m to the side; (0, 1, 0) is (0, 1, -0.5) away,
    # 0.2 of it along the normal: (0, 0.88, -0.66) in the plane, 1.1 m
    xy = ctx.voxel_xy
    assert xy[0] == pytest.approx(xy[4]) and xy[0] == pytest.approx(xy[3])
    assert np.linalg.norm(xy[2] - xy[0]) == pytest.approx(0.3)
    assert np.linalg.norm(xy[1] - xy[0]) == pytest.approx(1.1)
    assert np.linalg.norm(ctx.sv_normals_xy, axis=1) == pytest.approx(
        [np.sin(np.radians(19.0)), np.sin(np.radians(21.0)), 1.0]
    )
    assert ctx.sv_xy == pytest.approx(xy[[1, 3, 0]])
    assert ctx.first_voxel.tolist() == [1, 3, 0]
    assert ctx.point_colors is None and ctx.voxel_lab is None  # no usable colour
    assert ctx.size.min_object_voxels == 40  # the settings' sizes: 10 cm^2 of 5 mm voxels
    assert ctx.voxel_height is ctx.voxel_height  # worked out once


def test_refine_runs_the_enabled_stages_and_times_each_by_its_name() -> None:
    """A supervoxel-level stage sees and hands back one segment per supervoxel; a stage
    switched off or needing the pixel grid (on an unorganized cloud) is skipped, and
    every stage's time is reported, under its name."""
    from clearcli.perception.clock import Clock
    from clearcli.perception.refine import Stage, refine

    ctx = _context()
    seen = []

    def per_sv(seg: np.ndarray, c) -> np.ndarray:  # type: ignore[no-untyped-def]
        seen.append(seg.copy())
        return np.array([0, 1, 1])  # supervoxels 1 and 2 joined

    def never(seg: np.ndarray, c) -> np.ndarray:  # type: ignore[no-untyped-def]
        raise AssertionError("skipped stages are not run")

    stages = (
        Stage("sv", lambda s: True, per_sv, per_supervoxel=True),
        Stage("off", lambda s: not s.color_split, never),  # colour splits are on by default
        Stage("grid", lambda s: True, never, needs_grid=True),
        Stage("voxels", lambda s: True, lambda seg, c: seg + 10),
    )
    clock = Clock()
    out = refine(np.array([2, 0, 0, 1, 2]), ctx, clock, stages)
    assert [s.tolist() for s in seen] == [[0, 1, 2]]  # each supervoxel's segment
    assert out.tolist() == [11, 10, 10, 11, 11]  # voxel_label [2, 0, 0, 1, 2] -> [1, 0, 0, 1, 1]
    assert list(clock.timings) == ["sv", "off", "grid", "voxels"]
    assert all(t >= 0.0 for t in clock.timings.values())
