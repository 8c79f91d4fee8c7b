"""Tests of clearcli/settings/segment.py: section [segment]."""

from __future__ import annotations

from helpers.sections import assert_defaults_in_range, assert_numeric_bounds, refused

from clearcli.settings.segment import SegmentSettings


def test_defaults_lie_within_their_ranges() -> None:
    assert_defaults_in_range(SegmentSettings)
    d = SegmentSettings()
    assert d.seed_m >= d.voxel_m and d.prism_max_height_m > d.prism_min_height_m
    assert d.outlier_method == "depth_radius"


def test_every_number_is_refused_past_its_bounds_naming_its_key() -> None:
    assert_numeric_bounds(SegmentSettings)


def test_the_outlier_method_is_one_of_three() -> None:
    for method in ("depth_radius", "statistical", "none"):
        assert SegmentSettings(outlier_method=method).outlier_method == method
    error = refused(SegmentSettings, "outlier_method", "radius")
    assert "one of 'depth_radius', 'statistical', 'none'" in str(error)


def test_supervoxel_seeds_are_no_finer_than_the_voxels() -> None:
    assert SegmentSettings(voxel_m=0.01, seed_m=0.01).seed_m == 0.01
    error = refused(SegmentSettings, "seed_m", 0.009, voxel_m=0.01)
    assert "must be at least voxel_m (0.01)" in str(error)


def test_the_prism_keeps_a_band_of_heights() -> None:
    error = refused(SegmentSettings, "prism_max_height_m", 0.05, prism_min_height_m=0.05)
    assert "must be above prism_min_height_m (0.05)" in str(error)
    assert SegmentSettings(prism_min_height_m=0.05, prism_max_height_m=0.0501).prism_max_height_m == 0.0501


def test_off_switches_and_open_bounds() -> None:
    # 0 turns a filter off where the comments say so
    assert SegmentSettings(min_object_points=0, fragment_join_m=0).min_object_points == 0
    # a share of a ring's bands off the circle stays below 1 (all off is no circle)
    assert SegmentSettings(ring_max_off_share=0.999).ring_max_off_share == 0.999
    refused(SegmentSettings, "ring_max_off_share", 1.0)
    refused(SegmentSettings, "planar_cuts", 1)  # a switch is true or false
