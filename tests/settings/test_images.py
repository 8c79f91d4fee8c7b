"""Tests of clearcli/settings/images.py: section [images] (how depth images are read)."""

from __future__ import annotations

import pytest
from helpers.sections import assert_defaults_in_range, assert_numeric_bounds, refused

from clearcli.settings.images import MAX_SUFFIX_BYTES, ImageSettings


def test_defaults_lie_within_their_ranges() -> None:
    assert_defaults_in_range(ImageSettings)
    d = ImageSettings()
    # millimetres, as RealSense, Kinect and most datasets write 16-bit depth
    assert (d.depth_scale_m, d.depth_suffix, d.color_suffix, d.intrinsics) == (0.001, "_depth", "_color", "")


def test_the_depth_scale_is_positive_and_finite() -> None:
    assert_numeric_bounds(ImageSettings)
    assert ImageSettings(depth_scale_m=1).depth_scale_m == 1.0


def test_the_intrinsics_are_free_text_checked_where_used() -> None:
    assert ImageSettings(intrinsics="525 525 319.5 239.5").intrinsics == "525 525 319.5 239.5"
    refused(ImageSettings, "intrinsics", 525.0)  # text, not a number


@pytest.mark.parametrize("key", ["depth_suffix", "color_suffix"])
def test_a_suffix_names_a_file_beside_the_image(key: str) -> None:
    error = refused(ImageSettings, key, "/depth")
    assert "no '/'" in str(error)
    refused(ImageSettings, key, "_d\x00")
    # at most 64 bytes, counted in UTF-8: 32 two-byte letters fit, 33 do not
    assert MAX_SUFFIX_BYTES == 64
    assert getattr(ImageSettings(**{key: "_" + "a" * 63}), key) == "_" + "a" * 63
    assert getattr(ImageSettings(**{key: "\u00e9" * 32}), key) == "\u00e9" * 32
    error = refused(ImageSettings, key, "\u00e9" * 33)
    assert "at most 64 bytes" in str(error)


def test_the_depth_suffix_is_not_empty_and_differs_from_the_colour_one() -> None:
    refused(ImageSettings, "depth_suffix", "")
    error = refused(ImageSettings, "color_suffix", "_d", depth_suffix="_d")
    assert "must differ from depth_suffix" in str(error)
    # swapped names are two different endings
    swapped = ImageSettings(depth_suffix="_color", color_suffix="_depth")
    assert (swapped.depth_suffix, swapped.color_suffix) == ("_color", "_depth")
    assert ImageSettings(color_suffix="").color_suffix == ""  # `<stem>.png` the colour image


def test_a_depth_unit_below_a_nanometre_is_refused() -> None:
    # its reciprocal (units per metre) overflows, and its metres underflow float32
    from clearcli.errors import SettingsError

    assert ImageSettings(depth_scale_m=1e-9).depth_scale_m == 1e-9
    with pytest.raises(SettingsError, match=r"depth_scale_m = 5e-324: out of range; accepted: >= 1e-09"):
        ImageSettings(depth_scale_m=5e-324)
