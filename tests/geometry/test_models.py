"""Tests of clearcli/geometry/models.py."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.geometry import BOX, one_box, world_point_to_camera, world_to_camera

from clearcli.geometry.models import (
    DegenerateObject,
    TableFrame,
    build_object,
    column_tops,
)
from clearcli.perception.types import TablePlane
from clearcli.predicates.synthetic import Box
from clearcli.settings.geometry import PredicateSettings


# ------------------------------------------------------------------------------ table frame
def test_table_frame_axes_and_heights() -> None:
    n = np.array([0.0, -0.8, -0.6])
    table = TablePlane(normal=n, offset=0.7)
    tf = TableFrame.from_plane(table)
    R = tf.T_camera_table[:3, :3]
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-12) and np.isclose(np.linalg.det(R), 1.0)
    assert np.allclose(R[:, 2], n)
    assert R[2, 0] > 0  # table x: the camera's forward axis, flattened
    p = np.array([[0.1, 0.3, 0.9], [-0.2, 0.1, 1.2]])
    assert np.allclose(tf.to_table(p)[:, 2], table.height_of(p))
    assert np.allclose(tf.to_camera(tf.to_table(p)), p)


def test_column_tops_keep_the_highest_point_per_cell() -> None:
    q = np.array([[0.001, 0.001, 0.01], [0.002, 0.002, 0.05], [0.012, 0.001, 0.02], [0.004, 0.003, 0.03]])
    tops = column_tops(q, 0.005)
    assert sorted(tops[:, 2].tolist()) == [0.02, 0.05]


# ------------------------------------------------------------------------------ object model
def test_box_model_extents_axes_and_hull() -> None:
    state, obj = one_box(Box((0.0, 0.0), BOX, yaw_deg=30.0))
    assert np.allclose(obj.extents_m, [0.10, 0.05, 0.05], atol=0.004)
    # row 2 is the table normal; rows orthonormal
    assert np.allclose(obj.principal_axes @ obj.principal_axes.T, np.eye(3), atol=1e-9)
    assert np.allclose(obj.principal_axes[2], state.table.normal, atol=1e-9)
    yaw = np.radians(30.0)
    long_axis = world_to_camera([np.cos(yaw), np.sin(yaw), 0.0])
    assert abs(obj.principal_axes[0] @ long_axis) > 0.999
    # the hull reaches down to the table and up to the top, not beyond the box
    h = state.table.height_of(obj.hull_vertices)
    assert h.min() == pytest.approx(0.0, abs=1e-6) and h.max() == pytest.approx(0.05, abs=0.002)
    assert obj.height_m == pytest.approx(0.05, abs=0.002)
    # centroid of the sampled points lies within the box
    c = state.table.height_of(obj.centroid[None])[0]
    assert 0.0 < c < 0.05


def test_hull_is_solid_for_a_box_seen_from_above() -> None:
    """Points hidden from the camera (the far sides, the bottom) are inside the model."""
    import trimesh

    state, obj = one_box(Box((0.0, 0.0), BOX))
    mesh = trimesh.Trimesh(obj.hull_vertices, obj.hull_faces, process=False)
    assert mesh.is_watertight and mesh.volume == pytest.approx(0.10 * 0.05 * 0.05, rel=0.05)
    # faces are outward: hidden points are behind every face plane, an outside one is not
    hidden = np.array([world_point_to_camera(p) for p in ([0.049, 0.0, 0.001], [0.0, 0.024, 0.001], [0.0, 0.0, 0.001])])
    v = obj.hull_vertices[obj.hull_faces]
    normals = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    side = np.einsum("fj,pfj->pf", normals, hidden[:, None, :] - v[None, :, 0])
    assert (side <= 1e-12).all()
    outside = world_point_to_camera([0.0, 0.035, 0.01])
    assert (np.einsum("fj,fj->f", normals, outside - v[:, 0]) > 0).any()


def test_degenerate_inputs_raise() -> None:
    tf = TableFrame.from_plane(TablePlane(normal=np.array([0.0, -0.8, -0.6]), offset=0.7))
    with pytest.raises(DegenerateObject):
        build_object(np.zeros((3, 3)), tf, 0, PredicateSettings())
    line = np.column_stack([np.linspace(0, 0.1, 50), np.zeros(50), np.full(50, 0.5)])
    with pytest.raises(DegenerateObject):
        build_object(line, tf, 0, PredicateSettings())
