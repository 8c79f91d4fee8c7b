"""Tests of clearcli/perception/rims.py."""

from __future__ import annotations

import numpy as np
import pytest


def _column(x: float, z_lo: float, z_hi: float) -> np.ndarray:
    """Voxel centroids of a 4 cm wide vertical strip at x (table frame: z up), 5 mm grid."""
    z = np.arange(z_lo, z_hi + 1e-9, 0.005)
    y = np.arange(0.0, 0.04 + 1e-9, 0.005)
    zz, yy = np.meshgrid(z, y)
    return np.stack([np.full(zz.size, x), yy.ravel(), zz.ravel()], axis=1)


def _slope(x0: float, x1: float, z0: float, dz_dx: float) -> np.ndarray:
    """Voxel centroids of a 4 cm wide strip from x0 to x1, z = z0 + dz_dx (x - x0)."""
    x = np.arange(x0, x1 + 1e-9, 0.005)
    y = np.arange(0.0, 0.04 + 1e-9, 0.005)
    xx, yy = np.meshgrid(x, y)
    return np.stack([xx.ravel(), yy.ravel(), z0 + dz_dx * (xx.ravel() - x0)], axis=1)


@pytest.mark.parametrize(
    "shape, joined",
    [
        ("rim", True),  # an inner wall going down away from A's top: a container's rim
        ("on_top", False),  # stands on A: touches A's top with its bottom
        ("beside", False),  # side by side: touches all the way down
    ],
)
def test_rim_merge(shape: str, joined: bool) -> None:
    from clearcli.perception.rims import merge_rims

    a = _column(0.0, 0.0, 0.10)
    b = {
        "rim": _slope(0.015, 0.06, 0.10, -1.0),
        "on_top": _column(0.015, 0.10, 0.14),
        "beside": _column(0.015, 0.0, 0.10),
    }[shape]
    cent = np.vstack([a, b])
    seg = np.r_[np.zeros(len(a), np.int64), np.ones(len(b), np.int64)]
    out = merge_rims(seg, cent, cent[:, 2], tolerance_m=0.015, contact_m=0.02)
    assert (int(out.max()) + 1 == 1) == joined


def _flat(x0: float, x1: float, z: float) -> np.ndarray:
    """Voxel centroids of a horizontal 4 cm wide strip from x0 to x1 at height z."""
    return _slope(x0, x1, z, 0.0)


def test_rim_merge_keeps_touching_tops_apart() -> None:
    """Two tall boxes 1 cm apart whose lower parts hide each other: the camera sees two
    tops whose edges come within the contact distance, near the top of both. Without the
    top-face test that looks like a rim; with it, it is not one."""
    from clearcli.perception.rims import merge_rims

    a, b = _flat(0.0, 0.04, 0.10), _flat(0.05, 0.09, 0.095)
    cent = np.vstack([a, b])
    seg = np.r_[np.zeros(len(a), np.int64), np.ones(len(b), np.int64)]
    joined = merge_rims(seg, cent, cent[:, 2], tolerance_m=0.015, contact_m=0.02)
    assert int(joined.max()) == 0
    kept = merge_rims(seg, cent, cent[:, 2], 0.015, 0.02, voxel_is_top=np.ones(len(cent), bool))
    assert int(kept.max()) == 1
    # a rim's walls are not top faces: still joined
    outer, inner = _column(0.0, 0.0, 0.10), _slope(0.015, 0.06, 0.10, -1.0)
    rim = np.vstack([outer, inner])
    rim_seg = np.r_[np.zeros(len(outer), np.int64), np.ones(len(inner), np.int64)]
    assert int(merge_rims(rim_seg, rim, rim[:, 2], 0.015, 0.02, voxel_is_top=np.zeros(len(rim), bool)).max()) == 0


def test_near_another_segment_holds_every_pair_across_segments() -> None:
    """The pairs search runs on the voxels `_near_another_segment` keeps: every pair of
    two segments' voxels within reach has both ends among them, on random clouds with
    points exactly on the cells' boundaries too."""
    from scipy.spatial import cKDTree

    from clearcli.perception.rims import _near_another_segment

    rng = np.random.default_rng(3)
    for trial in range(20):
        pts = rng.uniform(0, 0.2, (600, 3))
        if trial % 2:
            pts = np.round(pts / 0.0101) * 0.0101  # on the 1.01 * reach cells' boundaries
        seg = rng.integers(0, 1 + trial % 5, 600)
        pairs = cKDTree(pts).query_pairs(0.01, output_type="ndarray")
        across = pairs[seg[pairs[:, 0]] != seg[pairs[:, 1]]]
        near = _near_another_segment(seg, pts, 0.01, int(seg.max()) + 1)
        assert near[across].all()
        if trial % 5 == 0:  # one segment: no voxel has another near
            assert not near.any()


def test_a_reach_of_zero_keeps_no_voxel_and_warns_nothing() -> None:
    # rim_contact_m = 0 is a valid setting: no two distinct voxels touch; it divided by zero
    import warnings

    from clearcli.perception.rims import _near_another_segment

    pts = np.random.default_rng(0).uniform(0, 0.2, (50, 3))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        near = _near_another_segment(np.arange(50) % 3, pts, 0.0, 3)
    assert near.shape == (50,) and not near.any()


def test_the_dense_grid_and_the_searched_cells_keep_the_same_voxels(monkeypatch: pytest.MonkeyPatch) -> None:
    """`_near_another_segment` reads a small grid as a dense array and searches a wide
    one's cells: the same voxels either way. By hand first: reach 1 cm (cells 1.01 cm),
    voxels of segment 0 at x = 0 and 5 cm, of segment 1 at x = 1.5 cm (the neighbouring
    cell of the first) and 10 cm (beside nothing of segment 0)."""
    from clearcli.perception import rims

    pts = np.array([[0.0, 0, 0], [0.05, 0, 0], [0.015, 0, 0], [0.10, 0, 0]])
    seg = np.array([0, 0, 1, 1])
    expected = np.array([True, False, True, False])
    assert np.array_equal(rims._near_another_segment(seg, pts, 0.01, 2), expected)
    rng = np.random.default_rng(5)
    clouds = [(pts, seg)] + [(rng.uniform(0, 0.3, (800, 3)), rng.integers(0, 6, 800)) for _ in range(10)]
    dense = [rims._near_another_segment(s, p, 0.01, int(s.max()) + 1) for p, s in clouds]
    monkeypatch.setattr(rims, "_MAX_GRID_CELLS", 0)  # every grid searched
    for (p, s), near in zip(clouds, dense, strict=True):
        assert np.array_equal(rims._near_another_segment(s, p, 0.01, int(s.max()) + 1), near)
    assert dense[0].tolist() == expected.tolist()


@pytest.mark.parametrize("gap_m, joined", [(0.018, True), (0.022, False)])
def test_walls_apart_across_a_diagonal_touch_within_the_contact_distance(gap_m: float, joined: bool) -> None:
    # a short wall beyond a taller one's top edge, apart across a diagonal of x and z:
    # their boxes are apart on two axes, so the pairs across the two segments are found
    # only if the boxes are judged by their distance in 3-D (18 mm: within contact_m =
    # 20 mm, near both tops with a 3 cm tolerance, a rim; 22 mm: nothing touches)
    from clearcli.perception.rims import merge_rims

    step = gap_m / np.sqrt(2.0)  # the nearest edges step apart in x and in z
    a = _column(0.0, 0.0, 0.10)
    b = _column(step, 0.10 + step, 0.11 + step)
    cent = np.vstack([a, b])
    seg = np.repeat([0, 1], [len(a), len(b)])
    out = merge_rims(seg, cent, cent[:, 2], tolerance_m=0.03, contact_m=0.02)
    assert (out.max() == 0) == joined


def test_near_another_segment_is_its_definition_voxel_by_voxel() -> None:
    """Against the definition, one voxel at a time (no grid arrays): a voxel is kept when
    a voxel of another segment lies in its cell or one of the 26 around it (cells of
    1.01 x the reach, by floor). Random clouds of few and many segments."""
    from clearcli.perception.rims import _near_another_segment

    rng = np.random.default_rng(11)
    for n_seg in (2, 5, 40):
        pts = rng.uniform(-0.2, 0.3, (300, 3))
        seg = rng.integers(0, n_seg, 300)
        cell = np.floor(pts / (1.01 * 0.02)).astype(np.int64)
        expected = [
            bool(((np.abs(cell - cell[i]).max(axis=1) <= 1) & (seg != seg[i])).any()) for i in range(pts.shape[0])
        ]
        assert _near_another_segment(seg, pts, 0.02, n_seg).tolist() == expected


def _merge_rims_by_every_pair(
    seg: np.ndarray, pts: np.ndarray, height: np.ndarray, tolerance_m: float, contact_m: float, is_top: np.ndarray
) -> np.ndarray:
    """merge_rims' rule over every pair of voxels (a full distance matrix, no grid, no
    trees): the oracle of its pairs search."""
    from clearcli.perception.lccp import join_pairs

    n_seg = int(seg.max()) + 1
    d = np.linalg.norm(pts[:, None, :] - pts[None, :, :], axis=2)
    i, j = np.nonzero(np.triu(d <= contact_m, k=1) & (seg[:, None] != seg[None, :]))
    top = np.full(n_seg, -np.inf)
    np.maximum.at(top, seg, height)
    lo, hi = np.minimum(seg[i], seg[j]), np.maximum(seg[i], seg[j])
    h = 0.5 * (height[i] + height[j])
    at_top = (h >= top[lo] - tolerance_m) & (h >= top[hi] - tolerance_m) & ~(is_top[i] | is_top[j])
    joined = []
    for a, b in sorted(set(zip(lo.tolist(), hi.tolist(), strict=True))):
        pair = (lo == a) & (hi == b)
        if pair.sum() >= 5 and at_top[pair].sum() >= 0.9 * pair.sum():
            joined.append((a, b))
    return join_pairs(seg, np.asarray(joined, dtype=np.int64).reshape(-1, 2), n_seg)


def test_merge_rims_joins_what_every_pair_of_voxels_says() -> None:
    """On random clouds of 600 voxels in 3-8 segments side by side (slabs along x that
    touch their neighbours), merge_rims (the grid, then a search between two segments'
    trees) joins exactly what the rule over every pair of voxels joins: thin layers at
    about one height touch at both tops (joined, but where top voxels spoil the
    contact), tall walls touch all the way down (apart)."""
    from clearcli.perception.rims import merge_rims

    rng = np.random.default_rng(21)
    n_joined = []
    for trial in range(12):
        n_seg = 3 + trial % 6
        seg = rng.integers(0, n_seg, 600)
        pts = np.column_stack([0.03 * seg + rng.uniform(0.0, 0.035, 600), rng.uniform(0.0, 0.1, 600), np.zeros(600)])
        if trial % 2:
            pts[:, 2] = rng.uniform(0.0, 0.1, 600)  # walls
        else:
            pts[:, 2] = 0.1 + 0.003 * seg + rng.uniform(0.0, 0.006, 600)  # layers, tops 0.106 + 0.003 s
        is_top = rng.uniform(size=600) < 0.02 * (trial % 3)
        got = merge_rims(seg, pts, pts[:, 2], 0.012, 0.01, voxel_is_top=is_top)
        want = _merge_rims_by_every_pair(seg, pts, pts[:, 2], 0.012, 0.01, is_top)
        assert np.array_equal(got, want)
        n_joined.append(n_seg - (int(got.max()) + 1))
    assert min(n_joined) == 0 and max(n_joined) >= 2
