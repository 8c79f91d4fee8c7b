"""Grasp and push poses of one object (thesis 4.3), in the table frame.

Gripper frame as in `clearcli.geometry.gripper`: closing point at the origin, approach
+z, closing direction x. A pose is ``T_table_gripper`` (4x4). The gripper is symmetric
under a half-turn about its approach axis, so every pose has two candidates (x, y) and
(-x, -y); the IK check may pick either.

Grasp: the closing direction is orthogonal to the first principal direction, the approach
follows the top surface's third principal axis pointing into the table (straight down for
an object lying flat, or when that axis tilts more than ``max_grasp_tilt_deg``); the
closing point is the top-surface centroid moved along the approach by half the
closing-region height, raised where needed so that the fingertips stay
``fingertips_above_table_m`` above the table. Pre-grasp: ``approach_m`` back along the
approach; lift: ``approach_m`` straight up from the grasp.

Push directions: dir1 = +first principal direction (sign rule in
`clearcli.geometry.models._fix_sign`: away from the camera), dir2 = -dir1,
dir3 = dir1 turned +90 deg about the table normal, dir4 = -dir3.
Push pose (thesis 4.3.1, Fig. 4.12): approach straight down; closing direction parallel to
the push for dir1/dir2 (the narrow side of the closed finger pair leads, so the gripper
does not also push a neighbour beside a long object), orthogonal for dir3/dir4; fingertips
``fingertips_above_table_m`` above the table; the fingers ``gripper_behind_m`` behind the
object's rear face along the push, centred on the object across it. Pre-push:
``approach_m`` above the push pose. Push length: ``pushing_step`` times the object's extent
along the direction, at most ``push_length_limit_m``; the gripper path is cut into steps of
at most ``path_resolution_m``; retreat: ``approach_m`` above the end.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from clearcli.geometry.gripper import GripperModel
from clearcli.geometry.models import ObjectGeometry
from clearcli.geometry.settings import PushSettings

DIRECTION_NAMES: tuple[str, ...] = ("dir1", "dir2", "dir3", "dir4")
UP = np.array([0.0, 0.0, 1.0])


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    # np.cross costs ~20 us per call for 3-vectors; this is called per pose
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _pose(x: np.ndarray, z: np.ndarray, origin: np.ndarray) -> np.ndarray:
    y = _cross(z, x)
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = x, y, z, origin
    return T


def _half_turns(x: np.ndarray, z: np.ndarray, origin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return _pose(x, z, origin), _pose(-x, z, origin)


def _moved(T: np.ndarray, offset: np.ndarray) -> np.ndarray:
    out = T.copy()
    out[:3, 3] = out[:3, 3] + offset
    return out


@dataclass(frozen=True, eq=False)
class GraspGeometry:
    candidates: tuple[tuple[np.ndarray, ...], ...]  # per half-turn: pre-grasp, grasp, lift
    closing_dir: np.ndarray  # (3,) x of the first candidate
    approach: np.ndarray  # (3,)
    width_m: float  # the object's size across the closing direction

    @property
    def T_grasp(self) -> np.ndarray:
        return self.candidates[0][1]


@dataclass(frozen=True, eq=False)
class PushGeometry:
    direction: str
    unit: np.ndarray  # (3,) on the table
    length_m: float
    object_translations: np.ndarray  # (n, 3) along the path, the last is the end
    candidates: tuple[tuple[np.ndarray, ...], ...]  # per half-turn: pre, start, ..., end, retreat

    @property
    def T_start(self) -> np.ndarray:
        return self.candidates[0][1]


def grasp_geometry(
    obj: ObjectGeometry, gripper: GripperModel, push: PushSettings, max_tilt_deg: float
) -> GraspGeometry:
    half = gripper.settings.closing_region_height_m / 2.0
    tilt = math.degrees(math.acos(float(np.clip(obj.top_normal @ UP, -1.0, 1.0))))
    approach = -obj.top_normal if tilt <= max_tilt_deg else -UP
    a1 = np.array([obj.axes2d[0, 0], obj.axes2d[0, 1], 0.0])
    x = _cross(approach, a1)
    x = x / np.linalg.norm(x)
    point = obj.top_centroid + half * approach
    tip_height = float((point + half * approach)[2])
    if tip_height < push.fingertips_above_table_m:
        # raise it back along the approach until the fingertips clear the table
        point = point - approach * (push.fingertips_above_table_m - tip_height) / (-approach[2])
    # the object's width across the closing direction, measured on the footprint: a tilted
    # approach must not add the object's height to it
    across = np.array([x[0], x[1]]) / max(float(np.hypot(x[0], x[1])), 1e-12)
    width = float(np.ptp(obj.footprint @ across))
    cands = []
    for T in _half_turns(x, approach, point):
        pre = _moved(T, -push.approach_m * approach)
        lift = _moved(T, push.approach_m * UP)
        cands.append((pre, T, lift))
    return GraspGeometry(candidates=tuple(cands), closing_dir=x, approach=approach, width_m=width)


def direction_vectors(obj: ObjectGeometry) -> dict[str, np.ndarray]:
    """The four push directions (3,) in the table frame."""
    a1 = np.array([obj.axes2d[0, 0], obj.axes2d[0, 1], 0.0])
    a2 = np.array([obj.axes2d[1, 0], obj.axes2d[1, 1], 0.0])
    return {"dir1": a1, "dir2": -a1, "dir3": a2, "dir4": -a2}


def push_geometry(obj: ObjectGeometry, gripper: GripperModel, push: PushSettings) -> dict[str, PushGeometry]:
    g = gripper.settings
    out: dict[str, PushGeometry] = {}
    height = push.fingertips_above_table_m + g.closing_region_height_m / 2.0
    hull_xy = obj.hull_vertices[:, :2]
    c = obj.center.copy()
    c[2] = 0.0
    up_approach = push.approach_m * UP
    # half size of the closed finger pair along the push: its width across the fingers
    # (dir1/dir2, closing direction along the push) or a finger's width (dir3/dir4)
    half_parallel = gripper.finger_half_extent_along_x(closed=True)
    half_across = g.finger_width_m / 2.0
    for name, d in direction_vectors(obj).items():
        parallel = name in ("dir1", "dir2")
        x = d if parallel else _cross(UP, d)
        half_along = half_parallel if parallel else half_across
        rear = float((hull_xy @ d[:2]).min())
        lateral = c - (c @ d) * d
        start = lateral + (rear - push.gripper_behind_m - half_along) * d
        start[2] = height
        extent = float(obj.extents[0] if parallel else obj.extents[1])
        length = min(push.pushing_step * extent, push.push_length_limit_m)
        n = max(1, math.ceil(length / push.path_resolution_m - 1e-9))
        steps = length * np.arange(1, n + 1) / n
        translations = steps[:, None] * d[None, :]
        T, T_turned = _half_turns(x, -UP, start)
        seq = np.repeat(T[None], n + 3, axis=0)  # pre, start, path, retreat
        seq[0, :3, 3] += up_approach
        seq[2:-1, :3, 3] += translations
        seq[-1, :3, 3] += translations[-1] + up_approach
        # the half-turned candidate: the same positions, its own rotation
        turned = seq.copy()
        turned[:, :3, :3] = T_turned[:3, :3]
        out[name] = PushGeometry(
            direction=name,
            unit=d,
            length_m=length,
            object_translations=translations,
            candidates=(tuple(seq), tuple(turned)),
        )
    return out
