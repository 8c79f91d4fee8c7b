"""Tests of clearcli/io/intrinsics.py."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from helpers import shared_path

from clearcli.errors import EXIT_INPUT, InputError
from clearcli.io.intrinsics import CameraModel, back_project, from_camera_info, read_intrinsics

# The UOIS RealSense intrinsics (../shared/data/rgbd/uois/camera_params.json).
FX, FY, CX, CY = 612.937, 613.173, 322.549, 248.158
K_ROW_MAJOR = [FX, 0.0, CX, 0.0, FY, CY, 0.0, 0.0, 1.0]
PLUMB_BOB = (-0.28, 0.07, 1e-3, -5e-4, 0.0)  # a RealSense/Kinect-like lens
# An Azure Kinect colour camera's rational_polynomial calibration (k1 k2 p1 p2 k3 k4 k5 k6).
RATIONAL = (0.5169, -2.6588, 4e-4, -1e-4, 1.5262, 0.3940, -2.4863, 1.4511)


def _assert_uois(model: CameraModel) -> None:
    assert (model.fx, model.fy, model.cx, model.cy) == (FX, FY, CX, CY)
    assert (model.width, model.height) == (640, 480)
    assert not model.distorted and model.binning_x == model.binning_y == 1 and model.roi is None


def _bad(spec: str | Path, *fragments: str) -> str:
    with pytest.raises(InputError) as e:
        read_intrinsics(spec)
    message = str(e.value)
    assert e.value.exit_code == EXIT_INPUT and "\n" not in message
    for fragment in fragments:
        assert fragment in message, message
    return message


def _write(tmp_path: Path, name: str, content: object) -> Path:
    path = tmp_path / name
    path.write_text(content if isinstance(content, str) else json.dumps(content))
    return path


def _forward(x: np.ndarray, y: np.ndarray, c: tuple[float, ...]) -> tuple[np.ndarray, np.ndarray]:
    """The ROS/OpenCV distortion model, written out independently of the module."""
    k1, k2, p1, p2, k3, k4, k5, k6 = (list(c) + [0.0] * 8)[:8]
    r2 = x * x + y * y
    radial = (1 + k1 * r2 + k2 * r2**2 + k3 * r2**3) / (1 + k4 * r2 + k5 * r2**2 + k6 * r2**3)
    return (
        x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
        y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y,
    )


# --- reading -------------------------------------------------------------------------------


def test_ros_calibration_yaml() -> None:
    model = read_intrinsics(shared_path("rgbd/uois/camera_info.yaml"))
    _assert_uois(model)
    assert model.distortion_model == "plumb_bob" and model.distortion == (0.0,) * 5
    assert model.source.endswith("camera_info.yaml")


def test_uois_camera_params_json() -> None:
    _assert_uois(read_intrinsics(str(shared_path("rgbd/uois/camera_params.json"))))


def test_open3d_json_is_column_major(tmp_path: Path) -> None:
    column_major = [FX, 0.0, 0.0, 0.0, FY, 0.0, CX, CY, 1.0]
    path = _write(tmp_path, "intrinsic.json", {"width": 640, "height": 480, "intrinsic_matrix": column_major})
    _assert_uois(read_intrinsics(path))
    # The same matrix given row-major is caught by its last row, not read as fx, fy, 0, 0.
    path = _write(tmp_path, "wrong.json", {"width": 640, "height": 480, "intrinsic_matrix": K_ROW_MAJOR})
    _bad(path, "wrong.json", "not a column-major camera matrix")


def test_camera_info_dumped_as_yaml_and_json(tmp_path: Path) -> None:
    ros1 = (
        "header:\n  seq: 1\n  frame_id: camera_color_optical_frame\nheight: 480\nwidth: 640\n"
        "distortion_model: plumb_bob\nD: [0.0, 0.0, 0.0, 0.0, 0.0]\n"
        f"K: {K_ROW_MAJOR}\nR: [1, 0, 0, 0, 1, 0, 0, 0, 1]\nbinning_x: 0\nbinning_y: 0\n"
        "roi:\n  x_offset: 0\n  y_offset: 0\n  height: 0\n  width: 0\n  do_rectify: false\n"
    )
    _assert_uois(read_intrinsics(_write(tmp_path, "info.yaml", ros1)))
    ros2 = {"height": 480, "width": 640, "distortion_model": "plumb_bob", "d": list(PLUMB_BOB), "k": K_ROW_MAJOR}
    model = read_intrinsics(_write(tmp_path, "info.json", ros2))
    assert (model.fx, model.fy, model.cx, model.cy, model.width, model.height) == (FX, FY, CX, CY, 640, 480)
    assert model.distortion == PLUMB_BOB and model.distorted


def test_four_numbers_string() -> None:
    for text in (f"{FX} {FY} {CX} {CY}", f"{FX},{FY}, {CX} ,{CY}"):
        model = read_intrinsics(text)
        assert (model.fx, model.fy, model.cx, model.cy) == (FX, FY, CX, CY)
        assert model.width is None and model.height is None and not model.distorted
        model.check_size(1280, 720, "the depth image")  # size unknown: any image is accepted


def test_from_camera_info_roi_and_binning() -> None:
    model = from_camera_info(640, 480, K_ROW_MAJOR, [], "", 2, 0, (100, 50, 200, 300, False), "/cam/info")
    assert model.roi == (100, 50, 300, 200)  # (x, y, width, height), from the message's (x, y, height, width)
    assert (model.binning_x, model.binning_y) == (2, 1)
    assert from_camera_info(640, 480, K_ROW_MAJOR, [], "", roi=(0, 0, 0, 0, False)).roi is None


# --- bad input -----------------------------------------------------------------------------


def test_bad_values_name_file_and_value(tmp_path: Path) -> None:
    good = {"img_width": 640, "img_height": 480, "fx": FX, "fy": FY, "x_offset": CX, "y_offset": CY}
    _bad(_write(tmp_path, "zero.json", {**good, "fx": 0}), "zero.json: fx = 0 (must be a positive finite number)")
    _bad(
        _write(tmp_path, "nan.json", {**good, "y_offset": float("nan")}), "nan.json: cy = nan (must be a finite number)"
    )
    _bad(_write(tmp_path, "text.json", {**good, "fy": "big"}), "text.json: fy = 'big' is not a number")
    _bad(_write(tmp_path, "width.json", {**good, "img_width": -640}), "width.json: width = -640", "positive whole")
    missing = {k: v for k, v in good.items() if k != "img_height"}
    _bad(_write(tmp_path, "missing.json", missing), "missing.json: missing key 'img_height'")
    yaml_text = shared_path("rgbd/uois/camera_info.yaml").read_text().replace("612.937, 0.0", "0, 0.0", 1)
    _bad(
        _write(tmp_path, "camera.yaml", yaml_text),
        "camera.yaml: fx = 0.0 (must be a positive finite number); fix the camera matrix",
    )
    no_matrix = "image_width: 640\nimage_height: 480\ncamera_matrix:\n  rows: 3\n"
    _bad(_write(tmp_path, "nodata.yaml", no_matrix), "nodata.yaml: missing key 'data'")


def test_bad_files_and_strings(tmp_path: Path) -> None:
    _bad(
        _write(tmp_path, "other.json", {"focal": 600, "centre": [320, 240]}),
        "other.json: unknown intrinsics layout",
        "centre, focal",
        "Open3D",
        "UOIS",
        "ROS camera calibration",
        "CameraInfo",
    )
    _bad(tmp_path / "absent.yaml", "absent.yaml: no such file")
    _bad(str(tmp_path / "absent.yaml"), "absent.yaml: no such file, and not four numbers")
    _bad("600 600 320", '"fx fy cx cy"')
    _bad("fx=600 fy=600 cx=320 cy=240", "not four numbers")
    _bad("", "not four numbers")
    _bad("0 600 320 240", '"0 600 320 240": fx = 0.0 (must be a positive finite number)')
    _bad(tmp_path, "is a folder")
    _bad(_write(tmp_path, "broken.yaml", "camera_matrix: [1, 2\n"), "broken.yaml: not valid YAML")
    _bad(_write(tmp_path, "broken.json", '{"fx": 1,'), "broken.json: not valid JSON")
    _bad(_write(tmp_path, "list.yaml", "- 1\n- 2\n"), "list.yaml: holds no mapping")
    _bad(_write(tmp_path, "empty.yaml", ""), "empty.yaml: is empty")
    (tmp_path / "binary.yaml").write_bytes(b"\xff\xfe\x00\x81")
    _bad(tmp_path / "binary.yaml", "binary.yaml: cannot be read as text")


def test_camera_info_errors() -> None:
    with pytest.raises(InputError, match=r"^camera info on /cam/info has no intrinsics \(K is all zero\)"):
        from_camera_info(640, 480, [0.0] * 9, [], "", source="/cam/info")
    with pytest.raises(InputError, match=r"^camera info on /cam/info: K has 4 numbers, not 9"):
        from_camera_info(640, 480, [1.0, 2.0, 3.0, 4.0], [], "", source="/cam/info")
    with pytest.raises(InputError, match=r"roi 300 x 200 at \(400, 50\) leaves the 640 x 480 image"):
        from_camera_info(640, 480, K_ROW_MAJOR, [], "", roi=(400, 50, 200, 300, False), source="/cam/info")
    with pytest.raises(InputError, match="distortion coefficients .* not all finite"):
        from_camera_info(640, 480, K_ROW_MAJOR, [float("inf")], "plumb_bob", source="/cam/info")


def test_check_size_message() -> None:
    model = CameraModel(FX, FY, CX, CY, 640, 480, source="camera.yaml")
    model.check_size(640, 480, "the depth image")
    with pytest.raises(InputError) as e:
        model.check_size(1280, 720, "the depth image")
    assert str(e.value) == (
        "the depth image is 1280 x 720 but the intrinsics (camera.yaml) are for 640 x 480; "
        "give the intrinsics of that image"
    )
    with pytest.raises(InputError, match="depth image is 640 x 480 but"):
        back_project(np.ones((480, 640), np.float32), CameraModel(FX, FY, CX, CY, 640, 480, binning_x=2, binning_y=2))


# --- back-projection ----------------------------------------------------------------------


@pytest.mark.parametrize("index", range(9))
def test_back_project_reproduces_uois_pcd(index: int) -> None:
    from PIL import Image

    from clearcli.io.read import read_frame

    model = read_intrinsics(shared_path("rgbd/uois/camera_params.json"))
    depth_mm = np.asarray(Image.open(shared_path(f"rgbd/uois/uois_{index:04d}_depth.png")))
    assert depth_mm.dtype == np.uint16 and depth_mm.shape == (480, 640)
    frame = read_frame(shared_path(f"scenes/uois_realsense/uois_image_{index:04d}.pcd"))
    assert frame.shape == (480, 640)
    points = back_project(depth_mm.astype(np.float32) / np.float32(1000.0), model)
    assert points.dtype == np.float32 and points.shape == (480 * 640, 3)
    assert np.array_equal(np.isnan(points).any(axis=1), depth_mm.reshape(-1) == 0)
    np.testing.assert_allclose(points, frame.points, rtol=1e-6, atol=1e-6, equal_nan=True)
    # Float32 arithmetic in the order (u - cx) * z / fx matches the PCD bit for bit.
    assert np.array_equal(points, frame.points, equal_nan=True)


def test_hand_worked_pixels_and_invalid_depth() -> None:
    model = CameraModel(fx=4.0, fy=6.0, cx=2.0, cy=3.0, width=8, height=5)
    depth = np.zeros((5, 8))  # float64 in: rounded to float32 first
    depth[3, 6] = 1.0  # u = cx + fx, v = cy: one metre right for each metre forward
    depth[0, 0] = 2.0  # x = (0 - 2) * 2 / 4, y = (0 - 3) * 2 / 6
    depth[4, 7] = -1.0
    depth[4, 6] = np.nan
    depth[4, 5] = np.inf
    points = back_project(depth, model)
    assert points.dtype == np.float32 and points.shape == (40, 3)
    np.testing.assert_array_equal(points[3 * 8 + 6], [1.0, 0.0, 1.0])
    np.testing.assert_array_equal(points[0], [-1.0, -1.0, 2.0])
    valid = ~np.isnan(points).any(axis=1)
    assert valid.sum() == 2 and np.isnan(points[~valid]).all()


def test_binning_and_roi_hand_worked() -> None:
    full = dict(fx=100.0, fy=50.0, cx=319.5, cy=239.5, width=640, height=480)
    binned = CameraModel(**full, binning_x=2, binning_y=2)
    depth = np.ones((240, 320), np.float32)
    points = back_project(depth, binned).reshape(240, 320, 3)
    # Binned pixel (0, 0) covers full pixels 0..1: its centre is at full (0.5, 0.5).
    np.testing.assert_allclose(points[0, 0], [(0.5 - 319.5) / 100, (0.5 - 239.5) / 50, 1.0], rtol=1e-6)
    # Binned (u=160, v=120) -> full (320.5, 240.5).
    np.testing.assert_allclose(points[120, 160], [0.01, 0.02, 1.0], rtol=1e-5)
    # ROI 300 x 200 at (100, 50), then 2 x 2 binning: a 150 x 100 image;
    # (u=10, v=4) -> full (100 + 10.5 * 2 - 0.5, 50 + 4.5 * 2 - 0.5) = (120.5, 58.5).
    k = [100.0, 0.0, 319.5, 0.0, 50.0, 239.5, 0.0, 0.0, 1.0]
    roi = from_camera_info(640, 480, k, [], "", 2, 2, {"x_offset": 100, "y_offset": 50, "height": 200, "width": 300})
    points = back_project(np.full((100, 150), 2.0, np.float32), roi).reshape(100, 150, 3)
    np.testing.assert_allclose(points[4, 10], [(120.5 - 319.5) * 2 / 100, (58.5 - 239.5) * 2 / 50, 2.0], rtol=1e-6)


def _rays_residual(model: CameraModel) -> float:
    """Largest miss of the rays back_project gives, distorted again, on the pixels' coordinates."""
    rays = back_project(np.ones((480, 640), np.float32), model)
    assert np.isfinite(rays).all()
    v, u = np.mgrid[0:480, 0:640]
    xd, yd = _forward(rays[:, 0].astype(np.float64), rays[:, 1].astype(np.float64), model.distortion)
    return max(np.abs(xd - ((u - CX) / FX).ravel()).max(), np.abs(yd - ((v - CY) / FY).ravel()).max())


@pytest.mark.parametrize("name, coeffs", [("plumb_bob", PLUMB_BOB), ("rational_polynomial", RATIONAL)])
def test_distortion_inverse(name: str, coeffs: tuple[float, ...]) -> None:
    model = from_camera_info(640, 480, K_ROW_MAJOR, coeffs, name, source="/cam/info")
    assert _rays_residual(model) < 1e-6
    # The rays really are corrected: away from the centre they differ from the pinhole ones.
    pinhole = back_project(np.ones((480, 640), np.float32), CameraModel(FX, FY, CX, CY, 640, 480))
    rays = back_project(np.full((480, 640), 2.0, np.float32), model)
    assert np.abs(rays[:, :2] / 2 - pinhole[:, :2]).max() > 0.01
    np.testing.assert_array_equal(rays[:, 2], 2.0)


def test_distortion_rays_are_cached_and_zero_coefficients_are_pinhole() -> None:
    from clearcli.io.intrinsics import _undistorted_rays

    model = from_camera_info(640, 480, K_ROW_MAJOR, PLUMB_BOB, "plumb_bob", source="/cam/info")
    depth = np.ones((480, 640), np.float32)
    first = back_project(depth, model)
    hits = _undistorted_rays.cache_info().hits
    np.testing.assert_array_equal(back_project(depth, model), first)
    assert _undistorted_rays.cache_info().hits == hits + 1
    pinhole = back_project(depth, CameraModel(FX, FY, CX, CY, 640, 480))
    for name in ("plumb_bob", "equidistant", "none"):
        zeros = CameraModel(FX, FY, CX, CY, 640, 480, distortion_model=name, distortion=(0.0,) * 5)
        assert not zeros.distorted
        np.testing.assert_array_equal(back_project(depth, zeros), pinhole)


def test_unsupported_distortion_refused() -> None:
    depth = np.ones((480, 640), np.float32)
    fisheye = from_camera_info(640, 480, K_ROW_MAJOR, [0.1, 0.01, 0.0, 0.0], "equidistant", source="/cam/info")
    with pytest.raises(InputError) as e:
        back_project(depth, fisheye)
    assert str(e.value) == (
        "distortion model 'equidistant' of /cam/info is not supported; "
        "give rectified images or plumb_bob / rational_polynomial intrinsics"
    )
    extra = from_camera_info(640, 480, K_ROW_MAJOR, [*PLUMB_BOB, 0.3, 0.0, 0.0], "plumb_bob", source="/cam/info")
    with pytest.raises(InputError, match="plumb_bob takes 5 distortion coefficients, got 8"):
        back_project(depth, extra)
    with pytest.raises(InputError, match="not one .height, width. image"):
        back_project(np.ones((480, 640, 3), np.float32), CameraModel(FX, FY, CX, CY))
    with pytest.raises(TypeError, match="metres"):
        back_project(np.ones((480, 640), np.uint16), CameraModel(FX, FY, CX, CY))


def test_a_distorted_depth_image_gives_the_known_undistorted_points() -> None:
    """Known 3D points (a plane 1.2 m away) seen through a plumb_bob lens: for sampled
    pixels the true point is found with SciPy's root finder (independent of our fixed-point
    inversion), and back_project of the depth image must give it."""
    from scipy.optimize import fsolve

    model = from_camera_info(640, 480, K_ROW_MAJOR, PLUMB_BOB, "plumb_bob", source="/cam/info")
    points = back_project(np.full((480, 640), 1.2, np.float32), model).reshape(480, 640, 3)
    rng = np.random.default_rng(7)
    for v, u in zip(rng.integers(0, 480, 40), rng.integers(0, 640, 40)):
        target = np.array([(u - CX) / FX, (v - CY) / FY])

        def miss(ray: np.ndarray) -> np.ndarray:
            xd, yd = _forward(np.array([ray[0]]), np.array([ray[1]]), PLUMB_BOB)
            return np.array([xd[0], yd[0]]) - target  # noqa: B023 (called within the iteration)

        ray = fsolve(miss, target, xtol=1e-12)
        np.testing.assert_allclose(points[v, u], [ray[0] * 1.2, ray[1] * 1.2, 1.2], atol=2e-6)


def test_back_project_overflowing_depth_is_no_point_and_no_warning() -> None:
    # 3e38 m is a corrupt pixel: (u - cx) * z overflows float32 to inf at the image's edge
    depth = np.full((4, 6), 1.0, np.float32)
    depth[0, 0] = np.float32(3e38)
    depth[3, 5] = np.float32(3e38)
    model = CameraModel(2.0, 2.0, 2.5, 1.5, 6, 4)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        points = back_project(depth, model)
    assert np.isnan(points[0]).all() and np.isnan(points[-1]).all()
    assert np.isfinite(points[1:-1]).all()
    # the other pixels by hand: pixel (row 1, column 3) at 1 m is ((3 - 2.5) / 2, (1 - 1.5) / 2, 1)
    assert np.allclose(points[1 * 6 + 3], [0.25, -0.25, 1.0])


def test_intrinsics_beyond_float32_are_refused(tmp_path: Path) -> None:
    # finite in float64 but inf (or 0 for a focal length) in the float32 back-projection
    _bad("600 600 1e308 240", "cx = 1e+308 (must be a finite number within float32's range")
    _bad("1e-300 600 320 240", "fx = 1e-300 (must be a positive finite number within float32's range")
    _bad("600 1e39 320 240", "fy = 1e+39 (must be a positive finite number within float32's range")


def test_a_camera_matrix_entry_beyond_any_float_is_refused(tmp_path: Path) -> None:
    # JSON holds integers of any size; float() of 10**400 raises OverflowError
    column_major = [FX, 0, 0, 0, FY, 0, 10**400, CY, 1]
    path = tmp_path / "huge.json"
    path.write_text(json.dumps({"width": 640, "height": 480, "intrinsic_matrix": column_major}))
    _bad(path, "huge.json: an entry of intrinsic_matrix = 1000", "is not a number a camera has; fix the camera matrix")
