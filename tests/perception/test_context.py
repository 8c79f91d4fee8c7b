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


def test_what_lccp_reads_of_the_context_is_what_it_worked_out_itself() -> None:
    """segment._lccp reads the frame's `RefineContext` (issue 39): its supervoxel colours
    are `flat.group_lab` of the points above the table by supervoxel (LCCP's own pass
    before), and its `sv_edge_shape` gives LCCP's convexity, the planar cuts' and the
    colour splits' angles bit for bit, on the committed cluttered fixture."""
    from helpers import FIXTURES

    from clearcli.io.read import read_frame
    from clearcli.perception import colors, cuts
    from clearcli.perception import segment as seg_mod
    from clearcli.perception.clock import Clock
    from clearcli.perception.flat import group_lab
    from clearcli.perception.lccp import convex_edges
    from clearcli.settings.segment import SegmentSettings

    frame = read_frame(FIXTURES / "clutter10.pcd")
    settings = SegmentSettings()
    w = seg_mod._Work(frame, settings, frame.is_organized and frame.shape is not None, Clock())
    for step in seg_mod.STEPS:
        step.run(w)
        if step.run is seg_mod._lccp:
            break
    ctx, vox, sv = w.ctx, w.vox, w.sv
    assert ctx is not None and vox is not None and sv is not None and w.color_used
    assert ctx.vox is vox and ctx.sv is sv and ctx.point_index is w.obj_idx
    assert frame.colors is not None
    own = group_lab(sv.voxel_label[vox.point_voxel], np.take(frame.colors, w.obj_idx, axis=0), sv.centroids.shape[0])
    assert np.array_equal(ctx.sv_lab, own)
    assert np.array_equal(ctx.vox.counts, np.bincount(vox.point_voxel, minlength=vox.n_voxels))
    shape = ctx.sv_edge_shape
    for lab, v in ((None, None), (own, vox)):
        assert np.array_equal(
            convex_edges(sv, settings, ctx.size, lab, v, shape), convex_edges(sv, settings, ctx.size, lab, v)
        )
    for a, b in zip(
        cuts._convex_and_angle(sv, settings, ctx.size, shape),
        cuts._convex_and_angle(sv, settings, ctx.size),
        strict=True,
    ):
        assert np.array_equal(a, b)
    seg = np.zeros(sv.centroids.shape[0], dtype=np.int64)
    for a, b in zip(colors._pieces(seg, sv, own, 25.0, shape), colors._pieces(seg, sv, own, 25.0), strict=True):
        assert np.array_equal(a, b)
