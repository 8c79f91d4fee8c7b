"""Tests of clearcli/perception/orientation.py: hand-worked turns and rolls."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers.segment import S, _render

from clearcli.io.frames import Frame
from clearcli.perception.orientation import Orientation, axes_turn, quarter_turns_for


def test_a_quarter_turn_moves_right_to_the_former_down_and_down_to_the_former_left() -> None:
    # worked by hand: after np.rot90 (k = 1) the working image's right (x) is the frame's
    # down (+y), its down (+y) the frame's left (-x); z stays
    q = Orientation().rolled(1)
    assert q.perm == (1, 0, 2) and q.sign == (1.0, -1.0, 1.0) and q.quarter_turns == 1
    # two are a half turn: x and y negated; four are none
    half = Orientation().rolled(2)
    assert half.perm == (0, 1, 2) and half.sign == (-1.0, -1.0, 1.0)
    assert Orientation().rolled(4).identity and not half.identity
    # back() undoes the points' turn, exactly
    p = np.array([[0.1, -0.2, 0.9], [1.5, 2.5, -3.5]], dtype=np.float32)
    turned = q.frame(Frame(points=p)).points
    assert np.array_equal(turned, np.array([[-0.2, -0.1, 0.9], [2.5, -1.5, -3.5]], dtype=np.float32))
    assert np.array_equal(q.back(turned), p.astype(np.float64))


def test_a_rolled_frame_moves_its_pixels_and_colours_with_its_points() -> None:
    # a 2 x 3 image turned a quarter: 3 x 2, pixel (r, c) of the turn shows (c, 2 - r)
    pts = np.arange(18, dtype=np.float32).reshape(6, 3) + 1.0
    colors = np.arange(18, dtype=np.uint8).reshape(6, 3)
    frame = Frame(points=pts, colors=colors, shape=(2, 3), fields={"label": np.arange(6)})
    rolled = Orientation().rolled(1).frame(frame)
    assert rolled.shape == (3, 2)
    shows = [2, 5, 1, 4, 0, 3]  # np.rot90 of [[0, 1, 2], [3, 4, 5]]
    assert rolled.fields["label"].tolist() == shows
    assert np.array_equal(rolled.colors, colors[shows])
    assert np.array_equal(rolled.points[:, 2], pts[shows, 2])  # z stays


@pytest.mark.parametrize(
    ("normal", "turns"),
    [
        ((0.0, -0.8, -0.6), 0),  # upright: the normal up the image
        ((0.0, 0.8, -0.6), 2),  # upside down
        ((0.8, 0.0, -0.6), 1),  # its top to the image's right: (x, y) -> (y, -x) = (0, -0.8), up
        ((-0.8, 0.0, -0.6), 3),
        ((0.0, 0.3, -0.95), 0),  # nearly straight down (0.3 < 0.5 in the image): no top
        ((0.6, -0.4, -0.69), 0),  # 56 degrees off upright: within 60, read as it is
        ((0.7, -0.3, -0.65), 1),  # 67 degrees off: a quarter turn, to (-0.3, -0.7)
    ],
)
def test_quarter_turns_bring_the_tables_normal_nearest_the_images_top(normal: tuple[float, ...], turns: int) -> None:
    n = np.array(normal) / np.linalg.norm(normal)
    assert quarter_turns_for(n) == turns
    if turns:
        # after the turns the normal points up the image, within 45 degrees
        after = Orientation().rolled(turns).frame(Frame(points=n[None].astype(np.float32))).points[0]
        assert -after[1] >= math.cos(math.radians(45)) * math.hypot(after[0], after[1]) - 1e-6


def test_the_axes_turn_is_found_for_other_conventions_and_none_for_the_optical_frame_or_a_mirror() -> None:
    from clearcli.sim.scene import isolated_box

    frame = _render(isolated_box())
    p = frame.points
    assert axes_turn(frame) is None  # the optical frame: as it is
    gl = axes_turn(Frame(points=p * np.array([1, -1, -1], np.float32), shape=frame.shape))
    assert gl is not None and gl.perm == (0, 1, 2) and gl.sign == (1.0, -1.0, -1.0)
    link = axes_turn(Frame(points=np.ascontiguousarray(np.stack([p[:, 2], -p[:, 0], -p[:, 1]], 1)), shape=frame.shape))
    # optical x = -link y, optical y = -link z, optical z = link x
    assert link is not None and link.perm == (1, 2, 0) and link.sign == (-1.0, -1.0, 1.0)
    # a mirror (x negated, looking along -z): no turn of a camera gives it
    assert axes_turn(Frame(points=p * np.array([-1, -1, -1], np.float32), shape=frame.shape)) is None
    # an unorganized cloud: no pixels to tell by
    assert axes_turn(Frame(points=p * np.array([1, -1, -1], np.float32))) is None


def _pinhole_image(R: np.ndarray, t: np.ndarray, h: int = 120, w: int = 160) -> np.ndarray:
    """(h * w, 3) points of a pinhole camera (fx = fy = 150, centre (79.5, 59.5)) looking at a
    plane 1 m ahead tilted 30 degrees with a box's top 10 cm nearer over a part of it, moved
    into a frame where camera = R @ point + t."""
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    rays = np.stack([(u - 79.5) / 150.0, (v - 59.5) / 150.0, np.ones_like(u)], axis=-1).reshape(-1, 3)
    # the plane z = 1 + 0.577 y (30 degrees): depth along each ray
    depth = 1.0 / (1.0 - 0.577 * rays[:, 1])
    box = ((u > 60) & (u < 100) & (v > 40) & (v < 80)).reshape(-1)
    depth[box] -= 0.1
    camera = rays * depth[:, None]
    camera[::7] = np.nan  # some pixels without depth
    return (camera - t) @ R  # point = R^T (camera - t)


def test_the_camera_pose_of_a_moved_image_is_recovered_from_its_pixels() -> None:
    from clearcli.perception.orientation import camera_pose

    angle = math.radians(40.0)
    R = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(angle), -math.sin(angle)], [0.0, math.sin(angle), math.cos(angle)]])
    R = R @ np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # and a quarter turn about z
    t = np.array([0.3, -0.2, 0.9])
    pose = camera_pose(_pinhole_image(R, t).astype(np.float32), (120, 160))
    assert pose is not None
    assert np.abs(pose[0] - R).max() < 1e-5 and np.abs(pose[1] - t).max() < 1e-5
    # the image in its own optical frame: no pose to apply
    assert camera_pose(_pinhole_image(np.eye(3), np.zeros(3)), (120, 160)) is None
    # the pixels shuffled: no pinhole's image
    shuffled = _pinhole_image(R, t)[np.random.default_rng(0).permutation(120 * 160)]
    assert camera_pose(shuffled, (120, 160)) is None
    # every point on one plane (no box): many projections fit it, so none is taken
    v, u = np.mgrid[0:120, 0:160].astype(np.float64)
    flat = np.stack([(u - 79.5) / 150.0, (v - 59.5) / 150.0, np.ones_like(u)], axis=-1).reshape(-1, 3)
    assert camera_pose(((flat - t) @ R), (120, 160)) is None


def test_a_moved_image_is_turned_into_its_cameras_frame_and_back() -> None:
    from clearcli.perception.orientation import Orientation

    angle = math.radians(25.0)
    R = np.array([[math.cos(angle), 0.0, math.sin(angle)], [0.0, 1.0, 0.0], [-math.sin(angle), 0.0, math.cos(angle)]])
    t = np.array([0.1, 0.2, -0.4])
    frame = Frame(points=_pinhole_image(R, t), shape=(120, 160))
    turn = axes_turn(frame)
    assert turn is not None and turn.R_camera_frame is not None and turn.quarter_turns == 0
    working = turn.frame(frame)
    assert np.allclose(working.points, _pinhole_image(np.eye(3), np.zeros(3)), atol=1e-9, equal_nan=True)
    # back: points (R^T (p - t)), directions (R^T n), a plane's offset (d + n . t)
    p = np.array([0.2, -0.1, 1.3])
    assert np.allclose(turn.back(p), (p - t) @ R)
    assert np.allclose(turn.back(p, points=False), p @ R)
    n, d = np.array([0.0, -0.6, -0.8]), 0.7  # a plane in the camera's frame
    n_frame, d_frame = turn.back(n, points=False), turn.offset_back(d, n)
    on_plane = p - (n @ p + d) * n
    assert abs(n_frame @ turn.back(on_plane) + d_frame) < 1e-12
    assert isinstance(turn.rolled(2), Orientation) and turn.rolled(2).R_camera_frame is turn.R_camera_frame


@pytest.mark.parametrize(
    ("forward", "normal", "perm", "sign"),
    [
        # the optical frame, upright (the normal up the image, towards the camera): no turn
        ((0.1, 0.2, 1.0), (0.0, -0.8, -0.6), None, None),
        # OpenGL's axes (looking along -z, y up): optical x = x, y = -y, z = -z
        ((0.1, -0.2, -1.0), (0.0, 0.8, 0.6), (0, 1, 2), (1.0, -1.0, -1.0)),
        # camera_link's (x forward, y left, z up): optical x = -y, y = -z, z = x
        ((1.0, -0.1, -0.2), (-0.6, 0.0, 0.8), (1, 2, 0), (-1.0, -1.0, 1.0)),
        # looking along no axis (45 degrees between two): none
        ((1.0, 0.0, 1.0), (0.0, -0.8, -0.6), None, None),
    ],
)
def test_an_unorganized_camera_cloud_is_turned_into_the_optical_axes_by_its_view(
    forward: tuple[float, ...], normal: tuple[float, ...], perm: tuple[int, ...] | None, sign: tuple[float, ...] | None
) -> None:
    from clearcli.perception.orientation import cloud_turn

    points = np.array(forward)[None] * np.linspace(0.5, 1.5, 50)[:, None]
    n = np.array(normal) / np.linalg.norm(normal)
    turn = cloud_turn(points, n)
    if perm is None:
        assert turn is None
        return
    assert turn is not None and turn.perm == perm and turn.sign == sign
    # the turned normal points up the image (-y) and towards the camera (-z)
    turned = turn.frame(Frame(points=n[None])).points[0]
    assert turned[1] < -0.5 and turned[2] < 0


def test_an_unorganized_cloud_in_other_axes_gives_the_optical_clouds_objects() -> None:
    # the same points, without pixels, in OpenGL's and camera_link's axes and upside down:
    # turned into the optical axes by cloud_turn, the same objects point for point (before:
    # camera_link 6 -> 7 objects on uois_image_0004, OpenGL's 15 -> 13 on test55)
    from clearcli.perception.segment import segment
    from clearcli.sim.scene import clutter

    frame = _render(clutter(6, 2))
    keep = np.isfinite(frame.points).all(axis=1)
    p = np.ascontiguousarray(frame.points[keep])
    optical = segment(Frame(points=p, colors=_kept_colors(frame, keep)), S)
    for moved in (p * np.array([1, -1, -1], np.float32), np.stack([p[:, 2], -p[:, 0], -p[:, 1]], axis=1)):
        seg = segment(Frame(points=np.ascontiguousarray(moved), colors=_kept_colors(frame, keep)), S)
        assert len(seg.objects) == len(optical.objects) >= 4
        assert np.array_equal(seg.labels(), optical.labels())
        assert "the frame's axes turned into the optical frame's" in seg.support[0].why


def _kept_colors(frame: Frame, keep: np.ndarray) -> np.ndarray | None:
    return None if frame.colors is None else np.ascontiguousarray(frame.colors[keep])
