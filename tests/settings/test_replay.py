"""Tests of clearcli/settings/replay.py: sections [replay], [tracking], [memory]."""

from __future__ import annotations

from helpers.sections import range_tests, refused

from clearcli.settings.replay import MemoryParams, ReplaySettings, TrackingParams

test_defaults_lie_within_their_ranges, test_every_number_is_refused_past_its_bounds_naming_its_key = range_tests(
    ReplaySettings, TrackingParams, MemoryParams
)


def test_the_closed_loop_switches_are_booleans_on_by_default() -> None:
    d = ReplaySettings()
    assert (d.push_memory, d.stop_when_cleared) == (True, True)
    assert ReplaySettings(push_memory=False).push_memory is False
    refused(ReplaySettings, "push_memory", 0)
    refused(ReplaySettings, "stop_when_cleared", "yes")


def test_tracking_gates_and_fractions() -> None:
    refused(TrackingParams, "gate_m", 0)  # a gate of nothing matches nothing
    assert TrackingParams(push_done_fraction=1).push_done_fraction == 1.0
    refused(TrackingParams, "push_done_fraction", 0)
    refused(TrackingParams, "push_done_fraction", 1.01)
    assert TrackingParams(max_missing_frames=0).max_missing_frames == 0  # forget at once
    refused(TrackingParams, "max_missing_frames", 1.5)


def test_memory_is_bounded_and_angles_are_degrees() -> None:
    for key in ("per_object", "max_objects", "horizon_frames"):
        refused(MemoryParams, key, 0)  # at least one of each
    assert MemoryParams(reverse_angle_deg=180).reverse_angle_deg == 180.0
    refused(MemoryParams, "reverse_angle_deg", 180.5)
    assert MemoryParams(reverse_penalty=0).reverse_penalty == 0
    refused(MemoryParams, "reverse_penalty", 10.5)
