"""Tests of clearcli/perception/context.py."""

from __future__ import annotations

import numpy as np

from clearcli.perception.context import by_label


def test_by_label_orders_by_label_then_index() -> None:
    # labels 2 0 1 0 2 1: label 0 at 1 and 3, label 1 at 2 and 5, label 2 at 0 and 4
    assert by_label(np.array([2, 0, 1, 0, 2, 1]), 3).tolist() == [1, 3, 2, 5, 0, 4]
    assert by_label(np.zeros(0, dtype=np.int64), 0).tolist() == []


def test_by_label_is_the_stable_argsort_with_few_and_many_labels() -> None:
    rng = np.random.default_rng(1)
    for n_labels in (1, 7, 300, 32767, 40000):  # int16 by radix up to 32767, then int64
        labels = rng.integers(0, n_labels, 5000)
        assert np.array_equal(by_label(labels, n_labels), np.argsort(labels, kind="stable"))


def _coloured_context(seed: int):  # type: ignore[no-untyped-def]
    """A random coloured frame of 3000 points in 400 voxels (some empty) and 37
    supervoxels, as a `RefineContext` with usable colour."""
    from dataclasses import replace

    from helpers.refine import hand_context

    from clearcli.io.frames import Frame
    from clearcli.perception.supervoxels import Supervoxels
    from clearcli.settings.segment import SegmentSettings

    rng = np.random.default_rng(seed)
    n_pts, n_vox, n_sv = 3000, 400, 37
    voxels = rng.normal(size=(n_vox, 3))
    sv = Supervoxels(
        voxel_label=rng.integers(0, n_sv, n_vox),
        centroids=rng.normal(size=(n_sv, 3)),
        normals=np.tile([0.0, 0.0, 1.0], (n_sv, 1)),
        n_voxels=np.ones(n_sv, dtype=np.int64),
        edges=np.zeros((0, 2), dtype=np.int64),
    )
    ctx = hand_context(voxels, sv, SegmentSettings())
    point_voxel = rng.integers(0, n_vox - 10, n_pts)  # the last ten voxels hold no point
    colors = rng.integers(0, 256, (n_pts + 50, 3)).astype(np.uint8)  # the frame has 50 points more
    point_index = rng.permutation(n_pts + 50)[:n_pts]
    frame = Frame(points=rng.normal(size=(n_pts + 50, 3)).astype(np.float32), colors=colors, source="random")
    vox = replace(ctx.vox, point_voxel=point_voxel, counts=np.bincount(point_voxel, minlength=n_vox))
    return replace(ctx, frame=frame, vox=vox, point_index=point_index, color_used=True), colors[point_index]


def test_voxel_and_supervoxel_colours_are_group_lab_of_the_points_exactly() -> None:
    """`voxel_lab` and `sv_lab` (one pass over the points, the supervoxels' sums from
    the voxels') are the very numbers of `flat.group_lab` over the points by voxel and
    by supervoxel (colors.supervoxel_lab), empty groups too."""
    from clearcli.perception.colors import supervoxel_lab
    from clearcli.perception.flat import group_lab

    for seed in range(3):
        ctx, point_colors = _coloured_context(seed)
        assert np.array_equal(ctx.point_colors, point_colors)
        n_vox = ctx.vox.centroids.shape[0]
        assert np.array_equal(ctx.voxel_lab, group_lab(ctx.vox.point_voxel, point_colors, n_vox))
        assert np.array_equal(ctx.sv_lab, supervoxel_lab(ctx.sv, ctx.vox.point_voxel, point_colors))


def test_no_usable_colour_gives_no_colours() -> None:
    from dataclasses import replace

    ctx, _ = _coloured_context(0)
    off = replace(ctx, color_used=False)
    assert off.point_colors is None and off.voxel_rgb_sum is None
    assert off.voxel_lab is None and off.sv_lab is None
