"""Checks shared by the tests of the settings sections (tests/settings/test_<area>.py):
every default within its declared range, and a value past a bound refused with a
SettingsError that names the section and the key, a value on an inclusive bound taken.

The bounds are read from each field's declared `Range` (clearcli/settings/fields.py); the
values tried past them are worked out here (a bound itself when exclusive, a step beyond
it when inclusive), so a bound that the check does not enforce, or enforces the other way
round, fails."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any

import pytest

from clearcli.errors import ClearError, SettingsError
from clearcli.settings.fields import range_of


def fields(cls: type) -> list[dataclasses.Field]:
    return list(dataclasses.fields(cls))


def numeric_keys(cls: type) -> list[str]:
    default = cls()
    return [f.name for f in fields(cls) if type(getattr(default, f.name)) in (int, float)]


def assert_defaults_in_range(cls: type) -> None:
    """Each default of ``cls`` lies in its declared range (numbers: bounds, finite; text
    with choices: one of them; name sets: members, required ones in; lists: item bounds
    and lengths), and the defaults build the section."""
    default = cls()
    for f in fields(cls):
        value = getattr(default, f.name)
        rng = range_of(cls, f.name)
        where = f"[{cls.NAME}] {f.name} = {value!r}"  # type: ignore[attr-defined]
        if isinstance(value, bool):
            continue
        if isinstance(value, (int, float)):
            assert math.isfinite(value) and rng.holds(float(value)), where
        elif isinstance(value, str):
            if rng.choices:
                assert value in rng.choices, where
            if rng.members:
                items = value.split(",")
                assert set(items) <= set(rng.members) and set(rng.required) <= set(items), where
        elif isinstance(value, tuple):
            assert all(rng.holds(float(v)) for v in value), where
            if rng.lengths:
                assert len(value) in rng.lengths, where
            if rng.max_items is not None:
                assert len(value) <= rng.max_items, where


def refused(cls: type, key: str, value: Any, **others: Any) -> SettingsError:
    """Building ``cls`` with ``key = value`` raises a SettingsError naming the section and key."""
    with pytest.raises(ClearError) as info:
        cls(**{**others, key: value})
    error = info.value
    assert isinstance(error, SettingsError) and error.exit_code == 3, repr(error)
    assert f"[{cls.NAME}] {key} = " in str(error), str(error)  # type: ignore[attr-defined]
    return error


def taken(cls: type, key: str, value: Any) -> None:
    """``key = value`` passes ``key``'s own range check (a rule between keys, a cross
    check, may still refuse it beside the other keys' defaults: not as out of range)."""
    try:
        built = cls(**{key: value})
    except SettingsError as exc:
        assert "out of range" not in str(exc) and "must be an integer" not in str(exc), str(exc)
        return
    assert getattr(built, key) == value


def _step(bound: float) -> float:
    return max(abs(bound) * 1e-6, 1e-9)


def assert_numeric_bounds(cls: type) -> None:
    """For every number of ``cls``: NaN and infinities refused; each declared bound
    enforced on the right side (exclusive bounds refused on the bound, inclusive ones
    taken on it and refused a step past it); zero and negatives refused where the range
    excludes them; a float field given an integer keeps its type."""
    default = cls()
    for key in numeric_keys(cls):
        rng = range_of(cls, key)
        is_int = type(getattr(default, key)) is int
        for bad in (math.nan, math.inf, -math.inf):
            refused(cls, key, bad)
        if rng.gt is not None:
            refused(cls, key, int(rng.gt) if is_int and float(rng.gt).is_integer() else rng.gt)
        if rng.lt is not None:
            refused(cls, key, rng.lt)
        if rng.ge is not None:
            taken(cls, key, int(rng.ge) if is_int else float(rng.ge))
            refused(cls, key, (int(rng.ge) - 1) if is_int else rng.ge - _step(rng.ge))
        if rng.le is not None:
            taken(cls, key, int(rng.le) if is_int else float(rng.le))
            refused(cls, key, (int(rng.le) + 1) if is_int else rng.le + _step(rng.le))
        if not rng.holds(0.0):
            refused(cls, key, 0)
        if not rng.holds(-1.0):
            refused(cls, key, -1)
        if is_int:
            refused(cls, key, getattr(default, key) + 0.5)  # not an integer
        refused(cls, key, True)  # a bool is no number here
        refused(cls, key, "1")  # nor is text


def range_tests(*sections: type) -> tuple[Callable[[type], None], Callable[[type], None]]:
    """The two tests every module of sections runs on each of ``sections`` (a test id
    each by its section's name): its defaults within their ranges, and every number
    refused past its bounds naming its key. A module binds them to its own test names:

        test_defaults_lie_within_their_ranges, test_every_number_is_refused_past_its_bounds_naming_its_key = (
            range_tests(A, B)
        )
    """

    @pytest.mark.parametrize("cls", sections, ids=lambda c: c.NAME)
    def defaults_in_range(cls: type) -> None:
        assert_defaults_in_range(cls)

    @pytest.mark.parametrize("cls", sections, ids=lambda c: c.NAME)
    def numbers_refused_past_bounds(cls: type) -> None:
        assert_numeric_bounds(cls)

    return defaults_in_range, numbers_refused_past_bounds
