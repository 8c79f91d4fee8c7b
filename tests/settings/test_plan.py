"""Tests of clearcli/settings/plan.py: section [plan]; its grasp kinds come from the
registry of clearcli/settings/kinds.py."""

from __future__ import annotations

import pytest
from helpers.sections import assert_defaults_in_range, assert_numeric_bounds, refused

from clearcli.settings import kinds
from clearcli.settings.fields import range_of
from clearcli.settings.plan import PlanSettings


def test_defaults_lie_within_their_ranges() -> None:
    assert_defaults_in_range(PlanSettings)
    d = PlanSettings()
    assert (d.check, d.replay_check, d.formulation) == ("whole", "first", "positive")
    assert d.time_limit_s == 30.0


def test_every_number_is_refused_past_its_bounds() -> None:
    assert_numeric_bounds(PlanSettings)
    assert PlanSettings(time_limit_s=0.1).time_limit_s == 0.1
    refused(PlanSettings, "time_limit_s", 0.099)
    refused(PlanSettings, "max_backtracks", 0)


@pytest.mark.parametrize("key", ["check", "replay_check"])
def test_which_actions_are_checked_is_whole_or_first(key: str) -> None:
    assert getattr(PlanSettings(**{key: "first"}), key) == "first"
    error = refused(PlanSettings, key, "all")
    assert "one of 'whole', 'first'" in str(error)


def test_the_allowed_grasps_are_the_registered_kinds() -> None:
    rng = range_of(PlanSettings, "grasps")
    assert tuple(rng.members) == tuple(e.name for e in kinds.entries()) == ("pinch", "rim", "slide", "suction")
    assert tuple(rng.required) == ("pinch",)
    assert PlanSettings().grasps == kinds.default_kinds() == "pinch,rim,slide"


def test_grasps_are_a_set_kept_in_preference_order() -> None:
    assert PlanSettings(grasps="rim, pinch").grasps == "pinch,rim"
    assert PlanSettings(grasps=["slide", "pinch"]).grasps == "pinch,slide"
    assert PlanSettings(grasps="pinch").grasps == "pinch"  # the thesis's behaviour exactly
    for bad in ("rim", "slide,rim", "pinch,pinch", "pinch,twist", "", "pinch,"):
        error = refused(PlanSettings, "grasps", bad)
        assert "that includes pinch" in str(error)


def test_a_kind_added_to_the_registry_is_allowed_at_once(monkeypatch: pytest.MonkeyPatch) -> None:
    toy = kinds.KindEntry("twist", "a toy kind")
    monkeypatch.setattr(kinds, "GRASP_KINDS", (*kinds.GRASP_KINDS, toy))
    assert PlanSettings(grasps="twist,pinch").grasps == "pinch,twist"
    monkeypatch.undo()
    refused(PlanSettings, "grasps", "pinch,twist")
