"""Tests of clearcli/perception/boundary.py: voxels on a segment's boundary moved to the
neighbouring segment whose colour they have."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from clearcli.settings.segment import SegmentSettings

WHITE, BLACK = (255, 255, 255), (0, 0, 0)  # CIELAB L 100 and 0, a = b = 0


def _context(  # type: ignore[no-untyped-def]
    rgb: list[tuple[int, int, int]],
    settings: SegmentSettings,
    color_used: bool = True,
    normals: np.ndarray | None = None,
):
    """A row of one-point voxels 5 mm apart along x, 5 cm above the table z = 0, each
    adjacent to the next, each its own supervoxel (normal up unless ``normals``),
    coloured ``rgb``."""
    from helpers.refine import hand_context

    from clearcli.perception.supervoxels import Supervoxels

    n = len(rgb)
    voxels = np.stack([0.005 * np.arange(n), np.zeros(n), np.full(n, 0.05)], axis=1)
    chain = np.stack([np.arange(n - 1), np.arange(1, n)], axis=1)
    sv = Supervoxels(
        voxel_label=np.arange(n),
        centroids=voxels.copy(),
        normals=np.tile([0.0, 0.0, 1.0], (n, 1)) if normals is None else normals,
        n_voxels=np.ones(n, dtype=np.int64),
        edges=chain,
    )
    return hand_context(voxels, sv, settings, voxel_edges=chain, rgb=np.array(rgb), color_used=color_used)


def test_the_colours_the_stage_reads_are_those_worked_out_by_hand() -> None:
    from clearcli.perception.boundary import segment_colours

    ctx = _context([WHITE, WHITE, BLACK], SegmentSettings())
    assert ctx.voxel_lab is not None
    assert ctx.voxel_lab[:, 0] == pytest.approx([100.0, 100.0, 0.0])
    assert np.abs(ctx.voxel_lab[:, 1:]).max() < 0.02  # greys: a = b = 0 (within 0.02)
    # segment 0: two whites and a black, L (100 + 100 + 0) / 3; segment 1: the black alone
    means = segment_colours(np.array([0, 0, 0, 1]), np.array([[100.0, 0, 0]] * 2 + [[0.0, 0, 0]] * 2), np.ones(4))
    assert means[:, 0] == pytest.approx([200 / 3, 0.0])


def test_white_voxels_left_with_the_black_segment_move_back_to_the_white_one() -> None:
    """Voxels 0-3 white, 4-7 black; the segments start with 2 and 3 on the black side.
    The black segment's mean L is (2 * 100 + 4 * 0) / 6 = 33.3, the white one's 100.
    Round 1: voxel 2 touches voxel 1 of the white segment: 0 from its mean, 66.7 from its
    own, 0 + 10 < 66.7: it moves; voxel 3 touches no other segment yet. Round 2: voxel 3
    now touches voxel 2: it moves. Voxel 4 (black: 100 from the white mean, 33.3 from its
    own) stays, and so does voxel 1 (white: 0 from its own mean)."""
    from clearcli.perception.boundary import move_boundary_voxels

    rgb = [WHITE] * 4 + [BLACK] * 4
    start = np.array([0, 0, 1, 1, 1, 1, 1, 1])
    ctx = _context(rgb, SegmentSettings())
    assert move_boundary_voxels(start, ctx).tolist() == [0, 0, 0, 0, 1, 1, 1, 1]
    # one round: only the voxel on the boundary moves
    one = _context(rgb, SegmentSettings(boundary_rounds=1))
    assert move_boundary_voxels(start, one).tolist() == [0, 0, 0, 1, 1, 1, 1, 1]
    # already right: nothing moves (voxel 3 is 0 from its own mean)
    assert move_boundary_voxels(np.array([0, 0, 0, 0, 1, 1, 1, 1]), ctx).tolist() == [0, 0, 0, 0, 1, 1, 1, 1]


def test_the_margin_and_the_colour_bound_the_moves() -> None:
    from clearcli.perception.boundary import move_boundary_voxels

    rgb = [WHITE] * 4 + [BLACK] * 4
    start = np.array([0, 0, 1, 1, 1, 1, 1, 1])
    # a margin of 70 dE: voxel 2 is 66.7 - 0 nearer the white mean, not enough
    wide = _context(rgb, SegmentSettings(boundary_color_margin_de=70.0))
    assert move_boundary_voxels(start, wide).tolist() == [0, 0, 1, 1, 1, 1, 1, 1]
    # no usable colour: the segments as they come
    blind = _context(rgb, SegmentSettings(), color_used=False)
    assert move_boundary_voxels(start, blind).tolist() == [0, 0, 1, 1, 1, 1, 1, 1]
    # a black voxel among the white ones' segment moves to the black one when it touches it
    mixed = np.array([0, 0, 0, 0, 0, 1, 1, 1])  # voxel 4 black, in the white segment
    out = move_boundary_voxels(mixed, _context(rgb, SegmentSettings()))
    assert out.tolist() == [0, 0, 0, 0, 1, 1, 1, 1]


def test_a_voxel_moves_only_onto_a_surface_it_continues() -> None:
    """Voxel 3 is white like the top's segment (voxels 0-2) but faces -x like the black
    wall (voxels 3-7, normals -x): its normal and that of voxel 2 across the boundary are
    90 degrees apart, more than boundary_max_turn_deg (45): it stays. Allowed any turn
    (180), it goes: the black segment's mean L is 100 / 5 = 20, 80 from it, 0 from the
    white one's."""
    from clearcli.perception.boundary import move_boundary_voxels

    rgb = [WHITE] * 4 + [BLACK] * 4
    normals = np.array([[0.0, 0.0, 1.0]] * 3 + [[-1.0, 0.0, 0.0]] * 5)
    start = np.array([0, 0, 0, 1, 1, 1, 1, 1])
    ctx = _context(rgb, SegmentSettings(), normals=normals)
    assert move_boundary_voxels(start, ctx).tolist() == [0, 0, 0, 1, 1, 1, 1, 1]
    any_turn = _context(rgb, SegmentSettings(boundary_max_turn_deg=180.0), normals=normals)
    assert move_boundary_voxels(start, any_turn).tolist() == [0, 0, 0, 0, 1, 1, 1, 1]


def test_the_stage_runs_in_refine_as_the_last_stage_and_can_be_switched_off() -> None:
    from clearcli.perception.refine import STAGES, refine

    only = tuple(s for s in STAGES if s.name == "boundary")
    assert len(only) == 1 and STAGES[-1].name == "boundary"
    assert SegmentSettings().boundary_refine is False  # off by default
    rgb = [WHITE] * 4 + [BLACK] * 4
    start = np.array([0, 0, 1, 1, 1, 1, 1, 1])
    on_settings = dataclasses.replace(SegmentSettings(), boundary_refine=True)
    on = refine(start, _context(rgb, on_settings), stages=only)
    assert on.tolist() == [0, 0, 0, 0, 1, 1, 1, 1]
    off_settings = dataclasses.replace(SegmentSettings(), boundary_refine=False)
    off = refine(start, _context(rgb, off_settings), stages=only)
    assert off.tolist() == [0, 0, 1, 1, 1, 1, 1, 1]
