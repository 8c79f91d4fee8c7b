"""Tests of clearcli/sim/camera.py."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers.sim import clutter_scene  # noqa: F401  (fixtures)

from clearcli.io.frames import Frame
from clearcli.sim import scene as S
from clearcli.sim.camera import KINECT, DepthNoise, render
from clearcli.sim.scene import Box, Cylinder

H, W = 480, 640


EXACT = DepthNoise(enabled=False)


def table_frame_points(frame: Frame, scene: S.Scene) -> np.ndarray:
    T_table_camera = S.invert_transform(scene.T_camera_table)
    return frame.points.astype(np.float64) @ T_table_camera[:3, :3].T + T_table_camera[:3, 3]


@pytest.fixture(scope="module")
def clutter_frame(clutter_scene: S.Scene) -> Frame:
    return render(clutter_scene, seed=3)


def test_camera_pose_puts_table_origin_on_the_optical_axis() -> None:
    T = S.T_CAMERA_TABLE
    np.testing.assert_allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-12)
    assert np.linalg.det(T[:3, :3]) == pytest.approx(1.0)
    origin_camera = T[:3, 3]
    # 0.62 m above the table, pitched 42 deg: the axis meets the table 0.62/sin(42) away.
    np.testing.assert_allclose(origin_camera, [0.0, 0.0, 0.62 / math.sin(math.radians(42))], atol=1e-12)
    assert origin_camera[2] == pytest.approx(0.92657, abs=1e-5)
    # The table's up axis, seen from the camera, points against y (up in the image) and z.
    up_camera = T[:3, :3] @ np.array([0.0, 0.0, 1.0])
    np.testing.assert_allclose(up_camera, [0.0, -math.cos(math.radians(42)), -math.sin(math.radians(42))], atol=1e-12)


def table_depth_by_hand(u: int, v: int) -> float:
    """Depth of the table plane on pixel (u, v): the plane is n.p = -h with
    n = (0, -cos 42, -sin 42) in the camera frame and p = z ((u-cx)/f, (v-cy)/f, 1)."""
    pitch = math.radians(42.0)
    b = (v - 239.5) / 525.0
    return 0.62 / (math.sin(pitch) + math.cos(pitch) * b)


def test_table_centre_pixel_depth_matches_hand_computation() -> None:
    scene = S.make_scene("empty", [])
    exact = render(scene, noise=EXACT)
    noisy = render(scene, seed=1)
    for u, v in [(320, 240), (319, 239), (100, 350), (500, 200)]:
        i = v * W + u
        z_hand = table_depth_by_hand(u, v)
        assert exact.points[i, 2] == pytest.approx(z_hand, abs=1e-6)
        # Noise: sigma(0.93 m) = 1.7 mm; disparity step 2.7 mm there, so at most +-1.4 mm.
        assert noisy.points[i, 2] == pytest.approx(z_hand, abs=4 * 0.0018 + 0.0014)
    assert exact.points[240 * W + 320, 2] == pytest.approx(0.92560, abs=1e-5)  # 0.62 / (sin 42 + cos 42 * 0.5/525)
    assert exact.fields["label"][240 * W + 320] == 1


def test_points_project_back_onto_their_pixels(clutter_frame: Frame) -> None:
    finite = clutter_frame.finite_mask
    uv = KINECT.project(clutter_frame.points[finite])
    index = np.flatnonzero(finite)
    np.testing.assert_allclose(uv[:, 0], index % W, atol=1e-3)
    np.testing.assert_allclose(uv[:, 1], index // W, atol=1e-3)


def test_table_point_at_known_pixel_lies_on_the_table() -> None:
    scene = S.make_scene("empty", [])
    frame = render(scene, noise=EXACT)
    # A table point 10 cm right and 5 cm beyond the centre, projected by hand.
    p_camera = (S.T_CAMERA_TABLE @ np.array([0.10, 0.05, 0.0, 1.0]))[:3]
    u, v = KINECT.project(p_camera[None])[0]
    i = int(round(v)) * W + int(round(u))
    p_back = table_frame_points(frame, scene)[i]
    assert p_back[2] == pytest.approx(0.0, abs=1e-9)
    # Within half a pixel's footprint (< 1.5 mm at this range) of the chosen point.
    np.testing.assert_allclose(p_back[:2], [0.10, 0.05], atol=0.0025)


def test_noise_level_is_kinect_like() -> None:
    scene = S.make_scene("empty", [])
    exact = render(scene, noise=EXACT).points[:, 2]
    noisy = render(scene, seed=5).points[:, 2]
    both = np.isfinite(exact) & np.isfinite(noisy)
    err = noisy[both] - exact[both]
    z = exact[both]
    near = z < 0.8  # sigma 1.5 mm at 0.75 m, disparity step ~1.8 mm
    assert abs(err.mean()) < 2e-4
    assert 0.0012 < err[near].std() < 0.0025
    assert err.std() < 0.0035
    # Quantised: depths come in a few disparity steps, not a continuum.
    disparity_px = 525.0 * 0.075 / noisy[both]
    steps = disparity_px * 8
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-3)


def test_isolated_box_top_surface_has_true_size() -> None:
    scene = S.isolated_box()
    box = scene.objects[0]
    frame = render(scene, seed=2)
    pts = table_frame_points(frame, scene)[frame.fields["label"] == 10]
    top = pts[pts[:, 2] > box.top_z_m - 0.006]
    assert top.shape[0] > 200
    assert np.median(top[:, 2]) == pytest.approx(box.top_z_m, abs=0.003)
    c, s = math.cos(box.yaw_rad), math.sin(box.yaw_rad)
    local = (top[:, :2] - [box.x_m, box.y_m]) @ np.array([[c, -s], [s, c]])
    extent = local.max(axis=0) - local.min(axis=0)
    np.testing.assert_allclose(extent, [box.size_x_m, box.size_y_m], atol=0.01)
    np.testing.assert_allclose(np.median(local, axis=0), [0.0, 0.0], atol=0.005)


def test_labels_cover_each_visible_object(clutter_scene: S.Scene, clutter_frame: Frame) -> None:
    label = clutter_frame.fields["label"]
    assert label.dtype == np.uint32 and label.shape == (H * W,)
    values, counts = np.unique(label, return_counts=True)
    expected = {0, 1} | {10 * (k + 1) for k in range(10)}
    assert set(values.tolist()) == expected
    assert counts[values >= 10].min() > 300  # every object clearly seen
    finite = clutter_frame.finite_mask
    assert (label[~finite] == 0).all() and (label[finite] != 0).all()
    # Each object's label sits where its top is, unless a nearer object hides that pixel.
    exact = render(clutter_scene, noise=EXACT)
    for obj in clutter_scene.objects:
        top_centre = S.T_CAMERA_TABLE @ np.array([obj.x_m, obj.y_m, obj.top_z_m, 1.0])
        u, v = np.round(KINECT.project(top_centre[None, :3])[0]).astype(int)
        i = v * W + u
        lab = int(exact.fields["label"][i])
        if lab != 10 * (obj.object_id + 1):
            assert exact.points[i, 2] < top_centre[2]  # occluded by something nearer


def test_object_points_lie_on_their_object(clutter_scene: S.Scene) -> None:
    frame = render(clutter_scene, noise=EXACT)
    pts = table_frame_points(frame, clutter_scene)
    label = frame.fields["label"]
    for obj in clutter_scene.objects:
        p = pts[label == 10 * (obj.object_id + 1)]
        c, s = math.cos(obj.yaw_rad), math.sin(obj.yaw_rad)
        local = (p[:, :2] - [obj.x_m, obj.y_m]) @ np.array([[c, -s], [s, c]])
        assert (p[:, 2] >= obj.base_z_m - 1e-6).all() and (p[:, 2] <= obj.top_z_m + 1e-6).all()
        if isinstance(obj, Box):
            assert (np.abs(local[:, 0]) <= obj.size_x_m / 2 + 1e-6).all()
            assert (np.abs(local[:, 1]) <= obj.size_y_m / 2 + 1e-6).all()
        else:
            assert (np.hypot(local[:, 0], local[:, 1]) <= obj.radius_m + 1e-6).all()


def test_table_points_are_on_the_table(clutter_frame: Frame, clutter_scene: S.Scene) -> None:
    pts = table_frame_points(clutter_frame, clutter_scene)[clutter_frame.fields["label"] == 1]
    assert np.abs(pts[:, 2]).max() < 0.012  # noise + quantisation at <= 1.25 m
    assert np.abs(pts[:, 0]).max() <= 0.40 + 0.01 and np.abs(pts[:, 1]).max() <= 0.30 + 0.01


def test_touching_boxes_share_a_face() -> None:
    scene = S.two_touching_boxes()
    frame = render(scene, noise=EXACT)
    pts = table_frame_points(frame, scene)
    label = frame.fields["label"]
    a, b = pts[label == 10], pts[label == 20]
    assert a.shape[0] > 500 and b.shape[0] > 500
    assert a[:, 0].max() == pytest.approx(0.0, abs=0.002)
    assert b[:, 0].min() == pytest.approx(0.0, abs=0.002)


def test_box_on_box_upper_box_is_seen_on_top() -> None:
    scene = S.box_on_box()
    lower, upper = scene.objects
    assert upper.base_z_m == pytest.approx(lower.top_z_m)
    frame = render(scene, seed=0)
    pts = table_frame_points(frame, scene)
    label = frame.fields["label"]
    assert np.median(pts[label == 20][:, 2].max()) == pytest.approx(0.09, abs=0.004)
    assert (label == 10).sum() > 300 and (label == 20).sum() > 300


def test_cylinder_radius_from_its_points() -> None:
    scene = S.make_scene("cyl", [Cylinder(0, 0.03, 0.1, x_m=0.0, y_m=0.0)])
    frame = render(scene, noise=EXACT)
    pts = table_frame_points(frame, scene)[frame.fields["label"] == 10]
    side = pts[pts[:, 2] < 0.099]
    np.testing.assert_allclose(np.hypot(side[:, 0], side[:, 1]), 0.03, atol=1e-6)
    cap = pts[pts[:, 2] > 0.1 - 1e-6]
    assert cap.shape[0] > 300


def test_floor_option_fills_beyond_the_table() -> None:
    scene = S.make_scene("empty", [])
    without = render(scene, noise=EXACT)
    with_floor = render(scene, noise=EXACT, floor=True)
    assert with_floor.finite_mask.sum() > without.finite_mask.sum()
    corner = 10 * W + 10  # top-left: past the table, on the floor
    assert not without.finite_mask[corner]
    assert with_floor.finite_mask[corner] and with_floor.fields["label"][corner] == 0
    z_table = table_frame_points(with_floor, scene)[corner, 2]
    assert z_table == pytest.approx(-0.75, abs=1e-6)


def test_frame_metadata(clutter_frame: Frame) -> None:
    assert clutter_frame.points.dtype == np.float32 and clutter_frame.points.shape == (H * W, 3)
    assert clutter_frame.colors is not None and clutter_frame.colors.dtype == np.uint8
    assert clutter_frame.shape == (H, W)
    assert clutter_frame.frame_id == "camera_rgb_optical_frame"
    assert clutter_frame.source == "sim:clutter(10, seed=3)"
    table_rgb = clutter_frame.colors[clutter_frame.fields["label"] == 1]
    assert (table_rgb[:, 0] == table_rgb[:, 1]).all()  # grey
    # Dropouts exist, but are rare: only behind depth edges.
    dropped = (~clutter_frame.finite_mask) & (render(S.clutter(10, seed=3), noise=EXACT).finite_mask)
    assert 0 < dropped.sum() < 0.02 * clutter_frame.finite_mask.sum()


def test_same_seed_same_frame(clutter_scene: S.Scene, clutter_frame: Frame) -> None:
    assert S.clutter(10, seed=3) == clutter_scene
    assert S.clutter(10, seed=4) != clutter_scene
    again = render(S.clutter(10, seed=3), seed=3)
    np.testing.assert_array_equal(again.points, clutter_frame.points)
    np.testing.assert_array_equal(again.fields["label"], clutter_frame.fields["label"])
    np.testing.assert_array_equal(again.colors, clutter_frame.colors)
    other = render(clutter_scene, seed=4)
    assert not np.array_equal(other.points, clutter_frame.points, equal_nan=True)
