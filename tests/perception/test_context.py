"""Tests of clearcli/perception/context.py."""

from __future__ import annotations

import numpy as np

from clearcli.perception.context import by_label


def test_by_label_orders_by_label_then_index() -> None:
    # labels 2 0 1 0 2 1: label 0 at 1 and 3, label 1 at 2 and 5, label 2 at 0 and 4
    assert by_label(np.array([2, 0, 1, 0, 2, 1]), 3).tolist() == [1, 3, 2, 5, 0, 4]
    assert by_label(np.zeros(0, dtype=np.int64), 0).tolist() == []


def test_by_label_is_the_stable_argsort_with_few_and_many_labels() -> None:
    rng = np.random.default_rng(1)
    for n_labels in (1, 7, 300, 32767, 40000):  # int16 by radix up to 32767, then int64
        labels = rng.integers(0, n_labels, 5000)
        assert np.array_equal(by_label(labels, n_labels), np.argsort(labels, kind="stable"))
