"""A surface beyond the support's edge at nearly its height is no object (issue 37,
perception/exclude.py `support_around`): gqcnn's foam board has a cluttered bench behind it
1.5 cm above the board's plane, inside the board's hull (the plane's inliers scatter over
the clutter) and cut by the image's border; the support is seen nowhere around it. On a
self-made pixel grid, and on the real gqcnn frame (../shared/data)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
import pytest
from helpers.foreign import labelled

from clearcli.evaluate.exact import exact_report
from clearcli.perception import exclude
from clearcli.perception.exclude import not_standing, support_around
from clearcli.perception.payload import segmentation_payload
from clearcli.perception.segment import segment
from clearcli.settings.segment import SegmentSettings

SHAPE = (60, 80)
ON = dataclasses.replace(SegmentSettings(), exclude_not_standing=True)


def _grid() -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    """Two segments on a 60 x 80 pixel grid: an object in the middle of the support, and
    a strip along the top border over pixels that are seen but not the support (a bench
    behind), the support starting 10 rows below it; the objects' pixels, the support's, the
    pixels seen."""
    rows, cols = np.mgrid[0 : SHAPE[0], 0 : SHAPE[1]]
    flat = rows * SHAPE[1] + cols
    obj = flat[30:40, 30:45].ravel()
    strip = flat[0:6, 20:60].ravel()
    support = np.zeros(SHAPE, dtype=bool)
    support[16:, :] = True
    seen = np.ones(SHAPE, dtype=bool)
    seen[0:3, 0:10] = False  # a few pixels without depth
    return [obj, strip], support.ravel(), seen.ravel()


def _state(support: np.ndarray, seen: np.ndarray):  # -> the pixels' (count, support)
    return lambda pixels: (seen[pixels], support[pixels])


def test_support_around_counts_the_seen_pixels_of_the_ring() -> None:
    indices, support, seen = _grid()
    (n_obj, s_obj), (n_strip, s_strip) = support_around(indices, SHAPE, _state(support, seen))
    # the object: the ring 4 wide all around a 10 x 15 block, all support
    assert n_obj == (10 + 8) * (15 + 8) - 10 * 15
    assert s_obj == n_obj
    # the strip: the ring below and at its ends (the border cuts it above), none support
    assert n_strip >= exclude._RING_MIN_PX and s_strip == 0


def _verdicts(
    around: list[tuple[int, int]] | None, inside_deep: Callable[[np.ndarray], np.ndarray] | None = None
) -> list[str]:
    rng = np.random.default_rng(0)
    # two small objects standing on the support (heights 0 to 5 cm), apart in the plane
    objs = [
        np.column_stack([rng.uniform(0, 0.05, 300), rng.uniform(0, 0.05, 300), rng.uniform(0.0, 0.05, 300)]),
        np.column_stack([rng.uniform(0.3, 0.4, 300), rng.uniform(0, 0.02, 300), rng.uniform(0.0, 0.02, 300)]),
    ]
    support = np.column_stack([rng.uniform(-0.5, 0.5, 2000), rng.uniform(-0.5, 0.5, 2000), np.zeros(2000)])
    verdicts = not_standing(
        objs,
        np.zeros((0, 3)),
        np.zeros((0, 3)),
        support[:, :2],  # in-plane: the support lies in z = 0
        lambda p: p[:, 2],
        lambda p: p[:, :2],
        lambda p: np.ones(p.shape[0], dtype=bool),
        lambda p: 0.01,
        None,
        None,
        around,
        inside_deep,
    )
    return [f"{v.index}: {v.reason}" for v in verdicts]


def test_a_segment_with_no_support_seen_around_it_is_excluded() -> None:
    indices, support, seen = _grid()
    around = support_around(indices, SHAPE, _state(support, seen))
    got = _verdicts(around)
    assert len(got) == 1 and got[0].startswith("1: stands beyond the support's edge: the support is seen nowhere")
    # the step off (no pixel grid): both stand
    assert _verdicts(None) == []
    # too few pixels seen around it to tell (inside a heap, or its ring without depth): it stands
    assert _verdicts([(300, 300), (exclude._RING_MIN_PX - 1, 0)]) == []


def test_a_segment_deep_inside_the_outline_does_not_stand_beyond_its_edge() -> None:
    # the same strip with no support round it, all of its points more than
    # DEEP_INSIDE_M inside the outline: the support goes on round it, so it stands on
    # something else there (a bowl's floor), not beyond the edge; one point nearer the
    # outline, and it is judged as before
    indices, support, seen = _grid()
    around = support_around(indices, SHAPE, _state(support, seen))
    assert _verdicts(around, lambda xy: np.ones(xy.shape[0], dtype=bool)) == []
    near_the_edge = _verdicts(around, lambda xy: np.arange(xy.shape[0]) > 0)
    assert len(near_the_edge) == 1 and near_the_edge[0].startswith("1: stands beyond the support's edge")


def test_the_bench_behind_gqcnns_foam_board_is_excluded(monkeypatch: pytest.MonkeyPatch) -> None:
    frame, truth, _ = labelled("gqcnn_primesense_0")
    seg = segment(frame, ON)
    bench = [e for e in seg.excluded if "seen nowhere around it" in e.reason]
    assert len(bench) == 2, [e.reason for e in seg.excluded]
    h, w = frame.shape
    for e in bench:
        assert (e.indices // w).min() == 0 and (e.indices // w).max() < 0.15 * h  # the top of the view
        assert np.mean(truth[e.indices] >= 10) < 0.05  # no labelled object's
    doc = segmentation_payload(seg)
    assert sum("seen nowhere around it" in e["reason"] for e in doc["excluded"]) == 2
    right = exact_report(seg.labels(), truth)
    monkeypatch.setattr(exclude, "_RING_SUPPORT_SHARE", 0.0)
    off = segment(frame, ON)
    assert len(off.objects) == len(seg.objects) + 2
    assert exact_report(off.labels(), truth).spurious == right.spurious + 2
