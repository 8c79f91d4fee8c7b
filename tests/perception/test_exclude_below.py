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
    # the rule off: the board is an object (a plan would try to grasp it); its foot, which
    # goes on below the table's level too, off as well (`_foot_below`)
    monkeypatch.setattr(exclude, "_BENEATH_SHARE", np.inf)
    monkeypatch.setattr(exclude, "_FOOT_BELOW_SHARE", np.inf)
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


@pytest.mark.parametrize(("below_x_m", "goes_on"), [(0.457, True), (0.462, False)])
def test_what_goes_on_below_outside_the_outline_is_found_among_a_far_floors_points(
    below_x_m: float, goes_on: bool
) -> None:
    # z-up, the prism's side at x = 0.43: a flat thing resting on the support (z = 12 mm)
    # from x = 0.36 to 0.44, 21 points a column along y; below the support's level outside,
    # a line of points at z = 5 mm along its end, and a far floor of 3000 points at -0.7 m.
    # Its edge column x = 0.44 is sqrt(17^2 + 7^2) = 18.4 mm from the line at x = 0.457
    # (within the 20 mm reach: 21 points touch, at least 15 do: it goes on below), 22.1 mm
    # from the line at 0.462 (none does); the next column (x = 0.436) 22.1 mm from 0.457.
    from clearcli.perception.exclude import not_standing

    xs, ys = np.meshgrid(np.arange(0.36, 0.44 + 1e-9, 0.004), np.arange(-0.04, 0.04 + 1e-9, 0.004))
    thing = np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, 0.012)])
    line_y = np.arange(-0.04, 0.04 + 1e-9, 0.004)
    line = np.column_stack([np.full(line_y.size, below_x_m), line_y, np.full(line_y.size, 0.005)])
    rng = np.random.default_rng(4)
    floor = np.column_stack([rng.uniform(-1.0, 1.0, (3000, 2)), np.full(3000, -0.7)])
    gx, gy = np.meshgrid(np.arange(-0.4, 0.4 + 1e-9, 0.01), np.arange(-0.3, 0.3 + 1e-9, 0.01))
    support = np.column_stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)])
    found = not_standing(
        [thing],
        np.zeros((0, 3)),
        np.vstack([floor, line]),
        support[:, :2],  # in-plane: the support lies in z = 0
        lambda p: p[:, 2],
        lambda p: p[:, :2],
        lambda p: (np.abs(p[:, 0]) <= 0.43) & (np.abs(p[:, 1]) <= 0.33),
        lambda p: 0.013,
    )
    reasons = [v.reason for v in found]
    if goes_on:
        assert len(reasons) == 1 and "goes on below the support's level outside its outline (21 of" in reasons[0]
    else:
        assert reasons == []


@pytest.mark.parametrize("seed", [22, 27])
def test_a_shelf_whose_side_boards_stand_in_the_prisms_margin_is_excluded_by_its_foot(
    seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """shelf_above(seed): the side boards holding the shelf board stand on the floor 1-3 cm
    beyond the table's ends, inside the prism's margin, so board and sides are one segment
    that comes down to the table's level there, where no outline rule sees it. Its foot
    (its points at resting height) goes on below the table's level beneath 95-100 % of it
    (`_foot_below`); no object's foot does beyond 39 %. Every object is right and nothing
    is spurious; with the rule off the shelf is an object, and so is what stands on it."""
    from clearcli.evaluate.exact import exact_report
    from clearcli.sim.families import support_frame

    frame = support_frame("shelf_above", seed)
    seg = segment(frame, ON)
    report = exact_report(seg.labels(), frame.fields["label"])
    assert report.right == report.n_objects and report.spurious == 0, report
    feet = [e for e in seg.excluded if "its foot goes on below the support's level" in e.reason]
    assert len(feet) == 1
    monkeypatch.setattr(exclude, "_FOOT_BELOW_SHARE", 2.0)
    off = exact_report(segment(frame, ON).labels(), frame.fields["label"])
    assert off.right == report.right and off.spurious >= 1, off
