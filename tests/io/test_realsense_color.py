"""Colour of RealSense SDK recordings (realsense-viewer, rs2::recorder) registered to the
depth through the recorded extrinsics (clearcli/io/mcap_images.py, clearcli/io/register.py).

The expected colour pixel of each depth pixel is worked out here by hand, with plain
arithmetic: back-project with the depth intrinsics, p_color = R p_depth + t (the recorded
`Color_0/tf/0` is the transform from the reference stream to colour, librealsense's
ros_writer::write_extrinsics), project with the colour intrinsics, nearest pixel.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from helpers.rgbd_logs import write_realsense_sdk_bag

from clearcli.io.read import iter_frames, read_frame

W_D, H_D, K_D = 64, 48, (50.0, 50.0, 32.0, 24.0)  # depth: fx, fy, cx, cy
W_C, H_C, K_C = 80, 60, (70.0, 72.0, 40.3, 29.6)  # colour: another size and other intrinsics
THETA = math.radians(4.0)  # colour camera turned 4 degrees about y
T_XYZ = (0.025, 0.002, -0.001)  # a 25 mm baseline along x (metres)
Q_COLOR_DEPTH = (0.0, math.sin(THETA / 2), 0.0, math.cos(THETA / 2))  # rotation about y by THETA
IDENTITY = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
T0 = 1_700_000_000_000_000_000


def _depth_mm() -> np.ndarray:
    depth = np.full((H_D, W_D), 800, dtype=np.uint16)
    depth[:, W_D // 2 :] = 1200  # the right half farther: another parallax
    depth[5, 5] = 0  # no depth
    return depth


def _painted() -> np.ndarray:
    """Each colour pixel its own colour: (3 col, 4 row, 200)."""
    col, row = np.meshgrid(np.arange(W_C), np.arange(H_C))
    return np.stack([3 * col, 4 * row, np.full_like(col, 200)], axis=-1).astype(np.uint8)


def _paint(col: int, row: int) -> tuple[int, int, int]:
    return (3 * col, 4 * row, 200)


def _by_hand(u: int, v: int, z: float, inverted: bool = False, k1: float = 0.0) -> tuple[float, float]:
    """The colour image coordinates depth pixel (u, v) at depth z lands on."""
    fx, fy, cx, cy = K_D
    x, y = (u - cx) * z / fx, (v - cy) * z / fy
    c, s = math.cos(THETA), math.sin(THETA)
    tx, ty, tz = T_XYZ
    if not inverted:  # p_color = R_y(theta) p + t
        xc, yc, zc = c * x + s * z + tx, y + ty, -s * x + c * z + tz
    else:  # the other direction, what reading the tf the wrong way round would do: R^T (p - t)
        dx, dy, dz = x - tx, y - ty, z - tz
        xc, yc, zc = c * dx - s * dz, dy, s * dx + c * dz
    xn, yn = xc / zc, yc / zc
    r2 = xn * xn + yn * yn
    xn, yn = xn * (1 + k1 * r2), yn * (1 + k1 * r2)
    fxc, fyc, cxc, cyc = K_C
    return fxc * xn + cxc, fyc * yn + cyc


def _nearest(uv: tuple[float, float]) -> tuple[int, int]:
    u, v = uv
    # the checked pixels are chosen away from a rounding tie, so float32 cannot flip them
    assert abs(u % 1 - 0.5) > 0.02 and abs(v % 1 - 0.5) > 0.02, uv
    return math.floor(u + 0.5), math.floor(v + 0.5)


def _write(path: Path, *, reference: str = "depth", **kw) -> Path:
    extrinsics = {"Depth": IDENTITY, "Color": (T_XYZ, Q_COLOR_DEPTH)}
    if reference == "other":
        # neither stream the reference: T_depth_ref a translation a, T_color_ref = T_color_depth T_depth_ref
        a = (0.01, -0.004, 0.003)
        c, s = math.cos(THETA), math.sin(THETA)
        ra = (c * a[0] + s * a[2], a[1], -s * a[0] + c * a[2])
        extrinsics = {"Depth": (a, IDENTITY[1]), "Color": (tuple(ra[i] + T_XYZ[i] for i in range(3)), Q_COLOR_DEPTH)}
    decoy = np.zeros((H_C, W_C, 3), dtype=np.uint8)
    decoy[...] = (255, 0, 255)
    args = dict(depth_k=K_D, color_k=K_C, extrinsics=extrinsics, color_at_ns=[-30_000_000, 6_000_000])
    args.update(kw)
    color = args.pop("color", [decoy, _painted()])
    return write_realsense_sdk_bag(path, [_depth_mm()], color, **args)


# (u, v) of depth pixels that land inside the colour image
INSIDE = [(12, 8), (20, 30), (31, 12), (33, 12), (45, 40), (50, 20), (8, 44)]


@pytest.mark.parametrize("reference", ["depth", "other"])
def test_colour_lands_on_the_pixels_worked_out_by_hand(tmp_path: Path, reference: str, capsys) -> None:
    frame = read_frame(_write(tmp_path / "rs.bag", reference=reference))
    assert frame.colors is not None and frame.colors.shape == (W_D * H_D, 3)
    colors = frame.colors.reshape(H_D, W_D, 3)
    depth = _depth_mm()
    for u, v in INSIDE:
        z = depth[v, u] / 1000.0
        col, row = _nearest(_by_hand(u, v, z))
        assert 0 <= col < W_C and 0 <= row < H_C, (u, v, col, row)
        assert tuple(colors[v, u]) == _paint(col, row), (u, v)
        # read the other way round, the extrinsic would put this pixel elsewhere: the test can fail
        other = _nearest(_by_hand(u, v, z, inverted=True))
        assert other != (col, row) and tuple(colors[v, u]) != _paint(*other)
    # the colour is the one logged nearest the depth image (6 ms after), not the decoy 30 ms before
    assert not np.all(colors == (255, 0, 255), axis=-1).any()
    # outside the colour camera's view (the depth camera sees wider), and no depth: no colour, black
    for u, v in ((2, 2), (63, 3), (55, 10), (5, 5)):
        if depth[v, u]:
            col, row = _nearest(_by_hand(u, v, depth[v, u] / 1000.0))
            assert not (0 <= col < W_C and 0 <= row < H_C)
        assert tuple(colors[v, u]) == (0, 0, 0)
    assert "colour left out" not in capsys.readouterr().err


def test_plumb_bob_colour_distortion_is_projected(tmp_path: Path) -> None:
    k1 = -0.2
    frame = read_frame(_write(tmp_path / "pb.bag", color_d=(k1, 0.0, 0.0, 0.0, 0.0)))
    colors = frame.colors.reshape(H_D, W_D, 3)
    moved = 0
    for u, v in INSIDE:
        z = _depth_mm()[v, u] / 1000.0
        col, row = _nearest(_by_hand(u, v, z, k1=k1))
        assert tuple(colors[v, u]) == _paint(col, row), (u, v)
        moved += (col, row) != _nearest(_by_hand(u, v, z))
    assert moved >= 5  # the distortion moved most of them (not those near the centre)


@pytest.mark.parametrize(
    "case, kw, words",
    [
        (
            "no tf topics",
            {"extrinsics": {}},
            "without Depth extrinsics (/device_0/sensor_0/Depth_0/tf/0) or Color extrinsics "
            "(/device_0/sensor_1/Color_0/tf/0): colour left out",
        ),
        (
            "no Depth tf",
            {"extrinsics": {"Color": (T_XYZ, Q_COLOR_DEPTH)}},
            "without Depth extrinsics (/device_0/sensor_0/Depth_0/tf/0): colour left out",
        ),
        (
            "no colour camera info",
            {"color_info": False},
            "without Color intrinsics (/device_0/sensor_1/Color_0/info/camera_info): colour left out",
        ),
        (
            "unreadable encoding",
            {"color_encoding": "yuv422", "color": [np.zeros((H_C, W_C, 2), np.uint8)], "color_at_ns": [0]},
            "is 'yuv422', not one clear reads",
        ),
        (
            "unprojectable distortion",
            {"color_model": "Inverse Brown Conrady", "color_d": (0.1, -0.05, 0, 0, 0)},
            "'Inverse Brown Conrady'",
        ),
        (
            "no colour near the depth",
            {"color_at_ns": [-90_000_000, 80_000_000]},
            "no Color image (/device_0/sensor_1/Color_0/image/data) within 50 ms of a depth image",
        ),
    ],
)
def test_what_registration_lacks_leaves_colour_out_by_name_and_depth_read(
    tmp_path: Path, capsys, case: str, kw: dict, words: str
) -> None:
    want = read_frame(_write(tmp_path / "full.bag"))
    capsys.readouterr()
    frame = read_frame(_write(tmp_path / "lacking.bag", **kw))
    err = capsys.readouterr().err
    assert frame.colors is None
    assert words in err and "lacking.bag" in err
    np.testing.assert_array_equal(frame.points, want.points)  # the depth is read all the same
    assert np.isfinite(frame.points).all(axis=1).sum() == W_D * H_D - 1


def test_every_frame_of_a_recording_gets_its_own_colour(tmp_path: Path) -> None:
    painted = _painted()
    other = painted.copy()
    other[..., 2] = 100  # the second frame's colour image, told apart by its blue
    log = write_realsense_sdk_bag(
        tmp_path / "two.bag",
        [_depth_mm(), _depth_mm()],
        [painted, other],
        depth_k=K_D,
        color_k=K_C,
        extrinsics={"Depth": IDENTITY, "Color": (T_XYZ, Q_COLOR_DEPTH)},
    )
    frames = list(iter_frames(log))
    assert [int(f.colors.reshape(H_D, W_D, 3)[20, 30, 2]) for f in frames] == [200, 100]


def test_identity_extrinsics_and_the_same_intrinsics_give_the_colour_image_itself(tmp_path: Path) -> None:
    from helpers import shared_path
    from PIL import Image

    from clearcli.io.pcd import read_pcd

    depth = np.asarray(Image.open(shared_path("rgbd/uois/uois_0003_depth.png")))
    color = np.asarray(Image.open(shared_path("rgbd/uois/uois_0003_color.png")))
    want = read_pcd(shared_path("scenes/uois_realsense/uois_image_0003.pcd"))
    log = write_realsense_sdk_bag(
        tmp_path / "same.bag", [depth], [color], extrinsics={"Depth": IDENTITY, "Color": IDENTITY}
    )
    frame = read_frame(log)
    finite = np.isfinite(frame.points).all(axis=1)
    np.testing.assert_array_equal(frame.points, want.points)
    np.testing.assert_array_equal(frame.colors[finite], want.colors[finite])
    assert not frame.colors[~finite].any()  # no depth: no colour
