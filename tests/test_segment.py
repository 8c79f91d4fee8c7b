"""The segment stage: each step on self-made scenes with known answers, then real frames."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from clearcli.errors import SceneError
from clearcli.evaluate.segmentation import score
from clearcli.io.frames import Frame
from clearcli.settings.segment import SegmentSettings
from utils import shared_path

S = SegmentSettings()


def _render(scene, floor: bool = False) -> Frame:  # type: ignore[no-untyped-def]
    from clearcli.sim.camera import render

    return render(scene, seed=0, floor=floor)


@pytest.fixture(scope="module")
def box_frame() -> Frame:
    from clearcli.sim.scene import isolated_box

    return _render(isolated_box())


# ------------------------------------------------------------------ 1. outliers
def test_depth_radius_keeps_far_surfaces_and_drops_flying_pixels() -> None:
    from clearcli.perception.filters import depth_radius_mask, statistical_mask

    # an organized Kinect view (f = 525 px) of a table 0.6 m below the camera, looking
    # down 37 degrees: the table reaches from 0.6 m to several metres; one pixel moved
    # 20 cm towards the camera (a flying pixel)
    h, w, f = 480, 640, 525.0
    v, u = np.mgrid[0:h, 0:w]
    rays = np.stack([(u - 319.5) / f, (v - 239.5) / f, np.ones((h, w))], axis=-1).reshape(-1, 3)
    n = np.array([0.0, -np.cos(np.radians(37)), -np.sin(np.radians(37))])
    t = -0.6 / (rays @ n)
    pts = np.where((t > 0)[:, None], rays * t[:, None], np.nan).astype(np.float32)
    pts[np.linalg.norm(pts, axis=1) > 4.0] = np.nan
    fly = 400 * w + 320
    pts[fly] *= 0.8
    pts[fly + 1] = np.nan
    keep = depth_radius_mask(pts, (h, w), 0.01, 2)
    finite = np.isfinite(pts).all(axis=1)
    assert not keep[fly] and not keep[fly + 1]
    assert keep.sum() >= finite.sum() - 3  # every surface point stays, near and far
    assert np.linalg.norm(pts[keep], axis=1).max() > 3.0
    # the same without the pixel grid (KD-tree path)
    sub = np.zeros_like(finite)
    sub[::7] = True
    sub[fly] = True
    keep_u = depth_radius_mask(np.where(sub[:, None], pts, np.nan), None, 0.02, 2)
    assert not keep_u[fly] and keep_u.sum() >= (finite & sub).sum() - 3
    # the original statistical filter (fixed k) loses the far, sparse points
    stat = statistical_mask(pts, 10, 1.0)
    far = finite & (np.linalg.norm(pts, axis=1) > 2.5)
    assert stat[far].mean() < 0.5 < keep[far].mean()


# ------------------------------------------------------------------ 2. table
def test_table_is_the_support_not_the_floor() -> None:
    from clearcli.perception.filters import clean_mask
    from clearcli.perception.table import find_table, table_and_prism
    from clearcli.sim.scene import isolated_box

    scene = isolated_box()
    frame = _render(scene, floor=True)
    T = scene.T_camera_table
    up = T[:3, 2]  # the table's z axis in the camera frame
    pts = frame.points[clean_mask(frame.points, frame.shape, S)].astype(np.float64)
    fit = find_table(pts, S, organized=True)
    assert np.dot(fit.plane.normal, up) > 0.999
    # the camera is 0.62 m above the table (sim placement)
    assert fit.plane.offset == pytest.approx(-(up @ T[:3, 3]), abs=0.005)
    table, prism, h = table_and_prism(pts, fit, S)
    assert table.sum() > 50_000
    assert np.all(h[prism] >= S.prism_min_height_m)


def test_empty_table_is_zero_objects() -> None:
    from clearcli.perception.segment import segment
    from clearcli.sim.scene import make_scene

    seg = segment(_render(make_scene("empty", [])), S)
    assert seg.objects == ()
    assert seg.table_indices.size > 50_000
    assert seg.table_polygon.shape[0] >= 4
    # the hull lies on the plane
    assert np.abs(seg.table.height_of(seg.table_polygon)).max() < 1e-9


def test_bad_scenes_raise_scene_error(box_frame: Frame) -> None:
    from clearcli.perception.segment import segment

    nan = Frame(points=np.full((480 * 640, 3), np.nan, np.float32), shape=(480, 640), source="nan.pcd")
    with pytest.raises(SceneError, match="no finite points"):
        segment(nan, S)
    few = Frame(points=np.random.default_rng(0).normal(size=(50, 3)).astype(np.float32) + [0, 0, 1])
    with pytest.raises(SceneError, match="no table"):
        segment(few, S)
    # a cloud of scattered points: no plane of table size
    blob = Frame(points=np.random.default_rng(1).normal(scale=0.3, size=(20_000, 3)).astype(np.float32) + [0, 0, 2])
    with pytest.raises(SceneError, match="no table"):
        segment(blob, S)


def test_table_seen_from_below_is_a_scene_error(box_frame: Frame) -> None:
    from clearcli.perception.segment import segment

    seg = segment(box_frame, S)
    # mirror the box through the table plane: it now stands on the far side of the
    # table from the camera, which is what a camera below the table would see
    p = box_frame.points.astype(np.float64)
    h = seg.table.height_of(p)
    mirrored = np.where((h > 0.005)[:, None], p - 2 * h[:, None] * seg.table.normal, p).astype(np.float32)
    with pytest.raises(SceneError, match="seen from below"):
        segment(replace(box_frame, points=mirrored), S)
    # an upside-down image (rows flipped): the table's top faces down the image
    flipped = box_frame.points.reshape(480, 640, 3)[::-1].reshape(-1, 3) * np.array([1, -1, 1], np.float32)
    with pytest.raises(SceneError, match="seen from below"):
        segment(replace(box_frame, points=np.ascontiguousarray(flipped)), S)


# ------------------------------------------------------------------ 3. supervoxels + LCCP
def _fold(sign: float) -> np.ndarray:
    """A 20 x 20 cm sheet folded along y at x = 0, seen from the origin: sign +1 a ridge
    towards the camera (convex), -1 a valley (concave). 1.5 mm sampling."""
    x, y = np.meshgrid(np.arange(-0.1, 0.1, 0.0015), np.arange(-0.1, 0.1, 0.0015))
    z = 0.8 + sign * 0.8 * np.abs(x)
    return np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)


@pytest.mark.parametrize("sign, n_segments", [(1.0, 1), (-1.0, 2)])
def test_lccp_joins_convex_and_cuts_concave(sign: float, n_segments: int) -> None:
    from clearcli.perception.lccp import lccp_segments
    from clearcli.perception.supervoxels import compute_supervoxels, voxelize

    vox = voxelize(_fold(sign), S.voxel_m)
    # the 26-neighbourhood on a regular grid: interior voxels have neighbours
    assert vox.edges.shape[0] > vox.n_voxels
    sv = compute_supervoxels(vox, np.zeros(3), S)
    # about one supervoxel per seed cell of the (tilted) sheet
    assert 50 <= sv.centroids.shape[0] <= 300
    assert np.all(np.einsum("ij,ij->i", sv.normals, -sv.centroids) > 0)  # facing the camera
    seg = lccp_segments(sv, S)
    assert int(seg.max()) + 1 == n_segments
    if n_segments == 2:  # the cut is the fold
        xs = sv.centroids[:, 0]
        far = np.abs(xs) > 0.02
        assert len(set(zip((xs[far] > 0).tolist(), seg[far].tolist()))) == 2


def test_voxel_adjacency_is_the_26_neighbourhood() -> None:
    from clearcli.perception.supervoxels import voxelize

    g = np.stack(np.meshgrid(*[np.arange(3)] * 3, indexing="ij"), -1).reshape(-1, 3) * 0.01 + 0.005
    vox = voxelize(g, 0.01)
    assert vox.n_voxels == 27
    # pairs of a 3x3x3 block at Chebyshev distance 1: (27*26 - non-adjacent) / 2
    d = np.abs(vox.keys[:, None, :] - vox.keys[None, :, :]).max(-1)
    assert vox.edges.shape[0] == int((d == 1).sum()) // 2


def _two_box_patches(with_lower_box: bool):  # type: ignore[no-untyped-def]
    """Hand-made supervoxels (table frame, z up, camera at -y) of a 6 cm wide, 10 cm tall
    box A (front face y = -0.025, top z = 0.1) and, touching its right side, a 4 cm wide,
    6 cm tall box B with its front face in A's front plane. Each patch: 5 x 5 voxels
    6 mm apart in its face. Returns (names, Supervoxels, voxel centroids)."""
    from clearcli.perception.supervoxels import Supervoxels

    front, top = np.array([0.0, -1.0, 0.0]), np.array([0.0, 0.0, 1.0])
    patches: dict[str, tuple[tuple[float, float, float], np.ndarray]] = {}
    for i, x in enumerate((-0.045, -0.015)):
        for k, z in enumerate((0.02, 0.05, 0.08)):
            patches[f"af{i}{k}"] = ((x, -0.025, z), front)
        for j, y in enumerate((-0.01, 0.015)):
            patches[f"at{i}{j}"] = ((x, y, 0.1), top)
    if with_lower_box:
        for i, x in enumerate((0.01, 0.03)):
            for k, z in enumerate((0.02, 0.045)):
                patches[f"bf{i}{k}"] = ((x, -0.025, z), front)
            for j, y in enumerate((-0.01, 0.015, 0.035)):
                patches[f"bt{i}{j}"] = ((x, y, 0.06), top)
    names = list(patches)
    cent = np.array([patches[n][0] for n in names])
    nor = np.array([patches[n][1] for n in names])
    grid = np.arange(-2, 3) * 0.006
    u, v = [a.ravel() for a in np.meshgrid(grid, grid)]
    voxels, labels = [], []
    for s, (c, n) in enumerate(zip(cent, nor)):
        # in-face axes: x and the face's other axis
        other = np.array([0.0, 0.0, 1.0]) if n[2] == 0 else np.array([0.0, 1.0, 0.0])
        voxels.append(c + u[:, None] * np.array([1.0, 0.0, 0.0]) + v[:, None] * other)
        labels.append(np.full(u.size, s))
    # adjacent: centroids closer than ~1.4 seed spacings (a patch's 8 neighbours)
    d = np.linalg.norm(cent[:, None] - cent[None], axis=-1)
    a, b = np.nonzero(np.triu(d < 0.042, 1))
    sv = Supervoxels(np.concatenate(labels), cent, nor, np.full(len(names), u.size), np.stack([a, b], axis=1))
    return names, sv, np.concatenate(voxels)


@pytest.mark.parametrize("with_lower_box", [True, False])
def test_planar_cut_splits_coplanar_touching_boxes(with_lower_box: bool) -> None:
    from clearcli.perception.cuts import concave_adjacencies, planar_cuts, seam_rise
    from clearcli.perception.lccp import lccp_segments

    names, sv, voxels = _two_box_patches(with_lower_box)
    seg = lccp_segments(sv, S)
    # LCCP alone: one segment, joined through the coplanar front faces
    assert int(seg.max()) == 0
    up = np.array([0.0, 0.0, 1.0])
    out = planar_cuts(seg, sv, voxels, up, S)
    if not with_lower_box:  # a lone box has only the odd edge adjacencies: no cut
        assert int(out.max()) == 0
        return
    # the seam A's front (its patch above B's top) - B's top: A's patch rises 32 mm out of
    # B's top plane (0.08 + 0.012 - 0.06); the patch beside it reaches 2 mm
    e = [tuple(p) for p in sv.edges.tolist()]
    seam = e.index((names.index("af12"), names.index("bt00")))
    low = e.index((names.index("af11"), names.index("bt00")))
    assert concave_adjacencies(sv, S)[[seam, low]].all()
    rise = seam_rise(sv, voxels, sv.edges[[seam, low]])
    assert rise == pytest.approx([0.032, 0.002], abs=1e-9)
    # the cut is the plane between the boxes: A's patches one side, B's the other
    box_b = np.array([n.startswith("b") for n in names])
    assert int(out.max()) == 1
    assert len(set(out[box_b].tolist())) == 1 and len(set(out[~box_b].tolist())) == 1
    assert out[box_b][0] != out[~box_b][0]
    # off: untouched
    assert np.array_equal(planar_cuts(seg, sv, voxels, up, replace(S, cut_min_score=0.9)), seg)


def _column(x: float, z_lo: float, z_hi: float) -> np.ndarray:
    """Voxel centroids of a 4 cm wide vertical strip at x (table frame: z up), 5 mm grid."""
    z = np.arange(z_lo, z_hi + 1e-9, 0.005)
    y = np.arange(0.0, 0.04 + 1e-9, 0.005)
    zz, yy = np.meshgrid(z, y)
    return np.stack([np.full(zz.size, x), yy.ravel(), zz.ravel()], axis=1)


def _slope(x0: float, x1: float, z0: float, dz_dx: float) -> np.ndarray:
    """Voxel centroids of a 4 cm wide strip from x0 to x1, z = z0 + dz_dx (x - x0)."""
    x = np.arange(x0, x1 + 1e-9, 0.005)
    y = np.arange(0.0, 0.04 + 1e-9, 0.005)
    xx, yy = np.meshgrid(x, y)
    return np.stack([xx.ravel(), yy.ravel(), z0 + dz_dx * (xx.ravel() - x0)], axis=1)


@pytest.mark.parametrize(
    "shape, joined",
    [
        ("rim", True),  # an inner wall going down away from A's top: a container's rim
        ("on_top", False),  # stands on A: touches A's top with its bottom
        ("beside", False),  # side by side: touches all the way down
    ],
)
def test_rim_merge(shape: str, joined: bool) -> None:
    from clearcli.perception.rims import merge_rims

    a = _column(0.0, 0.0, 0.10)
    b = {
        "rim": _slope(0.015, 0.06, 0.10, -1.0),
        "on_top": _column(0.015, 0.10, 0.14),
        "beside": _column(0.015, 0.0, 0.10),
    }[shape]
    cent = np.vstack([a, b])
    seg = np.r_[np.zeros(len(a), np.int64), np.ones(len(b), np.int64)]
    out = merge_rims(seg, cent, cent[:, 2], tolerance_m=0.015, contact_m=0.02)
    assert (int(out.max()) + 1 == 1) == joined


def _flat(x0: float, x1: float, z: float) -> np.ndarray:
    """Voxel centroids of a horizontal 4 cm wide strip from x0 to x1 at height z."""
    return _slope(x0, x1, z, 0.0)


def test_rim_merge_keeps_touching_tops_apart() -> None:
    """Two tall boxes 1 cm apart whose lower parts hide each other: the camera sees two
    tops whose edges come within the contact distance, near the top of both. Without the
    top-face test that looks like a rim; with it, it is not one."""
    from clearcli.perception.rims import merge_rims

    a, b = _flat(0.0, 0.04, 0.10), _flat(0.05, 0.09, 0.095)
    cent = np.vstack([a, b])
    seg = np.r_[np.zeros(len(a), np.int64), np.ones(len(b), np.int64)]
    joined = merge_rims(seg, cent, cent[:, 2], tolerance_m=0.015, contact_m=0.02)
    assert int(joined.max()) == 0
    kept = merge_rims(seg, cent, cent[:, 2], 0.015, 0.02, voxel_is_top=np.ones(len(cent), bool))
    assert int(kept.max()) == 1
    # a rim's walls are not top faces: still joined
    outer, inner = _column(0.0, 0.0, 0.10), _slope(0.015, 0.06, 0.10, -1.0)
    rim = np.vstack([outer, inner])
    rim_seg = np.r_[np.zeros(len(outer), np.int64), np.ones(len(inner), np.int64)]
    assert int(merge_rims(rim_seg, rim, rim[:, 2], 0.015, 0.02, voxel_is_top=np.zeros(len(rim), bool)).max()) == 0


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


def test_occlusion_merge_on_a_real_occluded_frame() -> None:
    """learn28: a tall box in front cuts the box behind it in two; LCCP alone gives
    three segments, the occlusion merge two."""
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment

    frame = read_frame(shared_path("mosd/learn/learn28.pcd"))
    off = score(segment(frame, replace(S, occlusion_merge=False)).labels(), frame.fields["label"])
    on = score(segment(frame, S).labels(), frame.fields["label"])
    assert (off.n_pred, off.over_segmented) == (3, 1)
    assert (on.n_pred, on.true_positives, on.f1) == (2, 2, 1.0)


# ------------------------------------------------------------------ 4. whole stage, synthetic
def test_isolated_box_one_object_true_size(box_frame: Frame) -> None:
    from clearcli.perception.segment import segment

    seg = segment(box_frame, S)
    assert len(seg.objects) == 1
    obj = seg.objects[0]
    assert obj.obb_extents == pytest.approx([0.05, 0.04, 0.08], abs=0.01)
    # the box axes: third along the table normal, first along the 5 cm side (30 deg yaw)
    assert np.allclose(obj.obb_axes[2], seg.table.normal)
    assert np.allclose(obj.obb_axes @ obj.obb_axes.T, np.eye(3), atol=1e-9)
    assert np.linalg.det(obj.principal_axes) == pytest.approx(1.0)
    # the bottom of the box is on the table, its top 8 cm above
    bottom = seg.table.height_of(obj.obb_center) - obj.obb_extents[2] / 2
    assert bottom == pytest.approx(0.0, abs=1e-9)
    assert score(seg.labels(), box_frame.fields["label"]).f1 == 1.0
    assert set(seg.timings_s) >= {"filter", "table", "supervoxels", "lccp", "total"}
    # indices point into the original frame (NaN rows kept in place)
    assert np.isfinite(box_frame.points[obj.indices]).all()


def test_two_touching_boxes_are_two() -> None:
    from clearcli.perception.segment import segment
    from clearcli.sim.scene import Box, make_scene

    # in contact along x; the smaller one set back 1.5 cm, so no face is shared in a
    # plane: LCCP alone separates them
    a = Box(0, 0.06, 0.05, 0.10, x_m=-0.03, y_m=0.0)
    b = Box(1, 0.04, 0.07, 0.06, x_m=0.02, y_m=0.025)
    frame = _render(make_scene("touching", [a, b]))
    seg = segment(frame, S)
    sc = score(seg.labels(), frame.fields["label"])
    assert (sc.n_pred, sc.true_positives) == (2, 2)
    assert min(sc.matched_iou) > 0.8


@pytest.mark.parametrize("seed", [0, 3, 5, "fixture"])
def test_touching_boxes_with_coplanar_fronts_are_two(seed: int | str) -> None:
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment
    from clearcli.sim.camera import render
    from clearcli.sim.scene import two_touching_boxes

    # front faces in one plane: LCCP joins the boxes through it, the planar cut at the
    # seam of the lower box's top and the taller box's front separates them (on by
    # default, see SegmentSettings.planar_cuts)
    if seed == "fixture":
        frame = read_frame(Path(__file__).resolve().parent.parent / "fixtures" / "two_touching_boxes.pcd")
    else:
        frame = render(two_touching_boxes(), seed=int(seed))
    sc = score(segment(frame, S).labels(), frame.fields["label"])
    assert (sc.n_pred, sc.true_positives) == (2, 2)
    assert min(sc.matched_iou) > 0.8
    if seed == 0:  # and without the cut, LCCP's blind spot
        off = score(segment(frame, replace(S, planar_cuts=False, step_split=False)).labels(), frame.fields["label"])
        assert off.n_pred == 1


def test_box_on_box_is_two() -> None:
    """The box on a box, on several noise seeds and as the committed fixture (one
    render per test hid that the fixture came out as one object)."""
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment
    from clearcli.sim.camera import render
    from clearcli.sim.scene import box_on_box
    from utils import FIXTURES

    frames = [render(box_on_box(), seed=seed) for seed in range(5)] + [read_frame(FIXTURES / "box_on_box.pcd")]
    for frame in frames:
        seg = segment(frame, S)
        sc = score(seg.labels(), frame.fields["label"])
        assert (sc.n_pred, sc.true_positives) == (2, 2), frame.source
        upper = min(seg.objects, key=lambda o: o.n_points)
        assert seg.table.height_of(upper.obb_center) > 0.06  # it stands on the lower box


def test_unorganized_and_table_frame_clouds(box_frame: Frame) -> None:
    from clearcli.perception.segment import segment

    finite = box_frame.finite_mask
    pts = box_frame.points[finite]
    flat = Frame(points=pts, shape=None)
    seg = segment(flat, S)
    assert len(seg.objects) == 1
    assert seg.objects[0].obb_extents == pytest.approx([0.05, 0.04, 0.08], abs=0.01)
    # the same cloud moved into the table's frame (z up, origin on the table): no camera
    ref = segment(box_frame, S)
    n = ref.table.normal
    x = np.cross([0.0, 0.0, 1.0], n)
    x /= np.linalg.norm(x)
    R = np.stack([x, np.cross(n, x), n])  # rows: table axes in the camera frame
    origin = -ref.table.offset * n
    up = ((pts.astype(np.float64) - origin) @ R.T).astype(np.float32)
    seg_up = segment(Frame(points=up), S)
    assert len(seg_up.objects) == 1
    assert seg_up.table.normal[2] > 0.999
    assert seg_up.objects[0].obb_extents == pytest.approx([0.05, 0.04, 0.08], abs=0.01)


def test_settings_are_used() -> None:
    from clearcli.perception.segment import segment
    from clearcli.sim.scene import isolated_box

    frame = _render(isolated_box())
    # an object smaller than the minimum area is dropped
    assert segment(frame, replace(S, min_object_area_m2=0.05)).objects == ()
    with pytest.raises(Exception, match="outlier_method"):
        segment(frame, replace(S, outlier_method="bogus"))


# ------------------------------------------------------------------ real frames
@pytest.mark.parametrize(
    "name, floor",
    [("mosd/learn/learn3.pcd", 0.99), ("mosd/learn/learn21.pcd", 0.99), ("mosd/test/test55.pcd", 0.9)],
)
def test_mosd_frames_score(name: str, floor: float) -> None:
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment

    frame = read_frame(shared_path(name))
    seg = segment(frame, S)
    sc = score(seg.labels(), frame.fields["label"])
    assert sc.f1 >= floor, sc
    # the table: normal up (towards the camera), about 0.6 m below it
    assert 0.5 < seg.table.offset < 0.75


def test_mosd_cylindrical_category_keeps_containers_whole() -> None:
    """mOSD's cylindrical frames (bowls, mugs, pots; learn33-44): mean F1 >= 0.93 (the
    issue's target; 0.857 before the rings stage). The six where a container's inner
    and outer walls came apart are here; without the rings stage they fall below."""
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment

    frames = [read_frame(shared_path(f"mosd/learn/learn{i}.pcd")) for i in range(33, 39)]
    on = [score(segment(f, S).labels(), f.fields["label"]).f1 for f in frames]
    off = [score(segment(f, replace(S, ring_merge=False)).labels(), f.fields["label"]).f1 for f in frames]
    assert np.mean(on) >= 0.93, on
    assert np.mean(off) < 0.8, off


# ------------------------------------------------------------------ CLI
def test_cli_segment_json_labels_png_and_evaluate(tmp_path, box_frame: Frame) -> None:  # type: ignore[no-untyped-def]
    from typer.testing import CliRunner

    from clearcli.cli import app
    from clearcli.io.pcd import write_pcd
    from clearcli.io.read import read_frame

    src = tmp_path / "box.pcd"
    write_pcd(src, box_frame)  # keeps the ground-truth labels as `label`
    out = tmp_path / "labels.pcd"
    png = tmp_path / "seg.png"
    runner = CliRunner()
    res = runner.invoke(app, ["segment", str(src), "--json", "-o", str(out), "--png", str(png)])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout.strip().splitlines()[-1])
    assert doc["schema"] == "clear.segmentation" and doc["version"] == 1
    assert len(doc["objects"]) == 1
    o = doc["objects"][0]
    assert (o["id"], o["label"]) == (0, 10)
    assert sorted(o["obb"]["extents"][:2]) == pytest.approx([0.04, 0.05], abs=0.01)
    assert len(doc["table"]["normal"]) == 3 and len(doc["table"]["polygon"]) >= 3
    assert png.stat().st_size > 10_000
    written = read_frame(out)
    assert written.shape == box_frame.shape
    assert set(np.unique(written.fields["label"]).tolist()) == {0, 1, 10}
    # scoring the written labels against the truth
    res = runner.invoke(app, ["evaluate", "segmentation", str(out), str(src), "--json"])
    assert res.exit_code == 0, res.output
    ev = json.loads(res.stdout.strip().splitlines()[-1])
    assert ev["f1"] == 1.0 and ev["n_true"] == 1
    # settings flags override
    res = runner.invoke(app, ["segment", str(src), "--json", "--min-object-area-m2", "0.05"])
    assert res.exit_code == 0 and json.loads(res.stdout.strip().splitlines()[-1])["objects"] == []


def _clear(*args: str) -> subprocess.CompletedProcess[str]:
    """The installed entry point, as a user runs it (exit codes, stderr)."""
    exe = Path(sys.executable).parent / "clear"
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "clearcli.cli"]
    return subprocess.run([*cmd, *args], capture_output=True, text=True, timeout=120)


def test_cli_segment_errors_exit_codes(tmp_path, box_frame: Frame) -> None:  # type: ignore[no-untyped-def]
    from clearcli.io.pcd import write_pcd

    src = tmp_path / "nan.pcd"
    write_pcd(src, Frame(points=np.full((480 * 640, 3), np.nan, np.float32), shape=(480, 640)))
    res = _clear("segment", str(src))
    assert res.returncode == 4, res.stderr
    assert "Traceback" not in res.stderr and "no finite points" in res.stderr
    box = tmp_path / "box.pcd"
    write_pcd(box, box_frame)
    out = tmp_path / "l.pcd"
    out.write_bytes(b"x")
    res = _clear("segment", str(box), "-o", str(out))
    assert res.returncode == 8 and out.read_bytes() == b"x"


def test_refinement_stages_run_from_one_list() -> None:
    """The refinements after LCCP are one list, in order, one signature each; a stage that
    needs the pixel grid is skipped on an unorganized cloud, so the result there equals
    the result with that stage off."""
    from clearcli.io.read import read_frame
    from clearcli.perception.refine import STAGES
    from clearcli.perception.segment import segment
    from utils import FIXTURES

    assert [s.name for s in STAGES] == ["stacks", "cuts", "occlusion", "steps", "rims", "rings", "fragments"]
    assert [s.name for s in STAGES if s.needs_grid] == ["occlusion"]
    frame = read_frame(FIXTURES / "clutter10.pcd")
    seg = segment(frame, SegmentSettings())
    assert {"cuts", "occlusion", "steps", "rims", "merge"} <= set(seg.timings_s)
    finite = np.isfinite(frame.points).all(axis=1)
    flat = Frame(points=frame.points[finite], colors=None if frame.colors is None else frame.colors[finite],
                 shape=None, fields={}, source="unorganized")
    on = segment(flat, SegmentSettings(occlusion_merge=True)).labels()
    off = segment(flat, SegmentSettings(occlusion_merge=False)).labels()
    assert np.array_equal(on, off) and len(np.unique(on[on >= 10])) >= 5
    # every stage off: LCCP's segments as they come
    bare = SegmentSettings(planar_cuts=False, occlusion_merge=False, step_split=False, rim_merge=False)
    assert segment(frame, bare).objects
