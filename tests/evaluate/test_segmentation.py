"""Tests of clearcli/evaluate/segmentation.py."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.evaluate import _labels

from clearcli.evaluate.segmentation import object_ids, score


def test_object_ids_follow_the_label_convention() -> None:
    # 0 none, 1..9 table (mOSD), 10*(k+1) (+ parts 11, 12, ...) objects
    assert object_ids(np.array([0, 1, 5, 9, 10, 19, 20, 31])).tolist() == [0, 0, 0, 0, 1, 1, 2, 3]


def test_perfect_prediction_with_other_numbers() -> None:
    truth = _labels((0, 5), (1, 20), (20, 10), (21, 5), (30, 8))  # object 2 in two parts
    pred = _labels((0, 5), (1, 20), (10, 15), (20, 8))
    s = score(pred, truth)
    assert (s.n_true, s.n_pred, s.true_positives) == (2, 2, 2)
    assert s.precision == s.recall == s.f1 == 1.0
    assert s.mean_best_iou == 1.0
    assert (s.over_segmented, s.under_segmented) == (0, 0)
    assert s.matched_iou == (1.0, 1.0)


def test_over_segmentation() -> None:
    # true object A: 10 points split 6/4 into two predictions; B (10 points) exact
    truth = _labels((20, 10), (30, 10))
    pred = _labels((10, 6), (20, 4), (30, 10))
    s = score(pred, truth)
    # IoU(A, p1) = 6/10 >= 0.5 matches, p2 is a false positive
    assert (s.n_true, s.n_pred, s.true_positives) == (2, 3, 2)
    assert s.precision == pytest.approx(2 / 3)
    assert s.recall == 1.0
    assert s.f1 == pytest.approx(0.8)
    assert s.mean_best_iou == pytest.approx((0.6 + 1.0) / 2)
    assert (s.over_segmented, s.under_segmented) == (1, 0)


def test_under_segmentation() -> None:
    # two true objects (10 and 30 points) predicted as one (40 points)
    truth = _labels((20, 10), (30, 30))
    pred = _labels((10, 40))
    s = score(pred, truth)
    # IoU with the big one 30/40 = 0.75 matches; the small one is missed
    assert (s.true_positives, s.precision, s.recall) == (1, 1.0, 0.5)
    assert s.f1 == pytest.approx(2 / 3)
    assert s.mean_best_iou == pytest.approx((10 / 40 + 30 / 40) / 2)
    assert (s.over_segmented, s.under_segmented) == (0, 1)


def test_matching_is_one_to_one() -> None:
    # one prediction exactly over two equal true objects: IoU 0.5 with each, which
    # passes the (inclusive) threshold twice, but it can be matched only once
    truth = _labels((20, 10), (30, 10))
    pred = _labels((10, 20))
    s = score(pred, truth)
    assert s.true_positives == 1
    assert sorted(s.matched_iou) == [0.0, 0.5]
    assert (s.precision, s.recall) == (1.0, 0.5)
    assert s.under_segmented == 1


def test_iou_threshold_is_inclusive_and_empty_cases() -> None:
    truth = _labels((20, 10), (0, 10))
    pred = _labels((10, 5), (10, 5), (0, 10))
    pred[5:10] = 0  # 5 of the 10 true points: IoU 0.5 exactly
    assert score(pred, truth).true_positives == 1
    empty = np.zeros(20, dtype=np.int64)
    s = score(empty, empty)
    assert (s.f1, s.n_true, s.n_pred) == (1.0, 0, 0)
    s = score(empty, truth)
    assert (s.f1, s.recall, s.mean_best_iou) == (0.0, 0.0, 0.0)
    s = score(truth, empty)
    assert (s.f1, s.precision) == (0.0, 0.0)
    with pytest.raises(ValueError, match="differ in length"):
        score(empty, np.zeros(5))
