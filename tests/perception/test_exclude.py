"""Only what stands on the support is an object (issue 37, perception/exclude.py): on
self-made frames (clearcli.sim.families.SUPPORT_FAMILIES), each shown to need the step:
with ``exclude_not_standing`` off the same frame has spurious objects."""

from __future__ import annotations

import dataclasses

import pytest

from clearcli.evaluate.segmentation import score
from clearcli.perception.payload import segmentation_payload
from clearcli.perception.segment import segment
from clearcli.settings.segment import SegmentSettings
from clearcli.sim.camera import render
from clearcli.sim.families import FURNITURE_ID, SUPPORT_FAMILIES, support_frame
from clearcli.sim.scene import make_scene

# the step is off by default (clearcli/settings/segment.py says why): on here
ON = dataclasses.replace(SegmentSettings(), exclude_not_standing=True)
OFF = dataclasses.replace(ON, exclude_not_standing=False)


@pytest.mark.parametrize("name, seed", [("arm_entering", 0), ("arm_entering", 2)])
def test_what_reaches_in_from_beyond_the_support_is_excluded(name: str, seed: int) -> None:
    frame = support_frame(name, seed)
    seg = segment(frame, ON)
    sc = score(seg.labels(), frame.fields["label"])
    assert sc.true_positives == sc.n_true == sc.n_pred
    assert seg.excluded and any("reaches in from beyond" in e.reason for e in seg.excluded)
    doc = segmentation_payload(seg)
    assert [e["reason"] for e in doc["excluded"]] == [e.reason for e in seg.excluded]
    assert all(e["points"] > 0 for e in doc["excluded"])
    # the step off: the arm (the desk's front) is an object
    off = segment(frame, OFF)
    sc_off = score(off.labels(), frame.fields["label"])
    assert sc_off.n_pred > sc_off.n_true and not off.excluded


def test_the_arm_filling_the_view_leaves_an_empty_object_list_with_the_reason() -> None:
    scene = SUPPORT_FAMILIES["arm_entering"](0)
    arm_only = make_scene("arm only", [o for o in scene.objects if o.object_id >= FURNITURE_ID])
    seg = segment(render(arm_only, seed=0), ON)
    assert seg.objects == ()
    assert seg.excluded and all(e.reason for e in seg.excluded)
    doc = segmentation_payload(seg)
    assert doc["objects"] == [] and doc["excluded"]
