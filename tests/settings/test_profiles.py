"""Tests of clearcli/settings/profiles.py: the robot profiles' registry (names, the module
holding each, the [robot] and [gripper] defaults each supplies), what `[robot] name`
accepts and what `--robot` and `clear robots` list."""

from __future__ import annotations

import dataclasses
import importlib

import pytest
from helpers import shared_path

from clearcli.errors import SettingsError
from clearcli.settings import profiles
from clearcli.settings.geometry import GripperSettings
from clearcli.settings.robot import RobotSettings

SECTION = {"robot": RobotSettings, "gripper": GripperSettings}


def test_the_registered_profiles_with_the_wam_first() -> None:
    assert list(profiles.REGISTRY) == ["wam", "panda", "ur5e", "panda-hybrid", "panda-suction", "ur5e-epick"]
    assert profiles.DEFAULT_PROFILE == "wam"
    assert list(profiles.PROFILE_NAMES) == list(profiles.REGISTRY) and len(profiles.PROFILE_NAMES) == 6
    assert (
        profiles.PROFILE_NAMES[0] == "wam" and "ur5e" in profiles.PROFILE_NAMES and "kuka" not in profiles.PROFILE_NAMES
    )
    assert profiles.names_text() == "wam (default), panda, ur5e, panda-hybrid, panda-suction, ur5e-epick"
    # the tools: fingers alone, a cup alone, or both
    assert [profiles.tools_of(n) for n in profiles.REGISTRY] == [
        ("fingers",),
        ("fingers",),
        ("fingers",),
        ("fingers", "cup"),
        ("cup",),
        ("cup",),
    ]
    assert profiles.profiles_with("cup") == ("panda-hybrid", "panda-suction", "ur5e-epick")


def test_each_profile_names_a_module_holding_its_profile() -> None:
    for name, entry in profiles.REGISTRY.items():
        module = importlib.import_module(entry.module)
        assert hasattr(module, "PROFILE"), name


@pytest.mark.parametrize("name", ["wam", "panda", "ur5e"])
def test_a_profiles_defaults_are_valid_values_of_robot_and_gripper(name: str) -> None:
    defaults = profiles.profile_defaults(name)
    assert set(defaults) <= {"robot", "gripper"}
    for section, values in defaults.items():
        cls = SECTION[section]
        known = {f.name for f in dataclasses.fields(cls)}
        assert set(values) <= known, (name, section)
        built = cls(**values)  # every value checked by the section, the rules between keys too
        assert all(getattr(built, k) == v for k, v in values.items())


def test_the_wam_supplies_nothing_the_sections_do_not_already_say() -> None:
    assert profiles.profile_defaults("wam") == {}
    with pytest.raises(KeyError):
        profiles.profile_defaults("kuka")


def test_the_grippers_are_the_makers_figures() -> None:
    readme = shared_path("robots/README.md").read_text(encoding="utf-8")
    # the README of ../shared/data/robots, from the makers' specifications
    assert "opens to 0.080 m" in readme and "0.1034 m past the flange" in readme and "opens to 0.085 m" in readme
    panda = profiles.profile_defaults("panda")["gripper"]
    assert panda["opening_width_m"] == 0.08 and panda["gripper_height_m"] == 0.1034
    assert profiles.profile_defaults("ur5e")["gripper"]["opening_width_m"] == 0.085
    # and each reach: the farthest object stays inside it (Panda ~0.855 m, UR5e ~0.850 m)
    assert "reach about 0.855 m" in readme and "reach about 0.850 m" in readme
    for name in ("panda", "ur5e"):
        assert profiles.profile_defaults(name)["robot"]["base_max_object_distance_m"] < 0.85


def test_a_profile_added_to_the_registry_is_a_robot_name_at_once(monkeypatch: pytest.MonkeyPatch) -> None:
    with pytest.raises(
        SettingsError, match=r"\[robot\] name = 'toy': must be one of 'wam', 'panda', 'ur5e', 'panda-hybrid'"
    ):
        RobotSettings(name="toy")
    registry = {**profiles.REGISTRY, "toy": profiles.ProfileEntry("tests.helpers.robot")}
    monkeypatch.setattr(profiles, "REGISTRY", registry)
    assert "toy" in profiles.PROFILE_NAMES and list(profiles.PROFILE_NAMES)[-1] == "toy"
    assert RobotSettings(name="toy").name == "toy"
    assert profiles.names_text().endswith(", ur5e-epick, toy")


def test_entries_compare_by_identity() -> None:
    a = profiles.ProfileEntry("m", {"robot": {}})
    b = profiles.ProfileEntry("m", {"robot": {}})
    assert a != b and a == a and len({a, b}) == 2
