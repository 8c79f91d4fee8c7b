"""Where the robot stands: T_base_camera (the points' optical frame in the robot's base
frame).

Three sources, in order of precedence:

1. ``--camera-pose x y z qx qy qz qw`` / ``[robot] camera_pose``: the optical frame's
   pose in the robot's base frame (the WAM's: DH frame 0, at the shoulder).
2. ``--camera-pose thesis``, for a profile whose ``thesis_camera`` says so (the WAM): the
   thesis's Kinect extrinsic (parameters.md), which is ``link_base -> camera_link`` (x
   forward, z up), composed with the fixed rotation from camera_link to the optical frame
   (z forward, x right, y down) the points are in.
3. Default, derived from the table found in the frame: the arm's footprint lies on the
   table plane just outside the table edge nearest the camera, its x axis facing the
   objects (their centroid on the plane), z along the table normal, the base frame the
   profile's ``base_above_footprint_m`` above the footprint (the WAM's shoulder 0.346 m);
   moved back if needed so that no object centroid is nearer than [robot]
   base_min_object_distance_m (a WAM cannot reach down right beside its own base: 0.30
   m), and farther, towards base_preferred_object_distance_m from the nearest, while the
   farthest stays within base_max_object_distance_m (room for pushes towards the base).
   Frames without calibration thus still give meaningful answers.

The arm's resolved value calls this (clearcli/robot/arm.py `Arm.place`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from clearcli import transforms
from clearcli.errors import SettingsError
from clearcli.robot.profiles import RobotProfile
from clearcli.robot.profiles import profile as named
from clearcli.settings.profiles import DEFAULT_PROFILE
from clearcli.settings.robot import RobotSettings

# Thesis extrinsic: estirabot_link_base -> camera_link (x y z, qx qy qz qw).
THESIS_BASE_CAMERA_LINK = (0.9014760, -0.0594, 0.7251720, -0.641407, 0.032404, 0.772933, 0.011045)
# Columns: the optical frame's axes in camera_link (x_opt = -y_link, y_opt = -z_link,
# z_opt = x_link).
R_CAMERA_LINK_OPTICAL = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


class _Centred(Protocol):
    @property
    def centroid(self) -> np.ndarray:
        """(3,) in the sensor frame."""
        ...


class _Plane(Protocol):
    @property
    def normal(self) -> np.ndarray:
        """(3,) unit, pointing up from the table."""
        ...

    @property
    def offset(self) -> float:
        """d of n . p + d = 0."""
        ...


class TableScene(Protocol):
    """What the default placement reads of a scene: the table (plane and outline) and the
    objects' centroids, in the sensor frame. `clearcli.predicates.state.SymbolicState` is
    one; the robot layer sits below predicates and names only what it uses."""

    @property
    def objects(self) -> Sequence[_Centred]: ...

    @property
    def table(self) -> _Plane: ...

    @property
    def table_polygon(self) -> np.ndarray:
        """(K, 3) the table's outline."""
        ...


def pose_to_matrix(pose: Sequence[float]) -> np.ndarray:
    """x y z qx qy qz qw -> 4x4."""
    if len(pose) != 7 or not all(np.isfinite(float(v)) for v in pose):
        raise SettingsError(f"camera pose: expected 7 finite numbers x y z qx qy qz qw, got {list(pose)!r}")
    try:
        return transforms.pose_to_matrix(pose[:3], pose[3:])
    except ValueError:
        raise SettingsError("camera pose: the quaternion must be non-zero") from None


def thesis_T_base_camera() -> np.ndarray:
    """The thesis setup's extrinsic, to the optical frame."""
    T = pose_to_matrix(THESIS_BASE_CAMERA_LINK)
    T[:3, :3] = T[:3, :3] @ R_CAMERA_LINK_OPTICAL
    return T


def _closest_on_polygon(point: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    a = polygon
    b = np.roll(polygon, -1, axis=0)
    ab = b - a
    denom = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-12)
    t = np.clip(np.einsum("ij,ij->i", point - a, ab) / denom, 0.0, 1.0)
    closest = a + t[:, None] * ab
    return closest[np.argmin(np.linalg.norm(closest - point, axis=1))]


def default_T_base_camera(
    table_normal: np.ndarray,
    table_offset: float,
    table_polygon: np.ndarray,
    object_centroids: np.ndarray | None,
    outside_edge_m: float,
    min_object_distance_m: float,
    preferred_object_distance_m: float,
    max_object_distance_m: float,
    base_above_footprint_m: float,
) -> np.ndarray:
    """Footprint just outside the table edge nearest the camera, facing the objects, and
    at least ``min_object_distance_m`` from every object's centroid (on the plane); then
    farther back, up to ``preferred_object_distance_m`` from the nearest object, as long
    as the farthest stays within ``max_object_distance_m``. The base frame is
    ``base_above_footprint_m`` above the footprint (the WAM's is its shoulder, 0.346 m
    up; a Panda's or a UR's is its mounting flange, on the table's plane)."""
    n = np.asarray(table_normal, dtype=float)
    n = n / np.linalg.norm(n)
    d = float(table_offset)

    def proj(p: np.ndarray) -> np.ndarray:
        return p - (p @ n + d) * n

    polygon = np.asarray(table_polygon, dtype=float).reshape(-1, 3)
    camera_on_table = proj(np.zeros(3))
    if len(polygon) >= 3:
        polygon = polygon - np.outer(polygon @ n + d, n)
        edge = _closest_on_polygon(camera_on_table, polygon)
        centre = polygon.mean(axis=0)
    else:
        edge = camera_on_table
        centre = camera_on_table
    outward = edge - centre
    outward -= (outward @ n) * n
    if np.linalg.norm(outward) < 1e-6:
        outward = camera_on_table - centre
        outward -= (outward @ n) * n
    if np.linalg.norm(outward) < 1e-6:
        outward = np.cross(n, [1.0, 0.0, 0.0])
    outward /= np.linalg.norm(outward)
    footprint = edge + outside_edge_m * outward
    if object_centroids is not None and len(object_centroids):
        target = proj(np.asarray(object_centroids, dtype=float).reshape(-1, 3).mean(axis=0))
    else:
        target = centre
    x = target - footprint
    x -= (x @ n) * n
    if np.linalg.norm(x) < 1e-6:
        x = -outward
    x /= np.linalg.norm(x)
    if object_centroids is not None and len(object_centroids) and min_object_distance_m > 0:
        # A table edge seen in the frame may be a crop of the real one, with objects
        # right at it: step back (away from the objects) until the nearest is at
        # min_object_distance_m, where a WAM can still reach down to it.
        flat = np.array([proj(c) for c in np.asarray(object_centroids, dtype=float).reshape(-1, 3)])
        for _ in range(20):
            gap = float(np.min(np.linalg.norm(flat - footprint, axis=1)))
            if gap >= min_object_distance_m - 1e-6:
                break
            footprint = footprint - x * (min_object_distance_m - gap)
        # Objects near the base are reachable for a grasp, but pushes towards the base
        # start 5-15 cm nearer still, where a top-down pose folds the WAM past its limits
        # (wrist centre within ~0.26 m of the shoulder axis: no IK). Step back further
        # while the farthest object stays well within reach.
        for _ in range(5):
            dist = np.linalg.norm(flat - footprint, axis=1)
            step = min(preferred_object_distance_m - float(dist.min()), max_object_distance_m - float(dist.max()))
            if step <= 1e-4:
                break
            footprint = footprint - x * step
    y = np.cross(n, x)
    T_camera_base = np.eye(4)
    T_camera_base[:3, :3] = np.column_stack([x, y, n])
    T_camera_base[:3, 3] = footprint + base_above_footprint_m * n
    return np.linalg.inv(T_camera_base)


def resolve_T_base_camera(
    camera_pose: Sequence[float] | str | None,
    state: TableScene | None = None,
    robot: RobotSettings | None = None,
    profile: RobotProfile | None = None,
) -> tuple[np.ndarray, str]:
    """T_base_camera and where it came from ("given", "thesis", "default from table");
    the default placement follows ``robot`` (the [robot] settings; their defaults when
    None: the distances have one home, clearcli/settings/robot.py) and ``profile`` (its
    mount height, whether the thesis's camera pose is its; the default profile when
    None)."""
    if robot is None:
        robot = RobotSettings()
    if profile is None:
        profile = named(DEFAULT_PROFILE)
    if isinstance(camera_pose, str):
        if camera_pose.strip().lower() == "thesis":
            if not profile.thesis_camera:
                raise SettingsError(
                    f"camera pose 'thesis' is where the thesis's camera stood relative to its WAM; with robot "
                    f"{profile.name!r} give the camera's pose as 7 numbers x y z qx qy qz qw, or none (placed from the table)"
                )
            return thesis_T_base_camera(), "thesis"
        try:
            values = [float(v) for v in camera_pose.replace(",", " ").split()]
        except ValueError:
            raise SettingsError(
                f"camera pose: expected 'thesis' or 7 numbers x y z qx qy qz qw, got {camera_pose!r}"
            ) from None
        return pose_to_matrix(values), "given"
    if camera_pose is not None and len(camera_pose) > 0:
        return pose_to_matrix(list(camera_pose)), "given"
    if state is None:
        raise SettingsError("camera pose: none given and no table to derive it from")
    centroids = np.array([o.centroid for o in state.objects]) if state.objects else None
    T = default_T_base_camera(
        state.table.normal,
        state.table.offset,
        state.table_polygon,
        centroids,
        robot.base_outside_edge_m,
        robot.base_min_object_distance_m,
        robot.base_preferred_object_distance_m,
        robot.base_max_object_distance_m,
        profile.base_above_footprint_m,
    )
    return T, "default from table"
