"""Tests of clearcli/robot/placement.py."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.robot import _trans

from clearcli.errors import SettingsError
from clearcli.robot import placement


def test_thesis_camera_pose() -> None:
    T = placement.thesis_T_base_camera()
    R = T[:3, :3]
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-6)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-6)
    link = placement.pose_to_matrix(placement.THESIS_BASE_CAMERA_LINK)
    # the optical z (viewing direction) is camera_link's x; optical y (down) is -z_link
    np.testing.assert_allclose(R[:, 2], link[:3, 0], atol=1e-9)
    np.testing.assert_allclose(R[:, 1], -link[:3, 2], atol=1e-9)
    np.testing.assert_allclose(T[:3, 3], [0.901476, -0.0594, 0.725172])
    # the camera looks down towards the table in front of the robot
    assert R[2, 2] < -0.5 and R[0, 2] < 0


def test_camera_pose_parsing() -> None:
    T, src = placement.resolve_T_base_camera("1 2 3 0 0 0 1")
    assert src == "given"
    np.testing.assert_allclose(T, _trans(1, 2, 3))
    T, src = placement.resolve_T_base_camera((0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0))
    np.testing.assert_allclose(T[:3, :3], np.diag([-1.0, -1.0, 1.0]), atol=1e-12)
    with pytest.raises(SettingsError):
        placement.resolve_T_base_camera("1 2 3")
    with pytest.raises(SettingsError):
        placement.resolve_T_base_camera("1 2 3 0 0 0 0")
    with pytest.raises(SettingsError):
        placement.resolve_T_base_camera("left")


def test_default_placement_from_table() -> None:
    """With no step back (preferred distance 0, a valid setting) the footprint stands
    just outside the near edge."""
    from helpers import plan_scenes as ps

    from clearcli.settings.robot import RobotSettings

    state = ps.clutter(3)
    T, src = placement.resolve_T_base_camera(None, state, RobotSettings(base_preferred_object_distance_m=0.0))
    assert src == "default from table"
    # Rebuild the scene's world frame: the table is z = 0, near edge x = 0, camera above
    # x = -0.05; the footprint should be at x = -0.10 (just outside the near edge),
    # facing +x (the objects), the shoulder 0.346 m above.
    T_world_base = ps.T_WORLD_CAMERA @ np.linalg.inv(T)
    np.testing.assert_allclose(T_world_base[:3, 3], [-0.10, 0.0, 0.346], atol=0.02)
    np.testing.assert_allclose(T_world_base[:3, 2], [0, 0, 1], atol=1e-9)
    assert T_world_base[0, 0] > 0.95  # base x towards the objects (+x)


@pytest.mark.parametrize(
    "near_x, far_x, preferred, footprint_x",
    [
        # nearest 0.25 m from the default footprint (x = -0.10): back to the 0.30 m floor
        (0.15, 0.45, 0.0, -0.15),
        # then on to 0.40 m from the nearest: the farthest ends 0.70 m away (<= 0.85)
        (0.15, 0.45, 0.40, -0.25),
        # the farthest would pass 0.85 m: stop where it reaches it (0.70 + 0.15 = 0.85)
        (0.15, 0.65, 0.40, -0.20),
        # far objects alone: the floor and the reach limit both hold already
        (0.15, 0.70, 0.40, -0.15),
    ],
)
def test_default_placement_steps_back_within_reach(
    near_x: float, far_x: float, preferred: float, footprint_x: float
) -> None:
    from helpers import plan_scenes as ps

    from clearcli.settings.robot import RobotSettings

    state = ps.scene({"a": ps.Box(near_x, 0.0), "b": ps.Box(far_x, 0.0)})
    robot = RobotSettings(
        base_outside_edge_m=0.10,
        base_min_object_distance_m=0.30,
        base_preferred_object_distance_m=preferred,
        base_max_object_distance_m=0.85,
    )
    T, _ = placement.resolve_T_base_camera(None, state, robot)
    T_world_base = ps.T_WORLD_CAMERA @ np.linalg.inv(T)
    np.testing.assert_allclose(T_world_base[:3, 3], [footprint_x, 0.0, 0.346], atol=1e-3)
