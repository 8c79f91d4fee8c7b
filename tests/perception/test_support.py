"""The support is the surface the objects stand on (issue 37, perception/support.py), on
self-made frames (clearcli.sim.families.SUPPORT_FAMILIES), each shown to need the step:
with ``support_by_standing`` off the same frame takes the wrong surface."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from clearcli.errors import EXIT_SCENE, SceneError
from clearcli.evaluate.segmentation import score
from clearcli.io.frames import Frame
from clearcli.perception.payload import segmentation_payload
from clearcli.perception.segment import segment
from clearcli.settings.segment import SegmentSettings
from clearcli.sim.families import support_frame

ON = SegmentSettings()
OFF = dataclasses.replace(ON, support_by_standing=False)


def _right(frame: Frame, settings: SegmentSettings) -> bool:
    sc = score(segment(frame, settings).labels(), frame.fields["label"])
    return sc.true_positives == sc.n_true == sc.n_pred


@pytest.mark.parametrize("seed", [1, 2])
def test_a_raised_surface_beats_the_floor_around_it(seed: int) -> None:
    # objects on a stool's top 75 cm above a floor that holds the stool's body and bags:
    # the floor has more points standing on it, the top holds the objects
    frame = support_frame("raised_surface", seed)
    seg = segment(frame, ON)
    assert _right(frame, ON)
    chosen = [v for v in seg.support if v.chosen]
    assert len(chosen) == 1 and "raised surface" in chosen[0].why
    assert any("floor around a raised surface" in v.why for v in seg.support if not v.chosen)
    doc = segmentation_payload(seg)
    assert doc["support"]["why"] == chosen[0].why
    assert any("floor" in r["why"] for r in doc["support"]["rejected"])
    # the step off: the floor is taken and the stool's body and the bags become objects
    off = segment(frame, OFF)
    assert not _right(frame, OFF)
    assert abs(off.table.offset) > abs(seg.table.offset) + 0.5


@pytest.mark.parametrize("seed", [4, 5])
def test_the_mat_the_objects_stand_on_is_the_support(seed: int) -> None:
    # a mat or board 10-16 mm thick on the table: the objects stand on it; the table's
    # plane leaves the mat in the prism, an "object" under the real ones
    frame = support_frame("mat_on_table", seed)
    seg = segment(frame, ON)
    assert _right(frame, ON)
    assert "mat or board" in next(v.why for v in seg.support if v.chosen)
    assert not _right(frame, OFF)


def test_a_camera_looking_down_at_a_floor_still_has_its_support() -> None:
    # the plain scene (one plane holding the objects) is unchanged by the step
    frame = support_frame("mat_on_table", 2)
    assert _right(frame, ON)
    seg = segment(frame, ON)
    assert [v.chosen for v in seg.support].count(True) == 1


def test_no_surface_holding_anything_is_exit_4_naming_the_surfaces() -> None:
    # a frame of a small patch only: no surface of table size; the one line names what
    # was considered
    frame = support_frame("mat_on_table", 2)
    pts = frame.points.copy()
    keep = np.zeros(frame.shape, dtype=bool)
    keep[300:315, :] = True  # a strip of table 15 pixels tall (a few cm)
    keep = keep.ravel()
    pts[~keep] = np.nan
    bad = dataclasses.replace(frame, points=pts)
    with pytest.raises(SceneError) as err:
        segment(bad, ON)
    assert err.value.exit_code == EXIT_SCENE
    assert "\n" not in str(err.value) and "considered" in str(err.value)
