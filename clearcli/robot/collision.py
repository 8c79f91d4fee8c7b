"""What the arm may hit: the table plane and the objects' convex hulls, in the robot's base
frame, tested against spheres covering the arm's capsules (the IK check of thesis 4.3)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from clearcli.settings.robot import RobotSettings


def hull_planes(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(F,4) outward face planes (n, d) with n.x + d <= 0 inside the convex hull."""
    v = np.asarray(vertices, dtype=float)
    f = np.asarray(faces, dtype=int)
    if len(v) == 0 or len(f) == 0:
        return np.zeros((0, 4))
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    n = np.cross(b - a, c - a)
    norm = np.linalg.norm(n, axis=1)
    keep = norm > 1e-12
    n = n[keep] / norm[keep, None]
    a = a[keep]
    d = -np.einsum("ij,ij->i", n, a)
    inside = v.mean(axis=0)
    flip = n @ inside + d > 0
    n[flip] *= -1
    d[flip] *= -1
    return np.column_stack([n, d])


def capsule_spheres(a: np.ndarray, b: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Spheres covering capsules, spaced at half a radius: (S,3) centres, (S,) radii."""
    a, b, r = (
        np.asarray(a, dtype=float).reshape(-1, 3),
        np.asarray(b, dtype=float).reshape(-1, 3),
        np.asarray(r, dtype=float),
    )
    if r.size == 0:  # an arm without collision geometry (its meshes missing)
        return np.zeros((0, 3)), np.zeros(0)
    # n spheres a capsule, evenly from a to b (t = k / (n - 1)): one array operation for
    # all capsules, the same spheres as one linspace each
    n = np.maximum(2, np.ceil(np.linalg.norm(b - a, axis=1) / (0.5 * r)).astype(np.int64) + 1)
    which = np.repeat(np.arange(r.size), n)
    k = np.arange(which.size) - np.repeat(np.cumsum(n) - n, n)
    m = n[which] - 1
    t = k * (1.0 / m)  # as numpy's linspace computes it, its last value exactly 1
    t[k == m] = 1.0
    t = t[:, None]
    return a[which] + t * (b[which] - a[which]), r[which]


@dataclass
class Obstacles:
    """Table plane and object hulls in the robot base frame."""

    table_normal: np.ndarray  # (3,) up
    table_offset: float  # n.x + d = height above the table
    names: tuple[str, ...] = ()
    planes: tuple[np.ndarray, ...] = ()  # (F,4) per object
    boxes: tuple[tuple[np.ndarray, np.ndarray], ...] = ()  # AABB per object
    margin_m: float = 0.01  # set by make_obstacles from [robot] collision_margin_m

    def collisions(self, centres: np.ndarray, radii: np.ndarray, ignore: Sequence[str] = ()) -> list[str]:
        """What the spheres touch: "table" and/or object names."""
        hit: list[str] = []
        heights = centres @ self.table_normal + self.table_offset
        if np.any(heights < radii + self.margin_m):
            hit.append("table")
        if not self.names:
            return hit
        reach = radii + self.margin_m
        lo, hi = self._stacked_boxes()
        # every sphere against every object's box in one array operation (the IK check
        # calls this for each pose of each candidate: a loop per object cost more than
        # the test itself); the face planes only for the objects some sphere is near
        c = centres[:, None, :]
        r = reach[:, None, None]
        near_all = np.all((c + r > lo) & (c - r < hi), axis=2)  # (spheres, objects)
        for j in np.flatnonzero(near_all.any(axis=0)):
            name, planes = self.names[j], self.planes[j]
            if name in ignore or len(planes) == 0:
                continue
            near = near_all[:, j]
            # Largest face-plane distance: a lower bound of the true distance, so this
            # errs towards "collides" near the hull's edges and corners.
            dist = np.max(centres[near] @ planes[:, :3].T + planes[:, 3], axis=1)
            if np.any(dist < reach[near]):
                hit.append(name)
        return hit

    def _stacked_boxes(self) -> tuple[np.ndarray, np.ndarray]:
        got = self.__dict__.get("_boxes_stacked")
        if got is None:
            lo = np.array([b[0] for b in self.boxes], dtype=float).reshape(-1, 3)
            hi = np.array([b[1] for b in self.boxes], dtype=float).reshape(-1, 3)
            got = self.__dict__["_boxes_stacked"] = (lo, hi)
        return got


def make_obstacles(state: Any, T_base_camera: np.ndarray, margin_m: float | None = None) -> Obstacles:
    """Table and object hulls of a SymbolicState, moved into the base frame; the arm keeps
    ``margin_m`` from them (None: [robot] collision_margin_m)."""
    if margin_m is None:
        margin_m = RobotSettings().collision_margin_m
    R, t = T_base_camera[:3, :3], T_base_camera[:3, 3]
    n_cam = np.asarray(state.table.normal, dtype=float)
    n = R @ n_cam
    # A point on the table in the camera frame: -d n; moved to the base frame.
    p = R @ (-float(state.table.offset) * n_cam) + t
    names, planes, boxes = [], [], []
    for obj in state.objects:
        v = np.asarray(obj.hull_vertices, dtype=float)
        if len(v) == 0:
            continue
        vb = v @ R.T + t
        names.append(obj.name)
        planes.append(hull_planes(vb, obj.hull_faces))
        boxes.append((vb.min(axis=0), vb.max(axis=0)))
    return Obstacles(n, float(-n @ p), tuple(names), tuple(planes), tuple(boxes), margin_m)
