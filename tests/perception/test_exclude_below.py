"""An upright face that goes on below the support's level beneath itself is no object
(issue 37, perception/exclude.py `_beneath_below`): a chair's back or a board standing on
the floor at the table's edge rises above the table's level; the table's fit keeps its strip
at that level as support, so the hull grows to it and no rule about the outline sees it, but
the camera sees its face go on down past the table's level, beneath its own footprint.
Self-made frames: desk_behind(seed)'s objects on the table and a board 35 cm wide and 2 cm
thick standing on the floor just in front of or behind the table. With the rule off the
board is an object."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from clearcli.evaluate.segmentation import score
from clearcli.io.frames import LABEL_NONE, object_label
from clearcli.perception import exclude
from clearcli.perception.payload import segmentation_payload
from clearcli.perception.segment import segment
from clearcli.settings.segment import SegmentSettings
from clearcli.sim.camera import FLOOR_BELOW_TABLE_M, render
from clearcli.sim.families import FURNITURE_ID, desk_behind
from clearcli.sim.scene import Box, Table, make_scene

ON = dataclasses.replace(SegmentSettings(), exclude_not_standing=True)


def _board_frame(seed: int, gap_m: float, rise_m: float, far: bool):  # -> Frame
    """desk_behind(seed)'s objects on the table (floor rendered); a board 35 cm wide, 2 cm
    thick, from the floor to ``rise_m`` above the table's top, ``gap_m`` beyond its far
    (``far``) or near edge. The board's labels are none."""
    objs = [o for o in desk_behind(seed).objects if o.object_id < FURNITURE_ID]
    y = (1.0 if far else -1.0) * (Table().size_y_m / 2 + gap_m + 0.01)
    board = Box(
        FURNITURE_ID, 0.35, 0.02, round(FLOOR_BELOW_TABLE_M + rise_m, 4), 0.0, round(y, 4), 0.0, -FLOOR_BELOW_TABLE_M
    )
    frame = render(make_scene(f"board({seed})", [*objs, board]), seed=seed, floor=True)
    labels = np.asarray(frame.fields["label"]).copy()
    labels[labels >= object_label(FURNITURE_ID)] = LABEL_NONE
    return dataclasses.replace(frame, fields={**frame.fields, "label": labels})


@pytest.mark.parametrize(
    "seed, gap_m, rise_m, far",
    [(0, 0.01, 0.08, False), (1, 0.005, 0.10, False), (3, 0.04, 0.12, True)],
)
def test_a_board_at_the_table_edge_going_on_below_its_level_is_excluded(
    seed: int, gap_m: float, rise_m: float, far: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    frame = _board_frame(seed, gap_m, rise_m, far)
    truth = np.asarray(frame.fields["label"])
    seg = segment(frame, ON)
    sc = score(seg.labels(), truth)
    assert sc.true_positives == sc.n_true == sc.n_pred, (sc, [e.reason for e in seg.excluded])
    boards = [e for e in seg.excluded if "goes on below the support's level" in e.reason]
    assert len(boards) == 1 and len(seg.excluded) == 1, [e.reason for e in seg.excluded]
    assert np.mean(truth[boards[0].indices] == LABEL_NONE) > 0.95  # the board's points, no object's
    doc = segmentation_payload(seg)
    assert any(e["reason"] == boards[0].reason and e["points"] == boards[0].indices.size for e in doc["excluded"])
    # the rule off: the board is an object (a plan would try to grasp it)
    monkeypatch.setattr(exclude, "_BENEATH_SHARE", np.inf)
    off = segment(frame, ON)
    sc_off = score(off.labels(), truth)
    assert sc_off.true_positives == sc_off.n_true and sc_off.n_pred == sc_off.n_true + 1 and not off.excluded


def test_the_floor_under_the_table_is_no_face_going_on(monkeypatch: pytest.MonkeyPatch) -> None:
    # the floor under the table, seen past its near edge, lies beneath the objects near that
    # edge in the plane's coordinates; 75 cm down, it is no face's continuation: with the
    # board behind the table (the floor in view) every object stays one
    frame = _board_frame(3, 0.04, 0.12, True)
    truth = np.asarray(frame.fields["label"])
    seg = segment(frame, ON)
    assert all(np.mean(truth[e.indices] == LABEL_NONE) > 0.95 for e in seg.excluded), [e.reason for e in seg.excluded]
    # the depth bound off (`_BELOW_DEEP_M`): the floor under the table takes objects for faces going on
    monkeypatch.setattr(exclude, "_BELOW_DEEP_M", np.inf)
    wide = segment(frame, ON)
    taken = [e for e in wide.excluded if "goes on below" in e.reason and np.mean(truth[e.indices] >= 10) > 0.95]
    assert taken, [e.reason for e in wide.excluded]
