"""clearcli/evaluate/exact.py: objects exactly right, merged, split, missed; spurious segments."""

from __future__ import annotations

import numpy as np

from clearcli.evaluate.exact import exact_report


def _labels(*runs: tuple[int, int]) -> np.ndarray:
    """Labels from (label, count) runs."""
    return np.concatenate([np.full(n, lab) for lab, n in runs])


def test_each_kind_worked_by_hand() -> None:
    # truth: A = points 0-9, B = 10-19, C = 20-29, D = 30-39, E = 40-43, the table 44-63
    true = _labels((10, 10), (20, 10), (30, 10), (40, 10), (50, 4), (1, 20))
    pred = np.zeros(64, dtype=np.int64)
    pred[0:20] = 10  # A and B in one segment: both merged
    pred[20:26] = 30  # C in two pieces, 6 and 4: split, although the larger has IoU 0.6 (a
    pred[26:30] = 70  # planner would see two objects)
    pred[30:39] = 40  # D: 9 of its 10 points in one segment (IoU 0.9): right
    pred[44:56] = 60  # 12 table points taken for an object: spurious; E (40-43) not found: missed
    pred[56:64] = 1
    r = exact_report(pred, true)
    assert r.verdicts == ("merged", "merged", "split", "right", "missed")
    assert (r.n_objects, r.right, r.merged, r.split, r.missed, r.spurious) == (5, 1, 2, 1, 1, 1)


def test_a_segment_with_iou_half_that_holds_a_second_object_is_not_right() -> None:
    # big object 20 points, small one 3: one segment holds both (IoU with the big 20/23)
    true = _labels((10, 20), (20, 3))
    pred = _labels((10, 23))
    assert exact_report(pred, true).verdicts == ("merged", "merged")


def test_everything_right_and_nothing_labelled() -> None:
    true = _labels((10, 5), (20, 5), (1, 5))
    assert exact_report(true.copy(), true).verdicts == ("right", "right")
    none = exact_report(_labels((10, 5)), _labels((1, 5)))
    assert (none.n_objects, none.spurious) == (0, 1)


def test_a_handle_apart_from_its_mug_makes_the_mug_split_and_a_crumb_does_not() -> None:
    true = _labels((10, 100))
    handle = np.array([10] * 85 + [20] * 15)  # 15 % of the mug in a second segment
    crumb = np.array([10] * 95 + [0] * 1 + [20] * 4)  # 4 % in a second segment
    assert exact_report(handle, true).verdicts == ("split",)
    assert exact_report(crumb, true).verdicts == ("right",)
