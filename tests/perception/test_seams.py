"""The join across smooth, convex seams (clearcli/perception/seams.py)."""

from __future__ import annotations

import importlib.util

import numpy as np
from helpers import REPO, shared_path

from clearcli.perception import learned, seams

_F = {name: k for k, name in enumerate(learned.FEATURES)}


def _feats(rows: list[dict[str, float]], pairs: list[tuple[int, int]], apart: list[bool], adj: list[int]):
    x = np.zeros((len(rows), len(learned.FEATURES)))
    for i, row in enumerate(rows):
        for name, value in row.items():
            x[i, _F[name]] = value
    return learned.PairFeatures(np.array(pairs, dtype=np.int64), x, np.array(apart), np.array(adj, dtype=np.int64))


# a spring clamp's two arms: a convex seam, tops 1 mm apart, colours 19 dE apart
_SMOOTH = {"convex_share": 0.8, "top_step_mm": 1.0, "colour_de": 19.0}


def _chosen(row: dict[str, float], adj: int = 4, apart: bool = False) -> bool:
    feats = _feats([row], [(0, 1)], [apart], [adj])
    return bool(seams.smooth_seams(feats, 0.7, 3, 0.008, 25.0)[0])


def test_a_smooth_seam_is_chosen_and_each_condition_alone_refuses_it() -> None:
    assert _chosen(_SMOOTH)
    assert not _chosen({**_SMOOTH, "convex_share": 0.65})  # a concave seam: two objects
    assert not _chosen(_SMOOTH, adj=2)  # a seam of two adjacencies is noise
    assert not _chosen({**_SMOOTH, "top_step_mm": 8.0})  # two tops a step apart
    assert not _chosen({**_SMOOTH, "colour_de": 25.0})  # two colours: two objects
    assert not _chosen(_SMOOTH, apart=True)  # the colour rule keeps them apart
    # no supervoxel adjacency across the seam at all (what pair_features says 1.0 of)
    none = learned.PairFeatures(np.array([[0, 1]]), _feats([_SMOOTH], [(0, 1)], [False], [0]).x, np.array([False]))
    assert not seams.smooth_seams(none, 0.7, 3, 0.008, 25.0)[0]


def test_joins_go_most_convex_first_and_never_chain_two_segments_apart() -> None:
    # 0-1 and 1-2 are smooth seams, 0-2 apart: only the more convex of the two is joined
    rows = [{**_SMOOTH, "convex_share": 0.8}, {**_SMOOTH, "convex_share": 1.0}, {**_SMOOTH, "convex_share": 0.9}]
    feats = _feats(rows, [(0, 1), (0, 2), (1, 2)], [False, True, False], [4, 4, 4])
    chosen = seams.smooth_seams(feats, 0.7, 3, 0.008, 25.0)
    assert chosen.tolist() == [True, False, True]
    assert seams.seam_joins(feats, chosen, 3) == [(1, 2)]
    rows[0]["convex_share"] = 0.95
    feats = _feats(rows, [(0, 1), (0, 2), (1, 2)], [False, True, False], [4, 4, 4])
    assert seams.seam_joins(feats, seams.smooth_seams(feats, 0.7, 3, 0.008, 25.0), 3) == [(0, 1)]


def _foreign():  # benchmarks/foreign.py, loaded by path (benchmarks is no package)
    spec = importlib.util.spec_from_file_location("foreign_bench", REPO / "benchmarks" / "foreign.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_the_stage_joins_a_bracket_in_two_and_is_stable_under_a_micrometre() -> None:
    """gqcnn_primesense_2 (foreign choose, an Asus Xtion): the brown bracket lying on the
    foam board comes out in two halves that meet at a convex seam (0.73 of 11
    adjacencies), tops 4 mm apart; with the stage one segment holds both. Moving
    every point by +-1 um gives the same objects."""
    from clearcli.perception.segment import segment
    from clearcli.perception.stability import perturbed, same_objects
    from clearcli.settings.segment import SegmentSettings

    shared_path("scenes")
    foreign = _foreign()
    frame, labels, spec = foreign.load("gqcnn_primesense_2")
    assert spec["part"] == "choose"
    k = [o["name"] for o in spec["object"]].index("brown bracket")
    bracket = np.flatnonzero(labels == 10 * (k + 1))

    def largest_share(seg) -> float:  # type: ignore[no-untyped-def]
        held = [np.intersect1d(o.indices, bracket).size for o in seg.objects]
        return max(held) / bracket.size

    off = segment(frame, SegmentSettings(seam_join=False))
    on = segment(frame, SegmentSettings())
    assert "seams" in on.timings_s
    # of its labelled points (all above 8 mm in its polygon, the board's noise too) the
    # largest segment holds 48 % without the stage, 80 % with it
    assert largest_share(off) < 0.55
    assert largest_share(on) > 0.75
    assert len(on.objects) == len(off.objects) - 1
    assert same_objects(on, segment(perturbed(frame, 1e-6, seed=0), SegmentSettings()))
