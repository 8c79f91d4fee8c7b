"""Tests of clearcli/settings/robot.py: section [robot] (which arm, where it stands, how IK
is searched); its names come from the profile registry (clearcli/settings/profiles.py)."""

from __future__ import annotations

import pytest
from helpers.sections import assert_defaults_in_range, assert_numeric_bounds, refused

from clearcli.settings.fields import range_of
from clearcli.settings.profiles import PROFILE_NAMES
from clearcli.settings.robot import RobotSettings


def test_defaults_lie_within_their_ranges_and_are_the_wams() -> None:
    assert_defaults_in_range(RobotSettings)
    d = RobotSettings()
    assert d.name == "wam" and d.urdf == "" and d.camera_pose == () and d.tcp_xyz_m == ()
    assert d.base_min_object_distance_m <= d.base_preferred_object_distance_m <= d.base_max_object_distance_m


def test_every_number_is_refused_past_its_bounds() -> None:
    assert_numeric_bounds(RobotSettings)


def test_the_names_are_the_registered_profiles() -> None:
    assert (
        tuple(range_of(RobotSettings, "name").choices)
        == tuple(PROFILE_NAMES)
        == ("wam", "panda", "ur5e", "panda-hybrid", "panda-suction", "ur5e-epick")
    )
    for name in PROFILE_NAMES:
        assert RobotSettings(name=name).name == name
    error = refused(RobotSettings, "name", "kuka")
    assert "one of 'wam', 'panda', 'ur5e'" in str(error)
    refused(RobotSettings, "name", "WAM")  # names are exact


def test_the_frames_and_tool_offset_describe_a_users_urdf_only() -> None:
    for key, value in (
        ("base_frame", "base"),
        ("flange_frame", "tool0"),
        ("tcp_xyz_m", (0, 0, 0.1)),
        ("tcp_yaw_deg", 90),
    ):
        error = refused(RobotSettings, key, value)
        assert "give urdf too" in str(error)
        built = RobotSettings(urdf="arm.urdf", **{key: value})  # the file is read later, where it is used
        assert getattr(built, key) == (tuple(float(v) for v in value) if isinstance(value, tuple) else value)


def test_the_tool_offset_is_three_numbers_within_half_a_metre_of_the_flange() -> None:
    assert RobotSettings(urdf="a.urdf", tcp_xyz_m=(0.3, 0.4, 0.0)).tcp_xyz_m == (0.3, 0.4, 0.0)  # 0.5 m exactly
    error = refused(RobotSettings, "tcp_xyz_m", (0.3, 0.4, 0.01), urdf="a.urdf")
    assert "within 0.5 m of the flange" in str(error)
    refused(RobotSettings, "tcp_xyz_m", (0.1, 0.1), urdf="a.urdf")  # 0 or 3 numbers
    refused(RobotSettings, "tcp_xyz_m", (0.6, 0.0, 0.0), urdf="a.urdf")  # each within +-0.5


def test_a_camera_pose_is_seven_numbers_with_a_nonzero_quaternion() -> None:
    pose = (0.1, 0.2, 0.9, 0.0, 0.0, 0.0, 1.0)
    assert RobotSettings(camera_pose=pose).camera_pose == pose
    refused(RobotSettings, "camera_pose", pose[:6])
    refused(RobotSettings, "camera_pose", (*pose[:6], float("nan")))
    error = refused(RobotSettings, "camera_pose", (0.1, 0.2, 0.9, 0.0, 0.0, 0.0, 0.0))
    assert "quaternion" in str(error)
    refused(RobotSettings, "camera_pose", (101.0, 0, 0, 0, 0, 0, 1))


def test_the_farthest_object_is_no_nearer_than_the_nearest() -> None:
    assert (
        RobotSettings(base_min_object_distance_m=0.5, base_max_object_distance_m=0.5).base_max_object_distance_m == 0.5
    )
    error = refused(RobotSettings, "base_max_object_distance_m", 0.29, base_min_object_distance_m=0.3)
    assert "must be at least base_min_object_distance_m (0.3)" in str(error)


@pytest.mark.parametrize("key", ["ik_seeds", "ik_max_iterations"])
def test_iteration_counts_are_positive_integers(key: str) -> None:
    refused(RobotSettings, key, 0)
    refused(RobotSettings, key, 2.5)
    assert getattr(RobotSettings(**{key: 2.0}), key) == 2
