"""Tests of clearcli/tasks/robots.py: the robot profiles (`clear robots`), one profile's
facts, and the early check of a user's URDF.

The joints and their limits are checked against the shipped URDF files read here with
ElementTree (not Pinocchio, which the task uses)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from clearcli.errors import SettingsError
from clearcli.settings.profiles import REGISTRY, profile_defaults
from clearcli.settings.robot import RobotSettings
from clearcli.tasks import robots as task

# the arms and their movable joints (the makers' figures: WAM and Panda 7, UR5e 6)
ARMS = {"wam": 7, "panda": 7, "ur5e": 6}


def _urdf_joints(path: Path) -> dict[str, tuple[float, float]]:
    """Movable joints of a URDF and their position limits, in file order."""
    found = {}
    for joint in ET.parse(path).getroot().iter("joint"):
        if joint.get("type") in ("revolute", "prismatic"):
            limit = joint.find("limit")
            assert limit is not None
            found[joint.get("name")] = (float(limit.get("lower")), float(limit.get("upper")))
    return found


def test_the_list_names_every_profile_with_wam_the_default() -> None:
    payload = task.robots_payload()
    profiles = payload["profiles"]
    assert (
        [p["name"] for p in profiles]
        == ["wam", "panda", "ur5e", "panda-hybrid", "panda-suction", "ur5e-epick"]
        == list(REGISTRY)
    )
    assert [p["default"] for p in profiles] == [True] + [False] * 5
    assert all(isinstance(p["summary"], str) and p["summary"] for p in profiles)
    assert (task.SCHEMA, task.VERSION) == ("robots", 1)


@pytest.mark.parametrize("name", sorted(ARMS))
def test_a_profiles_facts_give_the_joints_of_its_description(name: str) -> None:
    facts = task.robots_payload(name)["profile"]
    assert facts["name"] == name
    urdf = Path(facts["urdf"])
    assert urdf.is_file()
    joints = _urdf_joints(urdf)
    assert len(facts["joints"]) == len(joints) == ARMS[name]
    assert [j["name"] for j in facts["joints"]] == list(joints)
    for j in facts["joints"]:
        assert (j["lower_rad"], j["upper_rad"]) == pytest.approx(joints[j["name"]], abs=1e-9)
        assert j["lower_rad"] < j["upper_rad"]
    # the [robot]/[gripper] defaults it supplies are the registry's
    assert facts["defaults"] == {k: dict(v) for k, v in profile_defaults(name).items()}
    assert 0.5 < facts["reach_m"] < 1.5


def test_an_unknown_profile_is_a_settings_error_listing_the_known_ones() -> None:
    with pytest.raises(SettingsError) as info:
        task.robots_payload("kuka")
    assert info.value.exit_code == 3
    assert "kuka" in str(info.value) and "wam, panda, ur5e" in str(info.value)


def test_check_robot_reads_a_users_urdf_before_any_frame(tmp_path: Path) -> None:
    task.check_robot(RobotSettings())  # a profile's own description: nothing to read
    own = tmp_path / "arm.urdf"
    own.write_text((Path(task.robots_payload("ur5e")["profile"]["urdf"])).read_text())
    task.check_robot(RobotSettings(urdf=str(own)))  # a good description passes
    cases = {
        "missing.urdf": None,
        "garbage.urdf": "this is not XML",
        "one_link.urdf": "<robot name='x'><link name='a'/></robot>",
    }
    for file_name, text in cases.items():
        path = tmp_path / file_name
        if text is not None:
            path.write_text(text)
        with pytest.raises(SettingsError) as info:
            task.check_robot(RobotSettings(urdf=str(path)))
        assert str(path) in str(info.value) and info.value.exit_code == 3
