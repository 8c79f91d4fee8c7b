"""Tests of clearcli/perception/occlusion.py."""

from __future__ import annotations

from dataclasses import replace

from helpers import shared_path
from helpers.segment import S

from clearcli.evaluate.segmentation import score


def test_occlusion_merge_on_a_real_occluded_frame() -> None:
    """learn28: a tall box in front cuts the box behind it in two; LCCP alone gives
    three segments, the occlusion merge two."""
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment

    frame = read_frame(shared_path("mosd/learn/learn28.pcd"))
    off = score(segment(frame, replace(S, occlusion_merge=False)).labels(), frame.fields["label"])
    on = score(segment(frame, S).labels(), frame.fields["label"])
    assert (off.n_pred, off.over_segmented) == (3, 1)
    assert (on.n_pred, on.true_positives, on.f1) == (2, 2, 1.0)
