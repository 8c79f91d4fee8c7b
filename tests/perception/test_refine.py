"""Tests of clearcli/perception/refine.py."""

from __future__ import annotations

import numpy as np

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

    assert [s.name for s in STAGES] == ["stacks", "cuts", "occlusion", "colors", "steps", "rims", "rings", "vessels", "fragments"]
    assert [s.name for s in STAGES if s.needs_grid] == ["occlusion"]
    frame = read_frame(FIXTURES / "clutter10.pcd")
    seg = segment(frame, SegmentSettings())
    assert {"cuts", "occlusion", "steps", "rims", "merge"} <= set(seg.timings_s)
    finite = np.isfinite(frame.points).all(axis=1)
    flat = Frame(points=frame.points[finite], colors=None if frame.colors is None else frame.colors[finite],
                 shape=None, fields={}, source="unorganized")
    unorganized = segment(flat, SegmentSettings(occlusion_merge=True))
    # colour is read there by the containers' walls only: the flat objects need the grid
    assert unorganized.color_used and unorganized.color_note == "read by: containers' walls"
    on = unorganized.labels()
    off = segment(flat, SegmentSettings(occlusion_merge=False)).labels()
    assert np.array_equal(on, off) and len(np.unique(on[on >= 10])) >= 5
    # every stage off: LCCP's segments as they come
    bare = SegmentSettings(planar_cuts=False, occlusion_merge=False, step_split=False, rim_merge=False)
    assert segment(frame, bare).objects
