"""The working resolution (clearcli/perception/resolution.py): which frames are thinned
and which not, labels carried back to every pixel, and a 1280x720 frame's objects on
the working grid against its full-resolution result."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import FIXTURES, shared_path

from clearcli.io.frames import Frame
from clearcli.settings.segment import SegmentSettings

SETTINGS = SegmentSettings()


def _pinhole(h: int, w: int, f: float, depth: np.ndarray | float = 0.8) -> Frame:
    """An organized frame of a pinhole camera (focal length ``f`` pixels) seeing ``depth``."""
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    z = np.broadcast_to(np.asarray(depth, dtype=np.float64), (h, w))
    pts = np.stack([(u - w / 2) * z / f, (v - h / 2) * z / f, z], axis=-1).reshape(-1, 3)
    return Frame(points=pts.astype(np.float32), shape=(h, w))


@pytest.mark.parametrize(
    ("h", "w", "f", "k"),
    [
        (480, 640, 525.0, 1),  # Kinect, mOSD: 1.9 mrad
        (480, 640, 615.0, 1),  # RealSense at 640x480: 1.6 mrad
        (386, 516, 552.0, 1),  # PhoXi S at 516x386: 1.8 mrad
        (720, 1280, 921.0, 2),  # RealSense D435 at 1280x720: 1.09 mrad
        (1080, 1920, 1380.0, 3),  # a 1080p depth camera: 0.72 mrad
    ],
)
def test_the_stride_follows_the_pixel_pitch(h: int, w: int, f: float, k: int) -> None:
    from clearcli.perception.resolution import choose_stride, pixel_pitch

    frame = _pinhole(h, w, f)
    pitch = pixel_pitch(frame.points, (h, w))
    assert pitch is not None and pitch == pytest.approx((1 / f, 1 / f), rel=1e-3)
    assert choose_stride(frame, SETTINGS) == k


def test_the_rule_is_the_voxel_over_two_samples_at_a_metre() -> None:
    from clearcli.perception.resolution import stride_for

    # 5 mm voxel: at most 2.5 mrad a working pixel
    assert stride_for(2.5e-3, 0.005) == 1 and stride_for(1.25e-3, 0.005) == 2 and stride_for(1.26e-3, 0.005) == 1
    # a finer voxel asks for every pixel of the 1280x720 frame
    assert stride_for(1.086e-3, 0.002) == 1


def test_frames_that_are_no_pinhole_grid_keep_every_point() -> None:
    from clearcli.perception.resolution import choose_stride

    dense = _pinhole(720, 1280, 921.0)
    # unorganized: every point
    assert choose_stride(Frame(points=dense.points), SETTINGS) == 1
    # organized, but moved into another frame (rotated about x): x/z steps disagree
    c, s = np.cos(0.7), np.sin(0.7)
    rot = np.array([[1, 0, 0], [0, c, -s], [0, s, c]], dtype=np.float32)
    moved = Frame(points=dense.points @ rot.T + np.float32([0, 0, 0.5]), shape=(720, 1280))
    assert choose_stride(moved, SETTINGS) == 1
    # all NaN
    assert choose_stride(Frame(points=np.full((720 * 1280, 3), np.nan, np.float32), shape=(720, 1280)), SETTINGS) == 1


@pytest.mark.parametrize(
    "relative",
    ["mosd/test/test44.pcd", "mosd/learn/learn30.pcd", "scenes/uois_realsense/uois_image_0003.pcd"],
)
def test_640x480_frames_keep_every_pixel(relative: str) -> None:
    from clearcli.io.read import read_frame
    from clearcli.perception.resolution import WorkingGrid

    frame = read_frame(shared_path(relative))
    grid = WorkingGrid.of(frame, SETTINGS)
    assert grid.stride == 1 and grid.frame is frame


def test_the_fixtures_keep_every_pixel() -> None:
    from clearcli.io.read import read_frame
    from clearcli.perception.resolution import choose_stride

    paths = sorted(FIXTURES.glob("*.pcd"))
    assert paths
    assert [choose_stride(read_frame(p), SETTINGS) for p in paths] == [1] * len(paths)


def test_the_working_grid_is_every_kth_row_and_column() -> None:
    from clearcli.perception.resolution import WorkingGrid

    frame = _pinhole(7, 9, 900.0)
    colors = np.arange(63 * 3, dtype=np.uint8).reshape(63, 3)
    frame = Frame(points=frame.points, colors=colors, shape=(7, 9), fields={"label": np.arange(63)})
    grid = WorkingGrid.of(frame, SETTINGS, stride=2)
    assert grid.frame.shape == (4, 5) and grid.frame.n_points == 20
    full_of = grid.full_index(np.arange(20))
    assert full_of.tolist() == [r * 9 + c for r in range(0, 7, 2) for c in range(0, 9, 2)]
    np.testing.assert_array_equal(grid.frame.points, frame.points[full_of])
    np.testing.assert_array_equal(grid.frame.colors, colors[full_of])
    np.testing.assert_array_equal(grid.frame.fields["label"], full_of)


def test_labels_go_to_the_nearest_working_pixel_within_a_voxel() -> None:
    from clearcli.perception.resolution import WorkingGrid

    # a 4x4 grid, stride 2: working pixels (0,0) (0,2) (2,0) (2,2)
    h = w = 4
    pts = np.zeros((h, w, 3), np.float32)
    pts[..., 0] = np.arange(w) * 0.001  # 1 mm apart
    pts[..., 1] = np.arange(h)[:, None] * 0.001
    pts[..., 2] = 1.0
    pts[1, 3] = (0.0, 0.0, 1.5)  # far from every working pixel: none
    pts[3, 3] = np.nan  # not finite: none
    pts[2, 1, 0] = 0.0017  # nearer (2,2) than (2,0)
    frame = Frame(points=pts.reshape(-1, 3), shape=(h, w))
    grid = WorkingGrid.of(frame, SETTINGS, stride=2)
    work = np.array([5, 6, 7, 8])  # labels of (0,0) (0,2) (2,0) (2,2)
    full = grid.full_labels(work, voxel_m=0.005).reshape(h, w)
    assert full[0, 0] == 5 and full[0, 2] == 6 and full[2, 0] == 7 and full[2, 2] == 8  # the working pixels
    assert full[0, 1] in (5, 6) and full[1, 0] in (5, 7)  # halfway: either
    assert full[2, 1] == 8  # the nearer one
    assert full[1, 3] == 0 and full[3, 3] == 0
    # the last row and column have no next working pixel: the block's own
    assert full[3, 0] == 7 and full[3, 2] == 8 and full[0, 3] == 6


@pytest.fixture(scope="module")
def cleargrasp_080():
    """(frame, full-resolution result, working-grid result) of cleargrasp_000000080."""
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment

    frame = read_frame(shared_path("scenes/cleargrasp_d435/cleargrasp_000000080.pcd"))
    return frame, segment(frame, SETTINGS, stride=1), segment(frame, SETTINGS)


def test_a_1280x720_frame_is_segmented_on_a_working_grid_with_labels_on_every_pixel(cleargrasp_080) -> None:
    from clearcli.perception.resolution import WorkingGrid, choose_stride

    frame, _, seg = cleargrasp_080
    assert frame.shape == (720, 1280) and choose_stride(frame, SETTINGS) == 2
    assert seg.n_points == frame.n_points
    labels = seg.labels()
    assert labels.shape == (frame.n_points,)
    grid = WorkingGrid.of(frame, SETTINGS)
    on_grid = grid.full_index(np.arange(grid.frame.n_points))
    finite = frame.finite_mask
    label_img = labels.reshape(720, 1280)
    for k, obj in enumerate(seg.objects):
        assert np.isfinite(frame.points[obj.indices]).all()
        # about four pixels for every working pixel of the object
        mine = np.isin(on_grid, obj.indices)
        assert obj.n_points >= 3 * int(mine.sum())
        # every finite pixel inside the object (its block's four corners all the
        # object's) carries the object's label
        corners = (label_img[0:-2:2, 0:-2:2], label_img[0:-2:2, 2::2], label_img[2::2, 0:-2:2], label_img[2::2, 2::2])
        inside = np.logical_and.reduce([c == 10 * (k + 1) for c in corners])
        block = np.zeros((720, 1280), bool)
        for r in range(2):
            for c in range(2):
                block[r:-2:2, c:-2:2] |= inside
        candidates = block.reshape(-1) & finite
        assert candidates.any()
        assert np.mean(labels[candidates] == 10 * (k + 1)) >= 0.99
    # the table too
    assert seg.table_indices.shape[0] >= 3 * int(np.isin(on_grid, seg.table_indices).sum())


def test_a_1280x720_frame_matches_its_full_resolution_objects(cleargrasp_080) -> None:
    from clearcli.perception.stability import object_matches

    _, full, work = cleargrasp_080
    # every object of the working grid is one of the full resolution's, at IoU >= 0.9
    assert (object_matches(work, full) >= 0.9).all()
    # and every object of the full resolution is found, but for a sliver of a few
    # hundred points at the image's right edge (7 cm long, 6 mm tall)
    found = object_matches(full, work)
    lost = [o.n_points for o, iou in zip(full.objects, found, strict=True) if iou < 0.9]
    assert len(lost) <= 1 and all(n < 1000 for n in lost)
    assert len(work.objects) >= len(full.objects) - 1


def test_a_1280x720_frame_is_stable_under_a_micrometre(cleargrasp_080) -> None:
    from clearcli.perception.segment import segment
    from clearcli.perception.stability import perturbed, same_objects

    frame, _, seg = cleargrasp_080
    assert same_objects(seg, segment(perturbed(frame, 1e-6, seed=0), SETTINGS))
