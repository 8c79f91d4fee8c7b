"""Self-made table scenes for tests and benchmarks: boxes seen by a camera above.

A scene is described in a world frame with z up and the table at z = 0; the camera looks
down at the table from ``camera_xyz`` (default: 0.6 m up, 0.5 m back, about 50 deg down,
like the mOSD Kinect). Each box is sampled on a grid on the faces the camera can see
(the top and the sides facing it); points inside another box (a face covered by a box
standing on it) are dropped. Returns a `Frame` (sensor frame) and a `Segmentation`
whose objects are the boxes in the given order.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clearcli.io.frames import Frame, object_ids, table_mask
from clearcli.perception.types import Segmentation, SegmentedObject, TablePlane


@dataclass(frozen=True)
class Box:
    center_xy: tuple[float, float]
    size: tuple[float, float, float]  # length (along yaw), width, height, metres
    yaw_deg: float = 0.0
    base_z: float = 0.0  # bottom face height (the top of the box it stands on)


def pca_object(indices: np.ndarray, points: np.ndarray) -> SegmentedObject:
    """A SegmentedObject whose box and principal axes come from the PCA of its points."""
    centroid = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - centroid, full_matrices=False)
    if np.linalg.det(vt) < 0:
        vt[2] = -vt[2]
    local = (points - centroid) @ vt.T
    lo, hi = local.min(axis=0), local.max(axis=0)
    return SegmentedObject(
        indices=indices,
        centroid=centroid,
        obb_center=centroid + ((lo + hi) / 2.0) @ vt,
        obb_axes=vt,
        obb_extents=hi - lo,
        principal_axes=vt,
    )


def camera_pose(
    camera_xyz: tuple[float, float, float] = (-0.5, 0.0, 0.6), target_xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
) -> np.ndarray:
    """T_world_camera of an optical-frame camera (z forward, y down) at camera_xyz."""
    c = np.asarray(camera_xyz, float)
    z = np.asarray(target_xyz, float) - c
    z /= np.linalg.norm(z)
    x = np.cross(z, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, y, z])
    T[:3, 3] = c
    return T


def _box_frame(box: Box) -> tuple[np.ndarray, np.ndarray]:
    yaw = np.radians(box.yaw_deg)
    R = np.array([[np.cos(yaw), -np.sin(yaw), 0.0], [np.sin(yaw), np.cos(yaw), 0.0], [0.0, 0.0, 1.0]])
    center = np.array([box.center_xy[0], box.center_xy[1], box.base_z + box.size[2] / 2.0])
    return R, center


def _grid(n_u: int, n_v: int) -> np.ndarray:
    u, v = np.meshgrid(np.linspace(-0.5, 0.5, n_u), np.linspace(-0.5, 0.5, n_v), indexing="ij")
    return np.column_stack([u.ravel(), v.ravel()])


def sample_box(box: Box, camera_world: np.ndarray, spacing_m: float = 0.005) -> np.ndarray:
    """World points on the faces of ``box`` that face the camera (edges included)."""
    R, center = _box_frame(box)
    half = np.asarray(box.size, float) / 2.0
    out = []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            normal_local = np.zeros(3)
            normal_local[axis] = sign
            face_center = center + R @ (normal_local * half)
            if (R @ normal_local) @ (camera_world - face_center) <= 0.0:
                continue  # faces away from the camera
            if axis == 2 and sign < 0:
                continue  # the bottom
            others = [a for a in range(3) if a != axis]
            sizes = 2.0 * half[others]
            g = _grid(max(2, int(round(sizes[0] / spacing_m)) + 1), max(2, int(round(sizes[1] / spacing_m)) + 1))
            local = np.zeros((len(g), 3))
            local[:, others[0]] = g[:, 0] * sizes[0]
            local[:, others[1]] = g[:, 1] * sizes[1]
            local[:, axis] = sign * half[axis]
            out.append(local @ R.T + center)
    return np.vstack(out)


def _inside(points: np.ndarray, box: Box, tol: float) -> np.ndarray:
    R, center = _box_frame(box)
    local = (points - center) @ R
    return np.all(np.abs(local) <= np.asarray(box.size) / 2.0 + tol, axis=1)


def make_scene(
    boxes: list[Box],
    camera_xyz: tuple[float, float, float] = (-0.5, 0.0, 0.6),
    table_half_size_m: tuple[float, float] = (0.4, 0.5),
    spacing_m: float = 0.005,
    source: str = "synthetic",
) -> tuple[Frame, Segmentation]:
    T_world_camera = camera_pose(camera_xyz)
    cam = T_world_camera[:3, 3]
    R = T_world_camera[:3, :3]
    chunks, labels = [], []
    for k, box in enumerate(boxes):
        pts = sample_box(box, cam, spacing_m)
        covered = np.zeros(len(pts), dtype=bool)
        for j, other in enumerate(boxes):
            if j != k:
                covered |= _inside(pts, other, 1e-4)
        pts = pts[~covered]
        chunks.append(pts)
        labels.append(np.full(len(pts), k))
    # the table, coarse: only its outline matters here
    hx, hy = table_half_size_m
    g = _grid(int(2 * hx / 0.02) + 1, int(2 * hy / 0.02) + 1) * [2 * hx, 2 * hy]
    table = np.column_stack([g, np.zeros(len(g))])
    free = np.ones(len(table), dtype=bool)
    for box in boxes:
        free &= ~_inside(table, box, 1e-4)
    table = table[free]
    world = np.vstack([*chunks, table]) if chunks else table
    cam_pts = (world - cam) @ R  # R^T (p - c), row-wise
    n_obj = sum(len(c) for c in chunks)
    frame = Frame(points=cam_pts.astype(np.float32), source=source)
    normal = R.T @ np.array([0.0, 0.0, 1.0])
    plane = TablePlane(normal=normal, offset=float(cam[2]))
    corners = np.array([[-hx, -hy, 0], [hx, -hy, 0], [hx, hy, 0], [-hx, hy, 0]], float)
    objects = []
    start = 0
    for pts in chunks:
        idx = np.arange(start, start + len(pts), dtype=np.int64)
        start += len(pts)
        objects.append(pca_object(idx, cam_pts[idx]))
    seg = Segmentation(
        n_points=len(cam_pts),
        table=plane,
        table_polygon=(corners - cam) @ R,
        table_indices=np.arange(n_obj, len(cam_pts), dtype=np.int64),
        objects=tuple(objects),
        source=source,
    )
    return frame, seg


def segmentation_from_labels(frame: Frame, min_points: int = 50) -> Segmentation:
    """A Segmentation from a frame's ground-truth ``label`` field (mOSD: 1..9 table,
    label // 10 = object id): for tests and benchmarks of later stages without the
    segmentation stage. Table plane: least squares over the table points, normal towards
    the camera; polygon: their 2D convex hull."""
    from scipy.spatial import ConvexHull

    labels = np.asarray(frame.fields["label"]).reshape(-1)
    finite = frame.finite_mask
    pts = frame.points.astype(float)
    table_idx = np.nonzero(finite & table_mask(labels))[0]
    tp = pts[table_idx]
    c = tp.mean(axis=0)
    _, _, vt = np.linalg.svd(tp - c, full_matrices=False)
    n = vt[2]
    d = -float(n @ c)
    if d < 0:  # the camera (origin) must be above the table
        n, d = -n, -d
    plane = TablePlane(normal=n, offset=d)
    # polygon: hull in a plane basis
    e1 = np.cross(n, [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    proj = plane.project(tp)
    uv = np.column_stack([proj @ e1, proj @ e2])
    polygon = proj[ConvexHull(uv).vertices]
    ids = object_ids(labels)
    objects = []
    for oid in np.unique(ids[finite & (ids > 0)]):
        idx = np.nonzero(finite & (ids == oid))[0]
        if len(idx) < min_points:
            continue
        objects.append(pca_object(idx.astype(np.int64), pts[idx]))
    return Segmentation(
        n_points=frame.n_points,
        table=plane,
        table_polygon=polygon,
        table_indices=table_idx.astype(np.int64),
        objects=tuple(objects),
        source=frame.source,
    )
