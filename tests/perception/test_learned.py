"""The learned join (clearcli/perception/learned.py, trained by training/join.py)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from helpers import REPO, load_script, shared_path

from clearcli.perception import learned


def _training():  # training/join.py, loaded by path (training is no package)
    return load_script("training/join.py")


def test_the_shipped_model_loads_and_carries_its_version() -> None:
    model = learned.load_model()
    assert model.version.startswith("join-2 ")
    assert model.weights.shape == model.mean.shape == model.scale.shape == (len(learned.FEATURES),)
    assert np.all(model.scale > 0)
    path = REPO / "clearcli" / learned.MODEL_RESOURCE
    assert path.stat().st_size < 20_000_000
    assert json.loads(path.read_text(encoding="utf-8"))["format"] == learned.MODEL_FORMAT


def test_training_recreates_the_model_byte_for_byte() -> None:
    join = _training()
    _, x, y = join.read_pairs()
    assert int(y.sum()) > 10 and int((y == 0).sum()) > 10  # both kinds of pair
    text = join.dumps(join.fit(x, y))
    assert text == (REPO / "clearcli" / learned.MODEL_RESOURCE).read_text(encoding="utf-8")


def test_a_model_of_another_format_is_refused() -> None:
    from clearcli.errors import ClearError

    with pytest.raises(ClearError, match="format"):
        learned.JoinModel.from_dict({"format": "other", "features": list(learned.FEATURES)})


def _feats(pairs: list[tuple[int, int]], apart: list[bool]) -> learned.PairFeatures:
    return learned.PairFeatures(
        np.array(pairs, dtype=np.int64), np.zeros((len(pairs), len(learned.FEATURES))), np.array(apart)
    )


def test_joins_go_most_probable_first_and_never_chain_two_segments_apart() -> None:
    # 0-1 and 1-2 are likely one object, 0-2 are apart (the colour rule): joining both
    # would put 0 and 2 in one segment, so only the more probable join is made
    feats = _feats([(0, 1), (0, 2), (1, 2)], [False, True, False])
    assert learned.joins(feats, np.array([3.0, 9.0, 4.0]), 2.0, 3) == [(1, 2)]
    assert learned.joins(feats, np.array([5.0, 9.0, 4.0]), 2.0, 3) == [(0, 1)]
    # below the threshold (with its margin) nothing is joined
    assert learned.joins(feats, np.array([1.9, 9.0, 1.0]), 2.0, 3) == []


def test_the_margin_keeps_a_pair_at_the_threshold_as_it_is() -> None:
    p = 0.9
    at_threshold = float(np.log(p / (1 - p)))
    feats = _feats([(0, 1)], [False])
    assert learned.joins(feats, np.array([at_threshold + 0.01]), at_threshold + learned.MARGIN_LOGIT, 2) == []
    assert learned.joins(feats, np.array([at_threshold + 0.5]), at_threshold + learned.MARGIN_LOGIT, 2) == [(0, 1)]


def _frame(name: str):  # a foreign choose frame with its labels' source
    import tomllib

    spec = tomllib.loads((REPO / "benchmarks" / "foreign" / f"{name}.toml").read_text(encoding="utf-8"))
    assert spec["part"] == "choose"
    from clearcli.io.read import read_frame

    return read_frame(shared_path(str(Path(spec["source"]))))


def test_the_stage_joins_pieces_and_is_stable_under_a_micrometre() -> None:
    """On uois_image_0002 (a RealSense's depth: a can and a bowl split in pieces) the
    stage at 0.7 joins pieces (fewer objects than without it); moving every point by
    +-1 um gives the same objects with it on, there and on two more uois choose frames.
    (gqcnn_primesense_4 is no test of the stage: its objects change under +-1 um with
    the stage off, 10 -> 9.)"""
    from clearcli.perception.segment import segment
    from clearcli.perception.stability import perturbed, same_objects
    from clearcli.settings.segment import SegmentSettings

    on_settings = SegmentSettings(learned_join=True, learned_join_min_p=0.7)
    for name in ("uois_image_0002", "uois_image_0004", "uois_image_0006"):
        frame = _frame(name)
        on = segment(frame, on_settings)
        assert "learned" in on.timings_s
        if name == "uois_image_0002":
            # the pieces it joins there are the soup can's and the tin's, which stacks.py's
            # crescent rule now separates itself: with the stacks stage off
            no_stacks = SegmentSettings(learned_join=True, learned_join_min_p=0.7, stack_split=False)
            off = SegmentSettings(learned_join=False, stack_split=False)
            assert len(segment(frame, no_stacks).objects) < len(segment(frame, off).objects)
        assert same_objects(on, segment(perturbed(frame, 1e-6, seed=0), on_settings)), name


def test_pair_features_are_finite_and_in_sorted_pairs() -> None:
    from clearcli.perception import segment as seg_mod
    from clearcli.settings.segment import SegmentSettings

    captured = []
    original = seg_mod.refine

    def capture(seg_of_voxel, ctx, clock=None):  # type: ignore[no-untyped-def]
        out = original(seg_of_voxel, ctx, clock)
        captured.append((out, ctx))
        return out

    seg_mod.refine = capture
    try:
        seg_mod.segment(_frame("uois_image_0002"), SegmentSettings())
    finally:
        seg_mod.refine = original
    seg, ctx = captured[0]
    feats = learned.pair_features(seg, ctx)
    assert feats.pairs.shape[0] >= 3
    assert np.all(feats.pairs[:, 0] < feats.pairs[:, 1])
    keys = feats.pairs[:, 0] * (int(seg.max()) + 1) + feats.pairs[:, 1]
    assert np.all(np.diff(keys) > 0)
    assert np.isfinite(feats.x).all()
    assert feats.x[:, learned.FEATURES.index("gap_mm")].max() <= learned.GAP_M * 1000 + 1e-9


def test_a_frame_the_segmenter_refuses_gives_no_pairs() -> None:
    """A noisy copy may lose its table: extraction skips it (and says so), it does
    not stop (the segmenter raises a ClearError on these points: no plane in them)."""
    from clearcli.errors import ClearError
    from clearcli.io.frames import Frame
    from clearcli.perception.segment import segment
    from clearcli.settings.segment import SegmentSettings

    rng = np.random.default_rng(0)
    frame = Frame(points=rng.uniform(-0.01, 0.01, size=(50, 3)).astype(np.float32) + np.float32(1.0))
    with pytest.raises(ClearError):
        segment(frame, SegmentSettings(learned_join=False))
    assert _training()._pair_rows(frame, np.zeros(50, dtype=np.int64)) is None


def test_the_pairs_file_carries_each_pairs_purity() -> None:
    """Each row's lesser purity of its two segments (the share of a segment's points its
    own object holds) is a share, and pairs of mixed segments are there to be seen."""
    frames, x, y, purity = _training().read_pairs(with_purity=True)
    assert purity.shape == y.shape and x.shape == (y.size, len(learned.FEATURES))
    assert np.all((purity > 0) & (purity <= 1))
    assert np.any(purity < 0.6) and np.any(purity == 1)
