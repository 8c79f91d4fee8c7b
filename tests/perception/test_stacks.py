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


STEP_M = 0.004  # the voxel spacing the surfaces are sampled at


def _cylinder_near_half(r_m: float, z0: float, z1: float) -> tuple[np.ndarray, np.ndarray]:
    """The near half (180..360 degrees) of a cylinder's side about (0, 0), every STEP_M:
    points (N, 3) and their unit normals (N, 3), level, facing out."""
    pts, nrm = [], []
    n_a = int(np.pi * r_m / STEP_M)
    a = np.radians(np.linspace(180.0, 360.0, n_a))
    for z in np.arange(z0, z1 + 1e-9, STEP_M):
        pts.append(np.column_stack([r_m * np.cos(a), r_m * np.sin(a), np.full(n_a, z)]))
        nrm.append(np.column_stack([np.cos(a), np.sin(a), np.zeros(n_a)]))
    return np.vstack(pts), np.vstack(nrm)


def _disc(r0_m: float, r1_m: float, z: float, deg0: float, deg1: float) -> np.ndarray:
    """Points (N, 3) of a flat ring r0..r1 over deg0..deg1 at height z, every STEP_M."""
    pts = []
    for r in np.arange(max(r0_m, STEP_M), r1_m + 1e-9, STEP_M):
        n_a = max(2, int(np.radians(deg1 - deg0) * r / STEP_M))
        a = np.radians(np.linspace(deg0, deg1, n_a))
        pts.append(np.column_stack([r * np.cos(a), r * np.sin(a), np.full(n_a, z)]))
    return np.vstack(pts)


def _stack_splits(parts: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """parts: (points, normals) per surface, all one segment, each voxel its own
    supervoxel -> (part of each voxel, segment out)."""
    from helpers.refine import hand_context
    from scipy.spatial import cKDTree

    from clearcli.perception.supervoxels import Supervoxels
    from clearcli.settings.segment import SegmentSettings

    pts = np.vstack([p[0] for p in parts])
    normals = np.vstack([p[1] for p in parts])
    part = np.repeat(np.arange(len(parts)), [p[0].shape[0] for p in parts])
    n = pts.shape[0]
    edges = cKDTree(pts).query_pairs(1.8 * STEP_M, output_type="ndarray")
    sv = Supervoxels(np.arange(n), pts, normals, np.ones(n, dtype=np.int64), np.zeros((0, 2), dtype=np.int64))
    settings = SegmentSettings(voxel_m=STEP_M, min_object_area_m2=20.5 * STEP_M**2)
    ctx = hand_context(pts, sv, settings, edges)
    return part, stacks.stack_splits(np.zeros(n, dtype=np.int64), ctx)


def test_a_can_on_a_tin_of_its_diameter_is_split_off_above_the_tins_crescent() -> None:
    # a tin 8 cm across and 5 cm high, its top seen only as the crescent (radius 3-4 cm,
    # the near half) in front of a can 7 cm across standing on it up to 12 cm, whose top
    # is whole: the crescent cannot hold the can (most of it stands beyond the crescent's
    # hull), the tin's body does, and the crescent lies outside the can
    up = lambda p: np.tile([0.0, 0.0, 1.0], (p.shape[0], 1))  # noqa: E731
    tin_side = _cylinder_near_half(0.04, 0.0, 0.05)
    crescent = _disc(0.036, 0.04, 0.05, 185.0, 355.0)
    can_side = _cylinder_near_half(0.035, 0.054, 0.12)
    can_top = _disc(0.0, 0.035, 0.12, 0.0, 360.0)
    part, out = _stack_splits([tin_side, (crescent, up(crescent)), can_side, (can_top, up(can_top))])
    tin, can = np.isin(part, [0, 1]), np.isin(part, [2, 3])
    assert np.unique(out[tin]).size == 1 and np.unique(out[can]).size == 1
    assert out[tin][0] != out[can][0]
    # a mug's floor inside its walls is no crescent outside them: the mug stays whole
    wall = _cylinder_near_half(0.04, 0.0, 0.10)
    rim = _disc(0.038, 0.04, 0.10, 180.0, 360.0)
    floor = _disc(0.0, 0.034, 0.01, 0.0, 360.0)
    _, out = _stack_splits([wall, (rim, up(rim)), (floor, up(floor))])
    assert np.unique(out).size == 1


def test_a_lying_torch_whose_head_stands_above_its_handle_stays_whole() -> None:
    # a handle 15 cm long and 3 cm high, its head a 5 cm cube at one end: the head lies
    # within the hull of everything up to the handle's top (its own lower sides) and the
    # handle's top outside the head, but reaches 10 cm beyond it, no crescent hugging it
    def face(x0: float, x1: float, y0: float, y1: float, z0: float, z1: float, normal: list[float]):
        g = [np.arange(a, b + 1e-9, STEP_M) if b > a else np.array([a]) for a, b in ((x0, x1), (y0, y1), (z0, z1))]
        p = np.stack(np.meshgrid(*g, indexing="ij"), axis=-1).reshape(-1, 3)
        return p, np.tile(normal, (p.shape[0], 1))

    handle_top = face(0.0, 0.15, 0.0, 0.03, 0.03, 0.03, [0.0, 0.0, 1.0])
    handle_side = face(0.0, 0.15, 0.0, 0.0, 0.0, 0.026, [0.0, -1.0, 0.0])
    head_side = face(0.154, 0.2, -0.01, -0.01, 0.0, 0.05, [0.0, -1.0, 0.0])
    head_end = face(0.202, 0.202, -0.006, 0.03, 0.0, 0.05, [1.0, 0.0, 0.0])  # its far end, seen too
    head_top = face(0.154, 0.2, -0.006, 0.03, 0.052, 0.052, [0.0, 0.0, 1.0])
    _, out = _stack_splits([handle_top, handle_side, head_side, head_end, head_top])
    assert np.unique(out).size == 1
