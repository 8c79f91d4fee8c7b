"""clearcli/evaluate/osd.py: the OSD/OCID metrics, on label images worked out by hand."""

from __future__ import annotations

import numpy as np
import pytest

from clearcli.evaluate.osd import osd_metrics


def test_overlap_by_hand() -> None:
    # true A = points 0-9, B = 10-19; predicted A' = 0-7 and 10-11 (8 of A, 2 of B), B' = 12-19
    true = np.array([10] * 10 + [20] * 10)
    pred = np.array([10] * 8 + [0] * 2 + [10] * 2 + [20] * 8)
    s = osd_metrics(pred, true)
    # F(A', A) = 0.8 (P 8/10, R 8/10), F(B', B) = 2 * 1 * 0.8 / 1.8 = 0.889: matched A'-A, B'-B
    assert s.overlap_precision == pytest.approx(16 / 18)  # 8 + 8 of the 18 predicted object points
    assert s.overlap_recall == pytest.approx(16 / 20)
    assert s.overlap_f == pytest.approx(2 * (16 / 18) * 0.8 / (16 / 18 + 0.8))
    assert s.objects_f75 == 1.0  # both matches have F >= 0.75
    assert s.boundary_f is None  # not an organized frame: no boundary measure


def _square(rows: slice, cols: slice, size: int = 20) -> np.ndarray:
    img = np.zeros((size, size), dtype=np.int64)
    img[rows, cols] = 10
    return img.ravel()


def test_boundary_by_hand() -> None:
    # a 6 x 6 true square, and the same square 3 columns to the right; the tolerance on a
    # 20 x 20 image is ceil(0.003 * 28.3) = 1 pixel
    true = _square(slice(5, 11), slice(5, 11))
    pred = _square(slice(5, 11), slice(8, 14))
    s = osd_metrics(pred, true, (20, 20))
    # predicted boundary: 20 pixels; within 1 px of the true boundary: left column rows
    # 5, 6, 9, 10 (4), top and bottom rows at columns 9, 10, 11 (3 + 3) = 10
    assert s.boundary_precision == pytest.approx(10 / 20)
    assert s.boundary_recall == pytest.approx(10 / 20)  # the same, mirrored
    assert s.boundary_f == pytest.approx(0.5)
    assert s.overlap_f == pytest.approx(0.5)  # 18 shared of 36 each side
    assert s.objects_f75 == 0.0
    # one column off: every boundary pixel within the tolerance
    near = osd_metrics(_square(slice(5, 11), slice(6, 12)), true, (20, 20))
    assert near.boundary_precision == near.boundary_recall == 1.0 and near.overlap_f == pytest.approx(5 / 6)


def test_no_objects_on_one_side_or_both() -> None:
    none = np.zeros(16, dtype=np.int64)
    some = np.array([10] * 8 + [0] * 8)
    assert osd_metrics(none, none, (4, 4)).as_dict() == {k: 1.0 for k in osd_metrics(none, none, (4, 4)).as_dict()}
    s = osd_metrics(none, some, (4, 4))
    assert s.overlap_f == s.boundary_f == s.objects_f75 == 0.0


def test_the_table_and_unlabelled_points_are_background() -> None:
    # mOSD's table labels 1..9 and our 1 are not objects: a table difference costs nothing
    true = np.array([1] * 5 + [10] * 5)
    pred = np.array([0] * 5 + [10] * 5)
    s = osd_metrics(pred, true)
    assert (s.overlap_precision, s.overlap_recall, s.objects_f75) == (1.0, 1.0, 1.0)
