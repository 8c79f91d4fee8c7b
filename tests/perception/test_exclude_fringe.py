"""A fringe of the support's colour against an object is no object (issue 37,
perception/exclude.py `_fringe`): an object's depth smeared over the support beside it (a
depth image registered a few pixels off the colour image, a stereo sensor's fattened
edge), cut off by the colour split because the colour image shows the support there. On
self-made points, and on the real uois_image_0006 (../shared/data)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from helpers.exclude import flat_support_verdicts
from helpers.foreign import labelled

from clearcli.evaluate.exact import exact_report
from clearcli.perception import exclude
from clearcli.perception.payload import segmentation_payload
from clearcli.perception.segment import segment
from clearcli.settings.segment import SegmentSettings

ON = dataclasses.replace(SegmentSettings(), exclude_not_standing=True)


def _slab(x0: float, x1: float, y0: float, y1: float, z0: float, z1: float, step: float = 0.004) -> np.ndarray:
    """Points filling a box on a grid of ``step`` (m)."""
    axes = [np.arange(a, b + 1e-9, step) for a, b in ((x0, x1), (y0, y1), (z0, z1))]
    return np.stack(np.meshgrid(*axes), -1).reshape(-1, 3)


# a tin 14 cm tall (median 7 cm) and, 4 mm from its side, a strip 2 cm wide rising from
# the support to 4 cm (its top, 95th percentile, 4 cm: 3 cm under the tin's median)
TIN = _slab(0.0, 0.06, 0.0, 0.06, 0.0, 0.14)
STRIP = _slab(-0.024, -0.004, 0.0, 0.06, 0.0, 0.04)


def test_a_strip_of_the_supports_colour_against_a_taller_object_is_a_fringe() -> None:
    found = flat_support_verdicts([TIN, STRIP], off_colour=[0.4, 0.0])
    assert len(found) == 1 and found[0].startswith("1: a fringe of the support's colour"), found
    # one pixel in a hundred of another colour (1 %: under the 2 %) is still the support's
    assert len(flat_support_verdicts([TIN, STRIP], off_colour=[0.4, 0.01])) == 1


@pytest.mark.parametrize(
    "objects, off_colour",
    [
        ([TIN, STRIP], [0.4, 0.05]),  # 5 % of its pixels another colour: an object of its own
        ([TIN, STRIP], None),  # no colour: not decided
        ([STRIP], [0.0]),  # of the support's colour but alone: an object of the table's colour
        ([TIN, _slab(-0.024, -0.004, 0.0, 0.06, 0.0, 0.06)], [0.4, 0.0]),  # its top 1 cm under the tin's median
        ([TIN, STRIP + np.array([-0.02, 0.0, 0.0])], [0.4, 0.0]),  # 2.4 cm away: touches nothing
    ],
)
def test_what_is_no_fringe_stays(objects: list[np.ndarray], off_colour: list[float] | None) -> None:
    assert flat_support_verdicts(objects, off_colour=off_colour) == []


def test_the_fringes_on_uois_image_0006_are_excluded_with_their_reason(monkeypatch: pytest.MonkeyPatch) -> None:
    # the RealSense's depth lies a few pixels off its colour image: the depth of the cup
    # and of the tin behind the eraser spreads over the table beside them (heights 1.4 to
    # 4.5 cm), and the colour split cuts those pieces off (on the choose part, the only two
    # spurious segments of the uois frames)
    frame, truth, _ = labelled("uois_image_0006")
    seg = segment(frame, ON)
    fringes = [e for e in seg.excluded if e.reason.startswith("a fringe of the support's colour")]
    assert len(fringes) == 2, [e.reason for e in seg.excluded]
    for e in fringes:
        assert np.mean(truth[e.indices] >= 10) < 0.2  # hardly any labelled object's points
    doc = segmentation_payload(seg)
    assert sum(e["reason"].startswith("a fringe") for e in doc["excluded"]) == 2
    right = exact_report(seg.labels(), truth)
    assert right.spurious == 0
    monkeypatch.setattr(exclude, "_FRINGE_OFF_SHARE", -1.0)  # the rule off
    off = segment(frame, ON)
    assert len(off.objects) == len(seg.objects) + 2
    assert exact_report(off.labels(), truth).spurious == 2
