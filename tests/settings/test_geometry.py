"""Tests of clearcli/settings/geometry.py: sections [gripper], [push], [predicates]."""

from __future__ import annotations

import math

import pytest
from helpers.sections import range_tests, refused

from clearcli.settings.geometry import GripperSettings, PredicateSettings, PushSettings

test_defaults_lie_within_their_ranges, test_every_number_is_refused_past_its_bounds_naming_its_key = range_tests(
    GripperSettings, PushSettings, PredicateSettings
)


def test_the_gripper_defaults_are_the_iri_grippers() -> None:
    g = GripperSettings()
    # parameters.md: the IRI parallel gripper opens to 7 cm and closes to 3 cm
    assert (g.opening_width_m, g.closing_width_m, g.closed_gap_m) == (0.07, 0.03, 0.03)
    assert GripperSettings.NAME == "gripper"


def test_the_closing_width_may_reach_the_opening_but_not_pass_it() -> None:
    assert GripperSettings(opening_width_m=0.05, closing_width_m=0.05).closing_width_m == 0.05
    error = refused(GripperSettings, "closing_width_m", 0.06, opening_width_m=0.05)
    assert "must be at most opening_width_m (0.05)" in str(error)
    # the rule sees the values the section holds, not the defaults: a wider gripper takes it
    assert GripperSettings(opening_width_m=0.1, closing_width_m=0.08).closing_width_m == 0.08


def test_raised_pushes_are_a_short_list_of_heights() -> None:
    assert PushSettings().raised_fingertips_m == (0.03, 0.05, 0.07)
    assert PushSettings(raised_fingertips_m=()).raised_fingertips_m == ()  # off
    assert PushSettings(raised_fingertips_m=[0.5] * 10).raised_fingertips_m == (0.5,) * 10
    refused(PushSettings, "raised_fingertips_m", [0.01] * 11)
    refused(PushSettings, "raised_fingertips_m", [0.01, 0.51])
    refused(PushSettings, "raised_fingertips_m", [0.01, -0.01])
    refused(PushSettings, "raised_fingertips_m", [0.01, math.nan])
    refused(PushSettings, "raised_fingertips_m", 0.03)  # one number is no list


def test_the_clearance_cost_must_stay_an_integer_fast_downward_takes() -> None:
    # cost = ceil(exp(gain (d0 - d))): gain * d0 up to 20 (e^20 ~ 4.9e8)
    p = PredicateSettings(clearance_cost_gain_per_m=400.0, clearance_cost_distance_m=0.05)
    assert p.clearance_cost_gain_per_m * p.clearance_cost_distance_m == pytest.approx(20.0)
    error = refused(PredicateSettings, "clearance_cost_gain_per_m", 401.0, clearance_cost_distance_m=0.05)
    assert "must be <= 20" in str(error)
    # parameters.md: cost 1 at d >= 0.05 m, else ceil(exp(100 (0.05 - d))): e^5 at d = 0
    d = PredicateSettings()
    assert (d.clearance_cost_distance_m, d.clearance_cost_gain_per_m, d.clearance_cost) == (0.05, 100.0, False)
    assert math.ceil(math.exp(d.clearance_cost_gain_per_m * d.clearance_cost_distance_m)) == 149


def test_counts_of_points_are_integers() -> None:
    assert PredicateSettings(on_threshold_points=100.0).on_threshold_points == 100
    refused(PredicateSettings, "on_threshold_points", 100.5)
    refused(PredicateSettings, "min_object_points", 0)  # at least one point to model
