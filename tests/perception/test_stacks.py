"""Tests of clearcli/perception/stacks.py."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np

from clearcli.perception import stacks


def _ctx(patch_of_voxel: list[int], height: list[float], is_top: list[bool], step_min_m: float = 0.008) -> Any:
    """What `_may_split` reads of a RefineContext: each voxel's supervoxel (its top
    patch), height and top flag, and the step."""
    n_sv = max(patch_of_voxel) + 1
    return SimpleNamespace(
        sv=SimpleNamespace(voxel_label=np.asarray(patch_of_voxel), centroids=np.zeros((n_sv, 3))),
        voxel_height=np.asarray(height, dtype=np.float64),
        voxel_is_top=np.asarray(is_top),
        settings=SimpleNamespace(step_min_m=step_min_m),
    )


def test_only_segments_with_tops_at_two_levels_may_split() -> None:
    # segment 0: top patches at 5 and 10 cm (a box on a tray); segment 1: at 5.0 and
    # 5.5 cm (under the 8 mm step: one level), and a wall voxel at 20 cm that is no top;
    # segment 2: one patch; segment 3: no top at all
    seg = np.array([0, 0, 0, 0, 1, 1, 1, 2, 2, 3])
    ctx = _ctx(
        [0, 0, 1, 1, 2, 3, 4, 5, 5, 6],
        [0.05, 0.05, 0.10, 0.10, 0.05, 0.055, 0.20, 0.03, 0.09, 0.04],
        [True, True, True, True, True, True, False, True, True, False],
    )
    assert stacks._may_split(seg, ctx).tolist() == [True, False, False, False]
    # a patch's height is its voxels' mean: 4.6 and 5.4 cm average to 5 cm, 8 mm under
    # the 5.8 cm patch beside it by a hair less than the step: one level ...
    ctx = _ctx([0, 0, 1], [0.046, 0.054, 0.0579], [True, True, True])
    assert stacks._may_split(np.zeros(3, dtype=np.int64), ctx).tolist() == [False]
    # ... and two a hair over it
    ctx = _ctx([0, 0, 1], [0.046, 0.054, 0.0581], [True, True, True])
    assert stacks._may_split(np.zeros(3, dtype=np.int64), ctx).tolist() == [True]


def test_may_split_is_the_levels_test_of_each_segment_on_random_tops() -> None:
    """The test for all segments at once is `stack_splits`' own per segment: its patch
    means and `_levels`, heights on a 2 mm grid (equal heights and exact steps too)."""
    from clearcli.perception.graph import dense_labels

    rng = np.random.default_rng(4)
    for _ in range(30):
        n = 200
        seg = rng.integers(0, 8, n)
        patch = rng.integers(0, 40, n)
        height = rng.integers(0, 30, n) * 0.002
        is_top = rng.random(n) < 0.7
        ctx = _ctx(patch.tolist(), height.tolist(), is_top.tolist())
        got = stacks._may_split(seg, ctx)
        for s in range(int(seg.max()) + 1):
            tops = np.flatnonzero((seg == s) & is_top)
            want = False
            if tops.size >= 2:
                p = dense_labels(patch[tops])
                h = np.bincount(p, weights=height[tops]) / np.bincount(p)
                want = int(stacks._levels(h, 0.008).max()) >= 1
            assert bool(got[s]) == want
