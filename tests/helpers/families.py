"""Helpers that several test modules share (from the tests of families)."""

from __future__ import annotations

from clearcli.evaluate.segmentation import score
from clearcli.io.frames import Frame
from clearcli.settings.segment import SegmentSettings

S = SegmentSettings()


def _right(frame: Frame, settings: SegmentSettings = S) -> bool:
    """Every object matched at IoU >= 0.5 and nothing more predicted."""
    from clearcli.perception.segment import segment

    sc = score(segment(frame, settings).labels(), frame.fields["label"])
    return sc.true_positives == sc.n_true == sc.n_pred
