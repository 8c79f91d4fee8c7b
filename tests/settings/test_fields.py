"""Tests of clearcli/settings/fields.py: what a setting is (a typed field, its default,
its range) and how a section checks every value when it is built, on a toy section made
here so that each rule is seen on its own."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import pytest

from clearcli.errors import SettingsError
from clearcli.settings.fields import Range, Section, check_value, param, range_of, set_of_names


@dataclass(frozen=True)
class Toy(Section):
    NAME = "toy"

    size_m: float = param(0.5, gt=0, le=1)
    count: int = param(3, ge=1, lt=10)
    mode: str = param("fast", choices=["fast", "slow"])  # a list: kept as a tuple
    path: str = param("", text='"" or a file')
    flag: bool = param(False)
    pose: tuple[float, ...] = param((), ge=-1, le=1, lengths=(0, 3))
    steps: tuple[float, ...] = param((0.1,), ge=0, le=1, max_items=2)
    kinds: str = param("a,b", members=("a", "b", "c"), required=("a",))
    low: float = param(0.1, ge=0, le=1)
    high: float = param(0.9, ge=0, le=1)

    def cross_checks(self) -> None:
        if self.high < self.low:
            self.fail("high", f"must be at least low ({self.low:g})")


def test_range_describes_what_it_accepts() -> None:
    assert Range(gt=0, le=0.5).describe() == "> 0 and <= 0.5"
    assert Range(ge=1, lt=10).describe() == ">= 1 and < 10"
    assert Range().describe() == "any finite number"
    assert Range(choices=("whole", "first")).describe() == "one of 'whole', 'first'"
    assert Range(text='"" or a URDF file').describe() == '"" or a URDF file'
    assert Range(ge=-1, le=1, lengths=(0, 7)).describe() == "a list of 0 or 7 numbers, each >= -1 and <= 1"
    assert Range(ge=0, max_items=10).describe() == "a list of at most 10 numbers, each >= 0"
    assert Range(members=("pinch", "rim"), required=("pinch",)).describe() == (
        "a comma-separated list of pinch, rim (any order, each at most once) that includes pinch"
    )


def test_range_holds_inclusive_and_exclusive_bounds_and_only_finite_numbers() -> None:
    r = Range(gt=0, le=1)
    assert [r.holds(v) for v in (0.0, 1e-12, 1.0, 1.0 + 1e-12)] == [False, True, True, False]
    r = Range(ge=0, lt=1)
    assert [r.holds(v) for v in (0.0, -1e-12, 1.0, 1.0 - 1e-12)] == [True, False, False, True]
    assert not any(Range().holds(v) for v in (math.nan, math.inf, -math.inf))
    assert Range().holds(-1e300)


def test_param_keeps_the_default_and_the_range_on_the_field() -> None:
    assert Toy().size_m == 0.5 and Toy().mode == "fast"
    assert range_of(Toy, "size_m") == Range(gt=0, le=1)
    assert range_of(Toy, "mode").choices == ("fast", "slow")  # the list became a tuple
    assert range_of(Toy, "pose").lengths == (0, 3)
    with pytest.raises(KeyError):
        range_of(Toy, "colour")


def test_a_live_sequence_of_choices_is_read_when_a_value_is_checked() -> None:
    names = ["a"]  # stands for a registry that grows (robot profiles, grasp kinds)

    class Live:
        def __iter__(self):  # type: ignore[no-untyped-def]
            return iter(names)

        def __contains__(self, item: object) -> bool:
            return item in names

    live = Live()
    field = param("a", choices=live)
    rng = field.metadata["range"]
    assert rng.choices is live  # kept, not copied
    with pytest.raises(SettingsError):
        check_value("s", "k", str, rng, "b")
    names.append("b")
    assert check_value("s", "k", str, rng, "b") == "b"


def test_building_a_section_checks_every_value_and_names_the_key() -> None:
    cases = {
        "size_m": (0, "out of range; accepted: > 0 and <= 1"),
        "count": (10, "out of range; accepted: >= 1 and < 10"),
        "mode": ("medium", "must be one of 'fast', 'slow'"),
        "flag": (1, "must be true or false"),
        "path": (3, "must be a string"),
        "pose": ((0.1, 0.2), "accepted: a list of 0 or 3 numbers"),
        "steps": ((0.1, 0.2, 0.3), "accepted: a list of at most 2 numbers"),
        "kinds": ("b,c", "that includes a"),
    }
    for key, (value, words) in cases.items():
        with pytest.raises(SettingsError) as info:
            Toy(**{key: value})
        assert str(info.value).startswith(f"settings: [toy] {key} = {value!r}: ")
        assert words in str(info.value), str(info.value)
        assert info.value.exit_code == 3


def test_numbers_are_finite_typed_and_converted() -> None:
    assert type(Toy(size_m=1).size_m) is float and Toy(size_m=1).size_m == 1.0  # an integer for a float
    assert Toy(count=4.0).count == 4 and type(Toy(count=4.0).count) is int  # a whole float for an int
    for bad in (4.5, True, "4", math.nan):
        with pytest.raises(SettingsError, match=r"\[toy\] count"):
            Toy(count=bad)
    for bad in (math.nan, math.inf, -math.inf, False, None):
        with pytest.raises(SettingsError, match=r"\[toy\] size_m"):
            Toy(size_m=bad)
    assert Toy(pose=[1, -1, 0]).pose == (1.0, -1.0, 0.0)  # a list becomes a tuple of floats
    for bad in ((1, 2, 0), (0, 0, math.nan), (0, True, 0), "0 0 0"):
        with pytest.raises(SettingsError, match=r"\[toy\] pose"):
            Toy(pose=bad)


def test_a_set_of_names_is_kept_in_the_members_order() -> None:
    rng = range_of(Toy, "kinds")
    assert set_of_names("w", "c, a", rng) == "a,c"
    assert set_of_names("w", ["b", "a"], rng) == "a,b"
    assert Toy(kinds="c,b,a").kinds == "a,b,c"
    for bad in ("a,a", "a,d", "a,,b", "", "b"):
        with pytest.raises(SettingsError, match="^w: must be a comma-separated list"):
            set_of_names("w", bad, rng)


def test_cross_checks_run_after_every_value_is_checked() -> None:
    assert Toy(low=0.5, high=0.5).high == 0.5
    with pytest.raises(SettingsError) as info:
        Toy(low=0.6, high=0.5)
    assert str(info.value) == "settings: [toy] high = 0.5: must be at least low (0.6)"
    # a value out of its own range is reported first, not the rule between keys
    with pytest.raises(SettingsError, match=r"\[toy\] low = 2"):
        Toy(low=2, high=0.5)


def test_sections_are_frozen_and_replace_checks_again() -> None:
    toy = Toy()
    with pytest.raises(dataclasses.FrozenInstanceError):
        toy.size_m = 0.2  # type: ignore[misc]
    assert dataclasses.replace(toy, size_m=0.25).size_m == 0.25
    with pytest.raises(SettingsError, match=r"\[toy\] size_m"):
        dataclasses.replace(toy, size_m=-0.25)


def test_a_string_with_a_nul_character_is_refused() -> None:
    # a NUL can be in no path or frame name; pathlib raises ValueError on it (the fuzz
    # harness found `--set robot.urdf="\u0000"` ending in an internal error)
    rng = Range(text='"" or a URDF file')
    assert check_value("robot", "urdf", str, rng, "arm.urdf") == "arm.urdf"
    with pytest.raises(SettingsError, match=r"\[robot\] urdf = 'a\\x00b': holds a NUL character; give \"\" or a URDF"):
        check_value("robot", "urdf", str, rng, "a\x00b")
