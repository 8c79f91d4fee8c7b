"""A veil of mixed pixels is no object (issue 37, perception/exclude.py `_veil`): where a
near edge meets the far background the sensor returns depths between the two along each
pixel's ray. On a self-made frame, a strip of such pixels beside a tall box's edge is
excluded with its reason and the box kept; with the rule off the veil is an object. Thin
real things are kept: a 6 mm board standing face on, a thin box lying flat; and a thing
lying flat along the rays (seen as steeply as a veil) is no veil, for it keeps its height."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from clearcli.evaluate.segmentation import score
from clearcli.io.frames import LABEL_NONE, LABEL_TABLE, object_label
from clearcli.perception import exclude
from clearcli.perception.payload import segmentation_payload
from clearcli.perception.segment import segment
from clearcli.settings.segment import SegmentSettings
from clearcli.sim.camera import render
from clearcli.sim.scene import Box, make_scene

ON = dataclasses.replace(SegmentSettings(), exclude_not_standing=True)
VEIL_PX = 10  # pixels of the strip beside the edge: the first two lost (no depth), then the veil


def _frame_with_veil():  # -> Frame
    """A 20 cm tall box, a 6 mm board standing face on to the camera, a 1.5 cm thin box
    lying flat; beside the tall box's left edge in the image, on every row it covers, the
    table's pixels become mixed pixels: the two nearest the edge lose their depth (as a
    sensor's do there), the next eight lie on their own rays between the edge's range and
    the table's, 30 to 90 % of the way (labelled as nothing)."""
    tall = Box(0, 0.06, 0.06, 0.20, -0.05, 0.0)
    board = Box(1, 0.15, 0.006, 0.12, 0.15, 0.05)
    lying = Box(2, 0.03, 0.15, 0.015, -0.2, -0.05)
    frame = render(make_scene("veil", [tall, board, lying]), seed=0)
    assert frame.shape is not None
    h, w = frame.shape
    pts = frame.points.astype(np.float64).reshape(h, w, 3).copy()
    lab = np.asarray(frame.fields["label"]).reshape(h, w).copy()
    own = lab == object_label(0)
    for r in np.flatnonzero(own.any(axis=1)):
        c0 = int(np.flatnonzero(own[r])[0])
        near = float(np.linalg.norm(pts[r, c0]))
        for j in range(1, VEIL_PX + 1):
            c = c0 - j
            if lab[r, c] != LABEL_TABLE:
                continue
            lab[r, c] = LABEL_NONE
            if j <= 2:
                pts[r, c] = np.nan
                continue
            far = float(np.linalg.norm(pts[r, c]))
            f = 0.3 + 0.6 * (j - 3) / (VEIL_PX - 3)
            pts[r, c] *= ((1 - f) * near + f * far) / far
    return dataclasses.replace(
        frame, points=pts.reshape(-1, 3).astype(np.float32), fields={**frame.fields, "label": lab.ravel()}
    )


def test_a_veil_beside_an_edge_is_excluded_the_objects_kept(monkeypatch: pytest.MonkeyPatch) -> None:
    frame = _frame_with_veil()
    truth = np.asarray(frame.fields["label"])
    seg = segment(frame, ON)
    sc = score(seg.labels(), truth)
    # the tall box, the standing board and the lying box: each one object, nothing more
    assert sc.n_true == 3 and sc.n_pred == 3 and sc.true_positives == 3, (sc, [e.reason for e in seg.excluded])
    veils = [e for e in seg.excluded if e.reason.startswith("a veil")]
    assert len(veils) == 1 and len(seg.excluded) == 1, [e.reason for e in seg.excluded]
    assert np.mean(truth[veils[0].indices] == LABEL_NONE) > 0.95  # the mixed pixels, no object's
    assert veils[0].indices.size >= 300
    doc = segmentation_payload(seg)
    assert any(e["reason"] == veils[0].reason and e["points"] == veils[0].indices.size for e in doc["excluded"])
    # the rule off: the veil of the table's colour, lying against the tall box, is taken
    # for a fringe of the support's colour instead (`_fringe`, decided after the veils)
    monkeypatch.setattr(exclude, "_VEIL_ALONG", np.inf)
    fringe = segment(frame, ON)
    assert [e.indices.size for e in fringe.excluded] == [veils[0].indices.size]
    assert fringe.excluded[0].reason.startswith("a fringe of the support's colour")
    # and both off: the veil is an object of its own
    monkeypatch.setattr(exclude, "_FRINGE_OFF_SHARE", -1.0)
    off = segment(frame, ON)
    sc_off = score(off.labels(), truth)
    assert sc_off.n_pred == sc_off.n_true + 1 and not off.excluded
    assert np.mean(truth[np.concatenate([o.indices for o in off.objects])] == LABEL_NONE) > 0.05


def test_a_thing_lying_along_the_rays_keeps_its_height_and_is_no_veil(monkeypatch: pytest.MonkeyPatch) -> None:
    # a camera 0.3 m above the support looking 20 degrees down; a rod 25 cm long and 3 cm
    # thick lying on the support pointing away, 0.6 to 0.85 m off: seen as steeply as a
    # veil (its range spans 23 cm over 3 cm across), but its top stays level
    cam = np.array([0.0, 0.0, 0.3])
    rng = np.random.default_rng(0)
    n = 3000
    along = rng.uniform(0.6, 0.85, n)
    across = rng.uniform(-0.015, 0.015, n)
    top = 0.03 - across**2 / 0.03  # its rounded top, 2.3 to 3 cm high
    rod = np.column_stack([across, along, top]) - cam  # in the camera's frame (axes kept)
    # the height above the support: the camera 0.3 m above it
    assert exclude._veil(rod, rod[:, 2] + 0.3, 0.3, lambda p: p[:, 2] + 0.3) == ""
    # the same pixels' rays with depths spread between a near edge and the support (a veil:
    # its points on the rays): excluded
    rays = rod / np.linalg.norm(rod, axis=1, keepdims=True)
    far = 0.3 / -rays[:, 2]  # where each ray meets the support
    veil = rays * (far * rng.uniform(0.7, 0.98, n))[:, None]
    assert exclude._veil(veil, veil[:, 2] + 0.3, 0.3, lambda p: p[:, 2] + 0.3).startswith("a veil")
    # it is the fall that tells them apart: without it the rod is taken for a veil
    monkeypatch.setattr(exclude, "_VEIL_FALLS", -np.inf)
    monkeypatch.setattr(exclude, "_VEIL_RISE_M", -np.inf)
    assert exclude._veil(rod, rod[:, 2] + 0.3, 0.3, lambda p: p[:, 2] + 0.3).startswith("a veil")
