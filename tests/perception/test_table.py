"""Tests of clearcli/perception/table.py."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from helpers.segment import (
    S,
    _render,
    box_frame,  # noqa: F401  (fixtures)
)

from clearcli.errors import SceneError
from clearcli.io.frames import Frame


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


# ------------------------------------------------------------------ beyond the edge
def _table_gap_seat(gap_shows: str) -> tuple[np.ndarray, np.ndarray]:
    """An organized pinhole frame (640 x 480, f = 400 px) looking down at a plane 0.4 m
    below the camera (optical y down): the table where the plane is 0.67-1.2 m ahead,
    a gap 1.2-1.4 m, a seat on the same plane 1.4-1.7 m, a wall 2.5 m away above. Through
    the gap the camera sees the floor (1.1 m down: farther) or a box's front face at
    1.15 m (nearer). Returns (points (N, 3), flat pixels of the plane's points)."""
    h, w, f = 480, 640, 400.0
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    rays = np.stack([(u - w / 2) / f, (v - h / 2) / f, np.ones_like(u)], axis=-1)
    below = v > h / 2
    z_plane = np.where(below, 0.4 * f / np.maximum(v - h / 2, 1e-9), np.inf)
    z = np.full((h, w), 2.5)  # the wall
    table = below & (z_plane <= 1.2)
    gap = below & (z_plane > 1.2) & (z_plane < 1.4)
    seat = below & (z_plane >= 1.4) & (z_plane <= 1.7)
    z[table | seat] = z_plane[table | seat]
    z[gap] = 1.1 * f / (v[gap] - h / 2) if gap_shows == "floor" else 1.15
    points = (rays * z[..., None]).reshape(-1, 3).astype(np.float32)
    return points, np.flatnonzero((table | seat).ravel())


def test_a_piece_of_the_plane_seen_beyond_a_gap_is_not_table() -> None:
    from clearcli.perception.table import beyond_the_edge
    from clearcli.perception.types import TablePlane

    plane = TablePlane(normal=np.array([0.0, -1.0, 0.0]), offset=0.4)  # up = towards the camera
    points, on_plane = _table_gap_seat("floor")
    z = points[on_plane, 2]
    drop, solid = beyond_the_edge(points, (480, 640), on_plane, plane, S)
    # the seat (1.4-1.7 m) goes, the table stays: the camera sees the floor in between.
    # (The pixel rows at a jump belong to no piece: the seat's first and last rows.)
    assert drop[z >= 1.4].mean() > 0.85 and not drop[z <= 1.2].any()
    assert solid[z <= 1.2].mean() > 0.95 and not solid[z >= 1.4].any()
    # the same seat behind a box (nearer than the gap): table hidden by an object, kept
    points, on_plane = _table_gap_seat("box")
    drop, _ = beyond_the_edge(points, (480, 640), on_plane, plane, S)
    assert not drop.any()


def test_polygon_area_by_hand() -> None:
    from clearcli.perception.table import polygon_area

    assert polygon_area(np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]])) == pytest.approx(2.0)
    assert polygon_area(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])) == pytest.approx(0.5)


def test_hull_vertices_are_qhulls_on_every_point() -> None:
    """Qhull on the points outside the octagon of extremes gives the vertices, in the
    order, that it gives on all of them (of two equal points either may be the vertex:
    the same coordinates); degenerate input raises alike."""
    from scipy.spatial import ConvexHull, QhullError

    from clearcli.perception.table import _hull_candidates, hull_vertices

    gen = np.random.default_rng(7)
    for trial in range(60):
        n = int(gen.integers(3, 4000))
        xy = gen.normal(size=(n, 2)) * gen.uniform(0.01, 1.0, size=2)
        if trial % 3 == 0:
            xy = np.round(xy * 50) / 50  # on a grid: ties and collinear points
        assert xy[hull_vertices(xy)].tolist() == xy[ConvexHull(xy).vertices].tolist()
        if n > 500 and trial % 3:
            assert _hull_candidates(xy[:, 0].copy(), xy[:, 1].copy()).mean() < 0.5  # most are thrown away
    line = np.stack([np.linspace(0.0, 1.0, 200), np.linspace(0.0, 2.0, 200)], axis=1)
    with pytest.raises(QhullError):
        hull_vertices(line)


def test_label_grid_numbers_as_ndimage() -> None:
    """8-connected labels of the grid, numbered as scipy.ndimage.label numbers them
    (the runs along the rows joined by a running count give the same pieces)."""
    from scipy import ndimage

    from clearcli.perception.table import _label_grid

    gen = np.random.default_rng(11)
    for trial in range(40):
        h, w = (int(x) for x in gen.integers(1, 60, size=2))
        grid = gen.random((h, w)) < (0.2 + 0.02 * trial)
        want, n_want = ndimage.label(grid, structure=np.ones((3, 3), dtype=bool))
        got, n_got = _label_grid(grid)
        assert n_got == n_want
        assert np.array_equal(got, want)
