"""The settings tree: every section registered, ranges checked wherever a value comes
from, `--set` parsed like the file."""

from __future__ import annotations

import dataclasses
import math

import pytest

from clearcli.errors import SettingsError
from clearcli.settings import (
    SECTIONS,
    Settings,
    apply_sets,
    load_settings,
    parse_set,
    settings_from_dict,
    settings_to_toml,
)
from clearcli.settings.fields import range_of


def test_every_parameter_set_is_a_section_of_the_tree() -> None:
    # the seven sets the issue found unreachable are sections now
    for name in ("tracking", "memory", "replay", "world", "world_reach", "camera", "depth_noise"):
        assert name in SECTIONS
    text = settings_to_toml(Settings())
    for name in SECTIONS:
        assert f"[{name}]" in text


def test_printed_tree_reads_back_as_the_same_settings(tmp_path) -> None:
    changed = apply_sets(
        Settings(), ["tracking.gate_m=0.05", "world.frame_interval_s=2.5", "segment.outlier_method=none"]
    )
    path = tmp_path / "s.toml"
    path.write_text(settings_to_toml(changed))
    assert load_settings(path) == changed
    assert load_settings(path).tracking.gate_m == 0.05
    assert load_settings(path).world.frame_interval_s == 2.5


def test_set_values_are_read_as_toml() -> None:
    assert parse_set("segment.voxel_m=0.004") == ("segment", "voxel_m", 0.004)
    assert parse_set("push.raised_fingertips_m=[0.03, 0.05]") == ("push", "raised_fingertips_m", [0.03, 0.05])
    assert parse_set("segment.depth_edges=false") == ("segment", "depth_edges", False)
    assert parse_set("plan.formulation=negative") == ("plan", "formulation", "negative")
    assert math.isnan(parse_set("segment.voxel_m=nan")[2])
    for bad in ("segment.voxel_m", "voxel_m=1", ".x=1", "segment.=1"):
        with pytest.raises(SettingsError, match="SECTION.KEY=VALUE"):
            parse_set(bad)


@pytest.mark.parametrize(
    "data, words",
    [
        ({"segment": {"voxel_m": 0}}, ["[segment] voxel_m = 0", ">= 0.001"]),
        ({"segment": {"seed_m": float("nan")}}, ["[segment] seed_m = nan", "out of range"]),
        ({"segment": {"table_cell_m": -0.02}}, ["table_cell_m", ">= 0.002"]),
        ({"segment": {"normal_radius_m": 0}}, ["normal_radius_m", ">= 0.002"]),
        ({"segment": {"supervoxel_iterations": 10**9}}, ["supervoxel_iterations", "<= 50"]),
        ({"segment": {"outlier_method": "median"}}, ["outlier_method", "'depth_radius'"]),
        ({"plan": {"time_limit_s": -30}}, ["time_limit_s", ">= 0.1"]),
        ({"tracking": {"gate_m": float("inf")}}, ["[tracking] gate_m = inf", "> 0"]),
        ({"world": {"tight_grasp_fail_probability": 2}}, ["tight_grasp_fail_probability", "<= 1"]),
        ({"robot": {"camera_pose": [1, 2, 3]}}, ["camera_pose", "a list of 0 or 7 numbers"]),
        ({"segment": {"voxel_m": "small"}}, ["voxel_m", "must be a number"]),
        ({"segment": {"ransac_iterations": 2.5}}, ["ransac_iterations", "an integer"]),
        ({"segment": {"voxel_m": True}}, ["voxel_m", "must be a number"]),
        ({"segmnt": {"voxel_m": 0.005}}, ["unknown section", "segmnt"]),
        ({"segment": {"voxl_m": 0.005}}, ["unknown key", "voxl_m"]),
    ],
)
def test_bad_values_name_the_key_the_value_and_the_range(data, words) -> None:
    with pytest.raises(SettingsError) as err:
        settings_from_dict(data)
    message = str(err.value)
    assert "\n" not in message
    for w in words:
        assert w in message


def test_a_section_checks_its_values_whoever_builds_it() -> None:
    from clearcli.settings.segment import SegmentSettings

    with pytest.raises(SettingsError, match="voxel_m"):
        SegmentSettings(voxel_m=0.0)
    with pytest.raises(SettingsError, match="seed_m"):
        SegmentSettings(voxel_m=0.02, seed_m=0.01)  # seeds closer than voxels


def test_every_field_declares_a_range_or_is_a_flag() -> None:
    for name, cls in SECTIONS.items():
        for f in dataclasses.fields(cls):
            value = getattr(cls(), f.name)
            if isinstance(value, bool):
                continue
            rng = range_of(cls, f.name)
            assert (
                rng.choices
                or rng.members
                and isinstance(value, str)
                or rng.text
                and isinstance(value, str)
                or (rng.ge is not None or rng.gt is not None)
                and (rng.le is not None or rng.lt is not None)
            ), f"[{name}] {f.name} has no range"


def test_defaults_in_one_place_placement_follows_the_robot_section() -> None:
    """The placement's preferred distance comes from [robot], with no default of its
    own in the function signature (it had drifted to 0.0)."""
    import inspect

    from clearcli.robot import placement

    for fn in (getattr(placement, n) for n in dir(placement)):
        if inspect.isfunction(fn) and fn.__module__ == placement.__name__:
            p = inspect.signature(fn).parameters.get("preferred_object_distance_m")
            assert p is None or p.default is inspect.Parameter.empty, fn.__name__
