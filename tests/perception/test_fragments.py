"""Tests of clearcli/perception/fragments.py."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from helpers.families import S, _right
from scipy.spatial import cKDTree

from clearcli.perception.fragments import join_fragments, thickness
from clearcli.perception.graph import dense_labels
from clearcli.sim.camera import render
from clearcli.sim.families import FAMILIES
from clearcli.sim.scene import Box, make_scene


@pytest.mark.xfail(
    strict=True,
    reason="since the voxel grid's boundaries left the whole millimetre (issue 37, 6a58839) small_against_tall(73) "
    "comes out right without the fragments stage too, and no seed of 60-119 shows the effect: the stage needs a new case",
)
def test_without_the_fragments_stage_the_face_seen_edge_on_is_an_extra_object() -> None:
    frame = render(FAMILIES["small_against_tall"](73), seed=73)
    assert not _right(frame, replace(S, fragment_join_m=0.0))


def test_fragments_of_a_face_seen_edge_on_join_their_object() -> None:
    """small_against_tall(73): the tall box's side, seen edge-on, thinned to strips by
    the outlier filter; joined with the stage, an extra object without it. A small box
    standing 1 cm from a tall one has a top: never a fragment."""
    frame = render(FAMILIES["small_against_tall"](73), seed=73)
    assert _right(frame)
    apart = make_scene(
        "apart", [Box(0, 0.10, 0.08, 0.20, x_m=0.0, y_m=0.05), Box(1, 0.04, 0.04, 0.05, x_m=0.0, y_m=-0.02)]
    )
    for seed in range(3):
        assert _right(render(apart, seed=seed))


def _join_fragments_full_tree(
    seg: np.ndarray, centroids: np.ndarray, edges: np.ndarray, is_top: np.ndarray, max_voxels: int, gap_m: float
) -> np.ndarray:
    """The stage as it was before it searched only the cells near the fragments: one
    tree over every voxel outside them."""
    n_seg = int(seg.max()) + 1
    size = np.bincount(seg, minlength=n_seg)
    has_top = np.bincount(seg, weights=is_top.astype(np.float64), minlength=n_seg) > 0
    a, b = seg[edges[:, 0]], seg[edges[:, 1]]
    touches = np.zeros(n_seg, dtype=bool)
    touches[a[a != b]] = True
    touches[b[a != b]] = True
    fragment = (size < max_voxels) & ~has_top & ~touches
    if not fragment.any() or fragment.all():
        return seg
    rest = ~fragment[seg]
    rest_seg = seg[rest]
    frag_vox = np.flatnonzero(fragment[seg])
    dist, nearest = cKDTree(centroids[rest]).query(centroids[frag_vox], distance_upper_bound=gap_m)
    target = np.full(n_seg, -1)
    best = np.full(n_seg, np.inf)
    for v, d, k in zip(frag_vox, dist, nearest):
        if np.isfinite(d) and d < best[seg[v]]:
            best[seg[v]], target[seg[v]] = d, rest_seg[k]
    out = seg.copy()
    joined = target >= 0
    out[joined[seg]] = target[seg[joined[seg]]]
    return dense_labels(out)


@pytest.mark.parametrize("seed", range(12))
def test_searching_only_the_cells_near_the_fragments_joins_what_one_tree_over_all_joined(seed: int) -> None:
    """Random tables of segments (blobs with adjacency inside each) and fragments (a few
    voxels, no adjacency) scattered among them, some within the gap, some beyond it,
    some at negative coordinates: the same joins as the full tree."""
    rng = np.random.default_rng(seed)
    gap_m = 0.015
    pts, segs, edges = [], [], []
    n = 0
    for s in range(int(rng.integers(3, 12))):
        k = int(rng.integers(2, 40)) if s % 3 else int(rng.integers(1, 4))  # every third a fragment
        centre = rng.uniform(-0.3, 0.3, 3)
        p = centre + rng.normal(0, 0.02 if k > 4 else 0.003, (k, 3))
        pts.append(p)
        segs.append(np.full(k, s))
        if k > 4:  # a segment's own voxels adjacent in a chain; fragments touch nothing
            edges.append(np.stack([np.arange(n, n + k - 1), np.arange(n + 1, n + k)], axis=1))
        n += k
    centroids = np.concatenate(pts)
    seg = np.concatenate(segs)
    edge_arr = np.concatenate(edges) if edges else np.zeros((0, 2), np.int64)
    is_top = np.zeros(n, dtype=bool)
    got = join_fragments(seg, centroids, edge_arr, is_top, 5, gap_m)
    want = _join_fragments_full_tree(seg, centroids, edge_arr, is_top, 5, gap_m)
    assert np.array_equal(got, want)


def test_a_voxel_just_within_the_gap_in_the_next_cell_is_searched() -> None:
    """A fragment of one voxel at x = 0.0301 m, the object's nearest voxel at 0.045 m:
    0.0149 apart, within the 0.015 gap, and in the next cell of the 0.01515 m grid (cells
    1 and 2): the fragment joins the object. At 0.0299 (0.0151 apart) it stays alone. A
    lone voxel at x = -1 (a fragment too, far from all) puts cells at negative x."""
    line = np.array([[0.045, 0.0, 0.0], [0.06, 0.0, 0.0], [0.075, 0.0, 0.0]])
    edges = np.array([[1, 2], [2, 3]])
    for x, joined in ((0.0301, True), (0.0299, False)):
        centroids = np.vstack([[[x, 0.0, 0.0]], line, [[-1.0, 0.0, 0.0]]])
        seg = np.array([0, 1, 1, 1, 2])
        out = join_fragments(seg, centroids, edges, np.zeros(5, bool), 2, 0.015)
        assert bool(out[0] == out[1]) is joined
        assert out[4] != out[1]


def _strip_and_object(thick_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An object: a row of 10 voxels along x at y = 0, adjacent in a chain; 8 mm beside
    it a lone segment of 8 voxels, touching nothing: a 4 x 2 grid (x 0-15 mm, y 8 and
    13 mm) whose z is +-thick_m in a checkerboard, so z is uncorrelated with x and y.
    They spread 5.6 mm RMS in x and 2.5 mm in y, so up to 2.5 mm their flattest axis is
    z, and they lie thick_m (RMS) off the plane z = 0."""
    obj = np.column_stack([np.arange(10) * 0.005, np.zeros(10), np.zeros(10)])
    xs = np.array([0.0, 0.005, 0.010, 0.015])
    sign = np.array([1.0, -1.0, 1.0, -1.0])
    piece = np.vstack(
        [
            np.column_stack([xs, np.full(4, 0.008), sign * thick_m]),
            np.column_stack([xs, np.full(4, 0.013), -sign * thick_m]),
        ]
    )
    centroids = np.vstack([obj, piece])
    seg = np.array([0] * 10 + [1] * 8)
    edges = np.stack([np.arange(9), np.arange(1, 10)], axis=1)
    return seg, centroids, edges


def test_thickness_is_the_rms_distance_from_the_best_plane() -> None:
    # the piece's voxels are +-1 mm off z = 0 (its x spread is 5.6 mm RMS, y 2.5 mm):
    # 1 mm; the object's row of voxels on one line: 0
    seg, centroids, _ = _strip_and_object(0.001)
    got = thickness(seg, centroids, 2, np.array([True, True]))
    assert got[1] == pytest.approx(0.001, abs=1e-9)
    assert got[0] == pytest.approx(0.0, abs=1e-9)
    assert thickness(seg, centroids, 2, np.array([True, False]))[1] == 0.0


@pytest.mark.parametrize(
    "thick_m, other_colour, joined",
    [(0.0, True, True), (0.0014, True, True), (0.0016, True, False), (0.003, True, False), (0.003, False, True)],
)
def test_a_thick_lone_segment_of_its_own_colour_is_an_object(thick_m: float, other_colour: bool, joined: bool) -> None:
    """The lone segment 8 mm from the object joins it while it is a flat strip (up to
    1.5 mm thick, the default), whatever its colour; thicker and 30 apart in colour (L*
    50 against 80; the 25 of color_split_delta is the limit) it is a small object of its
    own (a ball, a deodorant lying in a bin), left alone; thicker and of the object's
    colour it joins. Without colour it always joins."""
    seg, centroids, edges = _strip_and_object(thick_m)
    is_top = np.zeros(18, dtype=bool)
    lab = np.zeros((18, 3))
    lab[:, 0] = 50.0
    lab[10:, 0] = 80.0 if other_colour else 55.0
    t, d = S.fragment_max_thickness_m, S.color_split_delta
    out = join_fragments(seg, centroids, edges, is_top, 9, 0.015, t, lab, d)
    assert bool(out[10] == out[0]) is joined
    assert join_fragments(seg, centroids, edges, is_top, 9, 0.015, t)[10] == 0


def test_a_ball_beside_a_box_on_a_real_frame_stays_apart() -> None:
    """gqcnn_primesense_2: the green ball (no level top, apart from the rest by a few
    millimetres) was joined as a fragment to the segment beside it, and both objects
    were merged; 6 mm thick and 28 apart in colour from the box's side beside it, it
    stays an object of its own."""
    from helpers.foreign import judged

    verdicts, _, _ = judged("gqcnn_primesense_2")
    assert verdicts["green ball"] == "right"
    verdicts, _, _ = judged("gqcnn_primesense_2", fragment_max_thickness_m=0.1)
    assert verdicts["green ball"] == "merged"


def test_near_cells_by_a_dense_grid_and_by_isin_agree(monkeypatch: pytest.MonkeyPatch) -> None:
    """`_near_cells` marks a small grid densely and looks a wide one's cells up with
    np.isin: the same voxels. By hand: reach 1 cm (cells 1.01 cm), the seed at x = 0;
    x = 1.5 cm is the next cell (kept), x = 2.5 cm two cells on (not), and x = 0.5 cm
    the seed's own cell."""
    from clearcli.perception import fragments

    pts = np.array([[0.0, 0, 0], [0.015, 0, 0], [0.025, 0, 0], [0.005, 0, 0]])
    expected = [True, True, False, True]
    assert fragments._near_cells(pts, np.array([0]), 0.01).tolist() == expected
    rng = np.random.default_rng(2)
    clouds = [(pts, np.array([0]))] + [
        (rng.uniform(0, 0.3, (500, 3)), rng.choice(500, 20, replace=False)) for _ in range(8)
    ]
    dense = [fragments._near_cells(p, seeds, 0.01) for p, seeds in clouds]
    monkeypatch.setattr(fragments, "_MAX_GRID_CELLS", 0)  # every grid looked up with np.isin
    for (p, seeds), near in zip(clouds, dense, strict=True):
        assert np.array_equal(fragments._near_cells(p, seeds, 0.01), near)


def test_near_cells_is_its_definition_voxel_by_voxel() -> None:
    """Against the definition, one voxel at a time: a voxel is kept when its cell (1.01 x
    the reach, by floor) is a seed's cell or one of the 26 around it."""
    from clearcli.perception.fragments import _near_cells

    rng = np.random.default_rng(12)
    for n_seeds in (1, 10, 100):
        pts = rng.uniform(-0.2, 0.3, (300, 3))
        seeds = rng.choice(300, n_seeds, replace=False)
        cell = np.floor(pts / (1.01 * 0.02)).astype(np.int64)
        expected = [bool((np.abs(cell[seeds] - cell[i]).max(axis=1) <= 1).any()) for i in range(pts.shape[0])]
        assert _near_cells(pts, seeds, 0.02).tolist() == expected
