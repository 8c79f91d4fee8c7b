"""Tests of clearcli/perception/boundary.py: a supervoxel on a boundary moved to the
segment whose surface it continues."""

from __future__ import annotations

import numpy as np

from clearcli.settings.segment import SegmentSettings


def _context(settings: SegmentSettings):  # type: ignore[no-untyped-def]
    """Five one-voxel supervoxels, z up, the table z = 0. A level top at z = 5 cm, three
    patches 2 cm apart along x (0: x = 0, 1: x = 2 cm, 2: x = 4 cm, normals up), and a
    wall rising beside its end (3: x = 6 cm, z = 7 cm; 4: z = 9 cm; normals -x, facing the
    top). Adjacent: 0-1, 1-2, 2-3, 3-4.

    By hand (lccp.convex_edges): 0-1 and 1-2 lie in one plane, one normal (the angles
    from the joining line to both normals are 90 degrees: convex, offset 0); 3-4 too;
    2-3 is the crease where the top meets the wall rising above it: d = x2 - x3 =
    (-2, 0, -2) cm makes 135 degrees with n2 = +z and 45 with n3 = -x, 135 - 45 > 0, and
    the normals are 90 degrees apart, beyond the 30 degree tolerance: concave."""
    from helpers.refine import hand_context

    from clearcli.perception.supervoxels import Supervoxels

    voxels = np.array([[0.0, 0.0, 0.05], [0.02, 0.0, 0.05], [0.04, 0.0, 0.05], [0.06, 0.0, 0.07], [0.06, 0.0, 0.09]])
    up, facing_top = [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]
    sv = Supervoxels(
        voxel_label=np.arange(5),
        centroids=voxels.copy(),
        normals=np.array([up, up, up, facing_top, facing_top]),
        n_voxels=np.ones(5, dtype=np.int64),
        edges=np.array([[0, 1], [1, 2], [2, 3], [3, 4]]),
    )
    return hand_context(voxels, sv, settings, voxel_edges=sv.edges)


def test_the_convexity_the_stage_reads_is_the_one_worked_out_by_hand() -> None:
    import dataclasses

    from clearcli.perception.lccp import convex_edges

    ctx = _context(SegmentSettings())
    relaxed = dataclasses.replace(ctx.settings, sanity_criterion=False)
    assert convex_edges(ctx.sv, relaxed, ctx.size, None, ctx.vox).tolist() == [True, True, False, True]


def test_a_piece_of_the_top_left_in_the_walls_segment_moves_back_to_the_top() -> None:
    """Patch 2 starts in the wall's segment (1). It has one convex adjacency with the top's
    segment (to patch 1) and none within its own (its only one there, to patch 3, is the
    concave crease): 1 >= 0 + boundary_min_lead (1), it moves to segment 0. Patch 1 has
    one convex adjacency at home (0) and one with segment 1 (2): 1 < 1 + 1, it stays;
    patch 3 has one at home (4) and none across: it stays. Segment 1 loses 1 of its 3
    voxels, under half."""
    from clearcli.perception.boundary import move_boundary_supervoxels

    ctx = _context(SegmentSettings(boundary_refine=True))
    assert move_boundary_supervoxels(np.array([0, 0, 1, 1, 1]), ctx).tolist() == [0, 0, 0, 1, 1]
    # already right: nothing moves (patch 3 has one convex adjacency at home, none across)
    assert move_boundary_supervoxels(np.array([0, 0, 0, 1, 1]), ctx).tolist() == [0, 0, 0, 1, 1]


def test_the_lead_and_the_half_of_a_segment_bound_the_moves() -> None:
    from clearcli.perception.boundary import move_boundary_supervoxels

    # a lead of 2: patch 2's one convex adjacency with the top is not enough
    ctx = _context(SegmentSettings(boundary_refine=True, boundary_min_lead=2))
    assert move_boundary_supervoxels(np.array([0, 0, 1, 1, 1]), ctx).tolist() == [0, 0, 1, 1, 1]
    # patch 2 a segment of its own: moving it would take all of that segment's voxels
    # (more than half), a join, not a boundary moved
    ctx = _context(SegmentSettings(boundary_refine=True))
    assert move_boundary_supervoxels(np.array([0, 0, 1, 2, 2]), ctx).tolist() == [0, 0, 1, 2, 2]


def test_the_stage_runs_in_refine_only_when_switched_on() -> None:
    from clearcli.perception.refine import STAGES, refine

    only = tuple(s for s in STAGES if s.name == "boundary")
    assert len(only) == 1 and STAGES[-1].name == "boundary"  # the last refinement
    wrong_side = np.array([0, 0, 1, 1, 1])
    assert SegmentSettings().boundary_refine is False  # off by default
    off = refine(wrong_side, _context(SegmentSettings()), stages=only)
    assert off.tolist() == [0, 0, 1, 1, 1]
    on = refine(wrong_side, _context(SegmentSettings(boundary_refine=True)), stages=only)
    assert on.tolist() == [0, 0, 0, 1, 1]
