"""Tests of clearcli/perception/steps.py."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from helpers.segment import S

from clearcli.evaluate.segmentation import score


def test_best_separating_line_by_hand() -> None:
    from clearcli.perception.steps import best_separating_line

    # two 4 x 4 cm tops side by side along x, the upper one at x > 0.01: the line is
    # x = 0.01 (normal +x, halfway between the grid columns at 0.0075 and 0.0125)
    g = np.arange(0.0, 0.04, 0.005) + 0.0025
    xx, yy = np.meshgrid(np.r_[g - 0.03, g + 0.01], g)
    xy = np.stack([xx.ravel(), yy.ravel()], axis=1)
    upper = xy[:, 0] > 0.01
    normal, offset, errors = best_separating_line(xy, upper)
    assert errors == 0
    assert normal == pytest.approx([1.0, 0.0], abs=1e-12)
    assert -0.0075 < offset < 0.0125  # any line in the gap between the two tops
    assert ((xy @ normal > offset) == upper).all()
    # the same with the upper top on the other side: the normal flips
    normal, offset, errors = best_separating_line(xy, ~upper)
    assert errors == 0 and normal == pytest.approx([-1.0, 0.0], abs=1e-12)
    # a bowl: its inside bottom (a disk) surrounded by its rim (a ring): no line
    # separates them; the best leaves at least the disk's share beyond its chord
    t = np.linspace(0, 2 * np.pi, 72, endpoint=False)
    ring = np.stack([0.07 * np.cos(t), 0.07 * np.sin(t)], axis=1)
    disk = np.stack([0.03 * np.cos(t[::4]), 0.03 * np.sin(t[::4])], axis=1) * np.linspace(0.1, 1, 18)[:, None]
    pts = np.vstack([ring, disk])
    _, _, errors = best_separating_line(pts, np.r_[np.ones(len(ring), bool), np.zeros(len(disk), bool)])
    assert errors >= 9  # half the disk, or most of the ring


def test_ledges_only_by_hand() -> None:
    """A step needs one top to be the top of its side: two boxes' tops are; a rough,
    rounded object's level patches on its flanks are ledges on both sides."""
    from clearcli.perception.steps import _ledges_only

    # 20 voxels a side, the upper side (the first 20) at 100 mm but for its top patch
    # (voxels 0-3) at 100 mm too; the lower side at 60 mm, its top patch (20-23) at 60
    two_boxes = np.r_[np.full(20, 0.100), np.full(20, 0.060)]
    side = np.r_[np.ones(20, bool), np.zeros(20, bool)]
    members = np.arange(40)
    tops = np.r_[0:4, 20:24]
    is_upper = np.r_[np.ones(4, bool), np.zeros(4, bool)]
    assert not _ledges_only(two_boxes, members, side, tops, is_upper, 0.02)
    # a loofah: the same patches are ledges at 60 and 20 mm, the rest of each side
    # rising to 90 and 50 mm: its 95th percentile 30 mm above either ledge
    blob = np.r_[np.full(4, 0.060), np.linspace(0.06, 0.09, 16), np.full(4, 0.020), np.linspace(0.02, 0.05, 16)]
    assert _ledges_only(blob, members, side, tops, is_upper, 0.02)
    # the 95th percentile of the upper side's 20: position 0.95 x 19 = 18.05 of them
    # sorted, 88 mm + 0.05 x 2 mm = 88.1 mm, 28.1 mm above its ledge; the lower side's
    # alike, 40 mm lower
    assert not _ledges_only(blob, members, side, tops, is_upper, 0.0282)
    assert _ledges_only(blob, members, side, tops, is_upper, 0.0280)
    # one side's top is its top (the lower one's, a box beside a rounded object): a step
    flank = blob.copy()
    flank[20:] = 0.020
    assert not _ledges_only(flank, members, side, tops, is_upper, 0.02)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_step_split_separates_flush_boxes_of_different_heights(seed: int) -> None:
    """Two boxes of the same footprint width, face to face along x, fronts and backs
    flush, 10 and 7 cm tall: LCCP joins them through the flush faces; the step between
    their tops separates them."""
    from clearcli.perception.segment import segment
    from clearcli.sim.camera import render
    from clearcli.sim.scene import Box, make_scene

    scene = make_scene(
        "flush_pair", [Box(0, 0.05, 0.06, 0.10, x_m=-0.025, y_m=0.0), Box(1, 0.05, 0.06, 0.07, x_m=0.025, y_m=0.0)]
    )
    frame = render(scene, seed=seed)
    off = score(segment(frame, replace(S, planar_cuts=False, step_split=False)).labels(), frame.fields["label"])
    assert off.n_pred == 1
    on = score(segment(frame, replace(S, planar_cuts=False)).labels(), frame.fields["label"])
    assert (on.n_pred, on.true_positives) == (2, 2)
    assert min(on.matched_iou) > 0.8
    # the same pair at equal heights has no step: one segment (the honest limit)
    same = make_scene(
        "flush_pair_same", [Box(0, 0.05, 0.06, 0.10, x_m=-0.025, y_m=0.0), Box(1, 0.05, 0.06, 0.10, x_m=0.025, y_m=0.0)]
    )
    frame = render(same, seed=seed)
    assert score(segment(frame, S).labels(), frame.fields["label"]).n_pred == 1


def _ctx(patch_of_voxel: list[int], height: list[float], step_min_m: float = 0.02) -> Any:
    """What `_may_step` reads of a RefineContext: each top voxel's supervoxel (its top
    patch) and height, and the step (every voxel a top one)."""
    n_sv = max(patch_of_voxel) + 1
    return SimpleNamespace(
        sv=SimpleNamespace(voxel_label=np.asarray(patch_of_voxel), centroids=np.zeros((n_sv, 3))),
        voxel_height=np.asarray(height, dtype=np.float64),
        voxel_is_top=np.ones(len(patch_of_voxel), dtype=bool),
        settings=SimpleNamespace(step_min_m=step_min_m),
    )


def test_may_step_wants_a_step_with_enough_top_on_either_side() -> None:
    from clearcli.perception.steps import _may_step

    # segment 0: 10 voxels at 5 cm and 10 at 10 cm: a step with 10 on each side;
    # segment 1: 10 at 5 cm and 3 at 10 cm: 3 above it; segment 2: 4 at 5 cm, 4 at
    # 6 cm (1 cm apart: no step) and 4 at 10 cm: 8 below the step, 4 above it
    seg = np.repeat([0, 0, 1, 1, 2, 2, 2], [10, 10, 10, 3, 4, 4, 4])
    patch = np.repeat([0, 1, 2, 3, 4, 5, 6], [10, 10, 10, 3, 4, 4, 4])
    height = np.repeat([0.05, 0.10, 0.05, 0.10, 0.05, 0.06, 0.10], [10, 10, 10, 3, 4, 4, 4])
    ctx = _ctx(patch.tolist(), height.tolist())
    assert _may_step(seg, ctx, 5).tolist() == [True, False, False]
    assert _may_step(seg, ctx, 4).tolist() == [True, False, True]
    assert _may_step(seg, ctx, 3).tolist() == [True, True, True]


def test_may_step_is_the_test_of_each_segment_on_random_tops() -> None:
    """For all segments at once, the test `step_splits` makes of each: its patch means
    sorted, a gap of step_min_m with min_top_vox on either side (heights on a 5 mm grid:
    equal heights and gaps of exactly the step too)."""
    from clearcli.perception.graph import dense_labels
    from clearcli.perception.steps import _may_step

    rng = np.random.default_rng(6)
    for trial in range(40):
        n = 150
        seg, patch = rng.integers(0, 6, n), rng.integers(0, 30, n)
        height = rng.integers(0, 12, n) * 0.005
        ctx = _ctx(patch.tolist(), height.tolist(), step_min_m=0.01)
        min_vox = 1 + trial % 12
        got = _may_step(seg, ctx, min_vox)
        for s in range(int(seg.max()) + 1):
            tops = np.flatnonzero(seg == s)
            want = False
            if tops.size >= 2:
                p = dense_labels(patch[tops])
                n_vox = np.bincount(p)
                h = np.bincount(p, weights=height[tops]) / n_vox
                order = np.argsort(h)
                below = np.cumsum(n_vox[order])[:-1]
                ok = (np.diff(h[order]) >= 0.01) & (below >= min_vox) & (tops.size - below >= min_vox)
                want = bool(ok.any())
            assert bool(got[s]) == want
