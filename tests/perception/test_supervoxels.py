"""Tests of clearcli/perception/supervoxels.py."""

from __future__ import annotations

import numpy as np
import pytest


def test_voxel_adjacency_is_the_26_neighbourhood() -> None:
    from clearcli.perception.supervoxels import voxelize

    g = np.stack(np.meshgrid(*[np.arange(3)] * 3, indexing="ij"), -1).reshape(-1, 3) * 0.01 + 0.005
    vox = voxelize(g, 0.01)
    assert vox.n_voxels == 27
    # pairs of a 3x3x3 block at Chebyshev distance 1: (27*26 - non-adjacent) / 2
    d = np.abs(vox.keys[:, None, :] - vox.keys[None, :, :]).max(-1)
    assert vox.edges.shape[0] == int((d == 1).sum()) // 2


def _edges_by_13_searches(uniq: np.ndarray, dims: list[int]) -> np.ndarray:
    """The adjacency as voxelize found it before: one binary search per half offset."""
    from clearcli.perception.supervoxels import _HALF_OFFSETS

    n = uniq.shape[0]
    src, dst = [], []
    for off in _HALF_OFFSETS:
        target = uniq + (off[0] * dims[1] + off[1]) * dims[2] + off[2]
        pos = np.minimum(np.searchsorted(uniq, target), n - 1)
        hit = uniq[pos] == target
        src.append(np.flatnonzero(hit))
        dst.append(pos[hit])
    return np.stack([np.concatenate(src), np.concatenate(dst)], axis=1)


def test_adjacency_and_voxels_as_the_searches_and_np_unique_gave_them() -> None:
    from clearcli.perception.supervoxels import _adjacency, _unique_inverse, grid_cells, voxelize

    gen = np.random.default_rng(7)
    for n_points, extent_m in ((300, 0.02), (3000, 0.05), (5000, 0.2)):
        # points in runs along x (as a camera row lists them), some voxels dense, some sparse
        start = gen.uniform(0, extent_m, (n_points // 5, 3))
        pts = (start[:, None, :] + np.arange(5)[None, :, None] * [0.0011, 0, 0]).reshape(-1, 3)
        vox = voxelize(pts, 0.005)
        keys = grid_cells(pts, 0.005)
        keys -= keys.min(axis=0) - 1
        dims = [int(d) for d in keys.max(axis=0) + 2]
        packed = (keys[:, 0] * dims[1] + keys[:, 1]) * dims[2] + keys[:, 2]
        uniq, inverse = np.unique(packed, return_inverse=True)
        got_u, got_i = _unique_inverse(packed)
        assert np.array_equal(got_u, uniq) and np.array_equal(got_i, inverse)
        assert np.array_equal(vox.point_voxel, inverse)
        want = _edges_by_13_searches(uniq, dims)
        assert want.shape[0] > 0
        assert np.array_equal(_adjacency(uniq, dims), want)  # the same pairs in the same order
        assert np.array_equal(vox.edges, want)
    empty = np.zeros(0, dtype=np.int64)
    assert _unique_inverse(empty)[0].shape == (0,) and _adjacency(empty, [3, 3, 3]).shape == (0, 2)


def test_dot3_sums_as_einsum() -> None:
    """The callers of _dot3 replaced np.einsum over rows of 3 and must give its bits
    (orient_towards's flips, the VCCS costs): a NumPy whose einsum sums otherwise fails here."""
    from clearcli.perception.supervoxels import _dot3

    gen = np.random.default_rng(11)
    x = gen.standard_normal((200_000, 3)) * 10.0 ** gen.integers(-8, 3, (200_000, 3))
    y = gen.standard_normal((200_000, 3)) * 10.0 ** gen.integers(-8, 3, (200_000, 3))

    def cols(a: np.ndarray) -> tuple[np.ndarray, ...]:
        return tuple(a[:, j] for j in range(3))

    assert np.array_equal(_dot3(cols(x), cols(y)), np.einsum("ij,ij->i", x, y))
    # a normal against the normals of its 8 nearest seeds
    v, s = x[:25_000], y.reshape(25_000, 8, 3)
    got = _dot3(tuple(v[:, j, None] for j in range(3)), tuple(s[:, :, j] for j in range(3)))
    assert np.array_equal(got, np.einsum("vj,vkj->vk", v, s))


def test_smallest_eigenvectors_are_eighs() -> None:
    from clearcli.perception.supervoxels import smallest_eigenvectors

    gen = np.random.default_rng(13)
    n = 4000
    # covariances of patches: flat (the closed form), thin lines and near-isotropic (eigh)
    axes = np.linalg.qr(gen.standard_normal((n, 3, 3)))[0]
    spread = np.stack([gen.uniform(1e-6, 1, n), gen.uniform(1e-6, 1, n), gen.uniform(1e-6, 1, n)], axis=1)
    spread[: n // 4, 0] = spread[: n // 4, 1]  # two equal: the smallest stands apart or not
    cov = np.einsum("nij,nj,nkj->nik", axes, spread, axes) * 1e-5
    got = smallest_eigenvectors(cov)
    evals, evecs = np.linalg.eigh(cov)
    apart = (evals[:, 1] - evals[:, 0]) > 1e-3 * evals[:, 2]
    assert apart.sum() > n // 2
    assert np.allclose(np.linalg.norm(got, axis=1), 1.0)
    # the same vector up to sign where the smallest eigenvalue is distinct
    assert np.abs(np.abs(np.einsum("ij,ij->i", got[apart], evecs[apart, :, 0])) - 1.0).max() < 1e-9
    assert np.allclose(np.einsum("nij,nj->ni", cov, got), evals[:, :1] * got, atol=1e-12)


# a voxel boundary (cells of 5 mm shifted by GRID_SHIFT_M: 4.465 cm) in the middle of the
# seed cell [2.965, 5.965) cm
_COLOUR_EDGE_M = 0.04465
_RED, _GREEN = (200, 30, 30), (30, 160, 60)  # 118.5 dE apart


def _two_colour_patch(
    color_importance: float, left_rgb: tuple[int, int, int], right_rgb: tuple[int, int, int]
) -> tuple[np.ndarray, np.ndarray]:
    """The supervoxel of each voxel of a flat 12 x 6 cm patch 1 m in front of the camera,
    facing it, points 1 mm apart, coloured ``left_rgb`` left of _COLOUR_EDGE_M and
    ``right_rgb`` beyond; and whether each voxel lies left of the edge."""
    import dataclasses

    from clearcli.perception.supervoxels import supervoxel_labels, voxel_normals, voxelize
    from clearcli.settings.segment import SegmentSettings

    settings = dataclasses.replace(SegmentSettings(), color_importance=color_importance)
    x, y = np.meshgrid(np.arange(0.0005, 0.12, 0.001), np.arange(0.0005, 0.06, 0.001), indexing="ij")
    points = np.stack([x.ravel(), y.ravel(), np.full(x.size, 1.0)], axis=1)
    left = points[:, 0] < _COLOUR_EDGE_M
    colors = np.where(left[:, None], np.array(left_rgb), np.array(right_rgb)).astype(np.uint8)
    vox = voxelize(points, settings.voxel_m, colors)
    normals = voxel_normals(vox.centroids, settings.normal_radius_m, np.zeros(3))
    return supervoxel_labels(vox, normals, settings), vox.centroids[:, 0] < _COLOUR_EDGE_M


def _straddling(labels: np.ndarray, voxel_left: np.ndarray) -> int:
    """How many supervoxels hold voxels on both sides of the colour edge."""
    return sum(len(set(voxel_left[labels == s].tolist())) == 2 for s in range(int(labels.max()) + 1))


def test_colour_keeps_a_supervoxel_on_one_side_of_a_colour_edge() -> None:
    # geometry alone: the two supervoxels seeded in the cells the edge runs through (one
    # per row of cells) hold both colours; with colour, none does
    assert _straddling(*_two_colour_patch(0.0, _RED, _GREEN)) == 2
    assert _straddling(*_two_colour_patch(0.7, _RED, _GREEN)) == 0


def test_a_faint_colour_difference_moves_no_voxel() -> None:
    # 8.7 dE (a print, light and shade): at 0.7 it weighs 0.06 in the cost, too little to
    # move a voxel here, so the supervoxels are those of geometry alone
    faint = (180, 30, 30)
    labels_0, _ = _two_colour_patch(0.0, _RED, faint)
    labels_c, _ = _two_colour_patch(0.7, _RED, faint)
    np.testing.assert_array_equal(labels_c, labels_0)


@pytest.mark.parametrize("iterations", [1, 2, 3])
def test_seeds_move_between_assignments_only(monkeypatch: pytest.MonkeyPatch, iterations: int) -> None:
    # the seeds move to their voxels' means (positions and normals: two _seed_sums, a
    # third for colour) after every assignment but the last, whose labels are the answer
    import dataclasses

    from clearcli.perception import supervoxels
    from clearcli.settings.segment import SegmentSettings

    settings = dataclasses.replace(SegmentSettings(), color_importance=0.0, supervoxel_iterations=iterations)
    x, y = np.meshgrid(np.arange(0.0005, 0.12, 0.001), np.arange(0.0005, 0.06, 0.001), indexing="ij")
    vox = supervoxels.voxelize(np.stack([x.ravel(), y.ravel(), np.full(x.size, 1.0)], axis=1), settings.voxel_m)
    normals = supervoxels.voxel_normals(vox.centroids, settings.normal_radius_m, np.zeros(3))
    sums = supervoxels._seed_sums
    calls: list[int] = []

    def counted(values: np.ndarray, lab: np.ndarray, used: np.ndarray | None, n_seeds: int) -> np.ndarray:
        calls.append(n_seeds)
        return sums(values, lab, used, n_seeds)

    monkeypatch.setattr(supervoxels, "_seed_sums", counted)
    labels = supervoxels.supervoxel_labels(vox, normals, settings)
    assert len(calls) == 2 * (iterations - 1)
    # a 12 x 6 cm patch on 3 cm seed cells: 4 x 2 cells, each a seed and a supervoxel
    assert int(labels.max()) + 1 == 8


def test_radius_knn_by_hand() -> None:
    from clearcli.perception.supervoxels import radius_knn

    # points on a line at 0, 1, 3 and 10 mm: within 5 mm, nearest first; 4 where none
    pts = np.array([[0.0, 0, 0], [0.001, 0, 0], [0.003, 0, 0], [0.010, 0, 0]])
    assert radius_knn(pts, 3, 0.005).tolist() == [[0, 1, 2], [1, 0, 2], [2, 1, 0], [3, 4, 4]]
    assert radius_knn(pts[:1], 1, 0.005).tolist() == [[0]]
    assert radius_knn(pts[:0], 3, 0.005).shape == (0, 3)


def test_radius_knn_is_the_trees_query() -> None:
    """The same neighbours in the same order as cKDTree's k-nearest query, ties included:
    the normals' sums follow that order, and so every later bit."""
    from scipy.spatial import cKDTree

    from clearcli.perception.supervoxels import radius_knn

    gen = np.random.default_rng(5)
    ties = 0
    for trial in range(120):
        n = int(gen.integers(2, 500))
        pts = gen.uniform(0.0, 0.03, (n, 3))
        if trial % 2:
            pts = np.round(pts, 3)  # whole millimetres: equal distances, repeated points
        k = int(min(gen.integers(1, 40), n))
        radius_m = float(gen.choice([0.002, 0.005, 0.01]))
        dist, want = cKDTree(pts).query(pts, k=k, distance_upper_bound=radius_m)
        want, dist = want.reshape(n, k), dist.reshape(n, k)
        ties += int(np.sum((dist[:, 1:] == dist[:, :-1]) & np.isfinite(dist[:, 1:])))
        assert np.array_equal(radius_knn(pts, k, radius_m), want)
    assert ties > 1000  # the trees' order of ties was asked for
    # a radius of many points (a dense grid: ~500 within it, k = 30): the same
    pts = np.stack(np.meshgrid(*[np.arange(12) * 0.001] * 3, indexing="ij"), -1).reshape(-1, 3)
    want = cKDTree(pts).query(pts, k=30, distance_upper_bound=0.005)[1]
    assert np.array_equal(radius_knn(pts, 30, 0.005), want)


def test_radius_knn_at_the_radius() -> None:
    """Few points (wide distance buckets) a few parts in 1e7 to 1e10 either side of the
    radius: the tree's verdict, and no bucket spilling into the point's bits."""
    from scipy.spatial import cKDTree

    from clearcli.perception.supervoxels import radius_knn

    gen = np.random.default_rng(1)
    radius_m = 0.005
    for n in range(1, 30):
        for _ in range(10):
            pts = np.zeros((n, 3))
            step = 1.0 + gen.choice([-1.0, 1.0], n) * 10.0 ** gen.uniform(-10, -7, n)
            pts[:, 0] = radius_m * np.cumsum(step * gen.choice([1.0, 0.5], n))
            k = int(gen.integers(1, n + 1))
            want = cKDTree(pts).query(pts, k=k, distance_upper_bound=radius_m)[1].reshape(n, k)
            assert np.array_equal(radius_knn(pts, k, radius_m), want)


def test_radius_knn_beyond_the_radius_on_many_points() -> None:
    """Over 2^17 points the distances keep 27 bits or fewer, and a pair just beyond the
    radius (the tree's pairs reach 1e-7 past it) falls in the last bucket, past the band
    asked of the tree: it is no neighbour, as in the tree's query."""
    from scipy.spatial import cKDTree

    from clearcli.perception.supervoxels import radius_knn

    radius_m = 0.005
    gen = np.random.default_rng(3)
    side = 52  # 52^3 = 140608 points 5 cm apart: no pairs but the ones placed below
    pts = np.stack(np.meshgrid(*[np.arange(side) * 0.05] * 3, indexing="ij"), -1).reshape(-1, 3)
    base = 2 * gen.choice(pts.shape[0] // 2, 2000, replace=False)
    # its odd neighbour moved next to each of them along x: a few parts in 1e8 beyond or
    # within the radius, or at half of it
    gap_m = radius_m * np.concatenate((1.0 + gen.choice([-5e-8, 5e-8], 1000), np.full(1000, 0.5)))
    pts[base + 1] = pts[base]
    pts[base + 1, 0] += gap_m
    want = cKDTree(pts).query(pts, k=3, distance_upper_bound=radius_m)[1]
    assert np.array_equal(radius_knn(pts, 3, radius_m), want)
    beyond = int(np.count_nonzero(want[base[:1000], 1] == pts.shape[0]))
    assert 300 < beyond < 700  # about half of the first thousand beyond it


def test_radius_knn_asks_the_tree_only_about_ties(monkeypatch: pytest.MonkeyPatch) -> None:
    """The tree's own k-nearest query is asked only about the points with two equal
    distances among their first k + 1 (or one at the radius): none on points at random,
    those with a tie on whole millimetres, no more than those with a near-tie (1e-9)."""
    import scipy.spatial

    from clearcli.perception.supervoxels import radius_knn

    tree_type = scipy.spatial.cKDTree
    asked: list[int] = []

    class Counting(tree_type):  # type: ignore[misc, valid-type]
        def query(self, x: np.ndarray, *args: object, **kwargs: object) -> object:
            asked.append(int(np.asarray(x).shape[0]))
            return super().query(x, *args, **kwargs)

    monkeypatch.setattr(scipy.spatial, "cKDTree", Counting)
    gen = np.random.default_rng(7)
    pts = gen.uniform(0.0, 0.03, (2000, 3))
    want = tree_type(pts).query(pts, k=30, distance_upper_bound=0.005)[1]
    assert np.array_equal(radius_knn(pts, 30, 0.005), want)
    assert sum(asked) == 0
    pts = np.round(pts, 3)  # whole millimetres: equal distances, each point with some
    dist = tree_type(pts).query(pts, k=31, distance_upper_bound=0.005)[0]
    want = tree_type(pts).query(pts, k=30, distance_upper_bound=0.005)[1]
    later, earlier = dist[:, 1:], dist[:, :-1]
    tied = ((later == earlier) & np.isfinite(later)).any(axis=1)
    with np.errstate(invalid="ignore"):  # inf - inf past the last neighbour: NaN, no near-tie
        near_tied = ((later - earlier <= 1e-9 * later) & np.isfinite(later)).any(axis=1)
    asked.clear()
    assert np.array_equal(radius_knn(pts, 30, 0.005), want)
    assert 1000 < int(tied.sum()) <= sum(asked) <= int(near_tied.sum())


def test_thin_strips_take_the_closed_form(monkeypatch: pytest.MonkeyPatch) -> None:
    """A strip's covariance (largest eigenvalue far above the other two, the smallest
    well apart from the middle one) needs no eigh: its vector is eigh's within 1e-9."""
    from clearcli.perception import supervoxels

    gen = np.random.default_rng(17)
    n = 2000
    axes = np.linalg.qr(gen.standard_normal((n, 3, 3)))[0]
    # eigenvalues 1, 0.02-0.2, 1e-6-1e-3 (scaled): the middle one nearer the smallest
    spread = np.stack([gen.uniform(1e-6, 1e-3, n), gen.uniform(0.02, 0.2, n), np.ones(n)], axis=1)
    cov = np.einsum("nij,nj,nkj->nik", axes, spread, axes) * 1e-5
    want = np.linalg.eigh(cov)[1][:, :, 0]
    calls: list[int] = []
    real_eigh = np.linalg.eigh

    def counted(a: np.ndarray) -> object:
        calls.append(a.shape[0])
        return real_eigh(a)

    monkeypatch.setattr(supervoxels.np.linalg, "eigh", counted)
    got = supervoxels.smallest_eigenvectors(cov)
    assert calls == []
    assert np.abs(np.abs(np.einsum("ij,ij->i", got, want)) - 1.0).max() < 1e-9


def test_weighted_normals_are_the_weighted_pca_of_the_stencils_points() -> None:
    """Each voxel's normal: the smallest eigenvector of the covariance of the points of
    the voxels whose cells lie within the radius of its cell, a voxel of n points
    weighing min(n, 4) / 4 (each of its points min(n, 4) / (4 n)), by hand with eigh."""
    from clearcli.perception.supervoxels import voxelize, weighted_voxel_normals

    gen = np.random.default_rng(3)
    # a bumpy sheet with sparse and dense patches: voxels of 1 to dozens of points
    xy = gen.uniform(0.0, 0.03, (900, 2))
    xy = np.concatenate([xy, gen.uniform(0.0, 0.008, (300, 2))])
    pts = np.column_stack([xy, 0.5 + 0.3 * xy[:, 0] + 0.002 * np.sin(300 * xy[:, 1])])
    vox = voxelize(pts, 0.005, scatter=True)
    assert vox.counts.min() < 4 < vox.counts.max()
    got = weighted_voxel_normals(vox, 0.011, 0.005, np.zeros(3), full_weight_points=4)
    point_weight = np.minimum(vox.counts, 4) / 4 / vox.counts
    for i in range(vox.n_voxels):
        near = np.flatnonzero(((vox.keys - vox.keys[i]) ** 2).sum(axis=1) <= (0.011 / 0.005) ** 2)
        mine = np.isin(vox.point_voxel, near)
        w = point_weight[vox.point_voxel[mine]]
        p = pts[mine]
        mean = (w[:, None] * p).sum(axis=0) / w.sum()
        cov = ((w[:, None] * (p - mean)).T @ (p - mean)) / w.sum()
        want = np.linalg.eigh(cov)[1][:, 0]
        if near.size >= 3:
            assert abs(float(got[i] @ want)) > 1 - 1e-9
    assert np.all(got[:, 2] < 0)  # facing the camera at the origin


def test_a_voxel_of_one_point_coming_or_going_turns_no_normal_far() -> None:
    """Issue 37: a point 3 mm off a tilted sheet (1 mm pitch) moved 1 um across a cell
    side makes a voxel of its own or joins one of 4 or more points. On the 30 nearest
    voxel centroids, each voxel weighing alike (the default), the normals around turned
    by 3.9 degrees; with normal_stencil (weighted by their points, up to 4) by 0.8."""
    from clearcli.perception.size import SegmentSize
    from clearcli.perception.supervoxels import GRID_SHIFT_M, grid_cells, stage_voxel_normals, voxelize
    from clearcli.settings.segment import SegmentSettings

    settings = SegmentSettings(normal_stencil=True)
    size = SegmentSize.of(settings)
    g = np.arange(0.0, 0.04, 0.001)
    x, y = np.meshgrid(g, g, indexing="ij")
    sheet = np.stack([x.ravel(), y.ravel(), 0.6 + 0.2 * x.ravel()], axis=1)
    side_x = 0.02 - GRID_SHIFT_M  # a cell side of the 5 mm grid
    runs = []
    for dx in (-0.5e-6, 0.5e-6):
        stray = np.array([[side_x + dx, 0.0224, 0.6 + 0.2 * side_x + 0.003]])
        vox = voxelize(np.concatenate([sheet, stray]), size.voxel_m, scatter=True)
        cells = {tuple(c): i for i, c in enumerate(grid_cells(vox.centroids, size.voxel_m).tolist())}
        runs.append((vox, cells, stage_voxel_normals(vox, np.zeros(3), settings, size)))
    (va, ca, na), (vb, cb, nb) = runs
    assert va.n_voxels == vb.n_voxels + 1 and va.counts.min() == 1  # a voxel of one point, then none
    both = np.array([(i, cb[c]) for c, i in ca.items() if c in cb])
    turn = np.degrees(np.arccos(np.clip(np.abs((na[both[:, 0]] * nb[both[:, 1]]).sum(axis=1)), 0.0, 1.0)))
    assert 0.1 < turn.max() < 1.2


def _star(variances: tuple[float, float, float]) -> np.ndarray:
    """7 voxel centroids: the origin (the seed) and two on each axis at +-a_j, so that
    the covariance of the 7 is diag(2 a_j^2 / 7): a_j^2 = 7 variance_j / 2."""
    pts = [np.zeros(3)]
    for j, var in enumerate(variances):
        for sign in (-1.0, 1.0):
            p = np.zeros(3)
            p[j] = sign * np.sqrt(3.5 * var)
            pts.append(p)
    return np.array(pts)


def test_seed_normal_tensors_by_hand() -> None:
    """Covariance diag(4, 2, 1) u, spread 2: weights (1 - (4 - 1) / 2) ** 2 -> 0,
    (1 - (2 - 1) / 2) ** 2 = 1/4 and 1, so T = diag(0, 1/4, 1); a voxel normal
    (0, sin 60, cos 60) aligns by sqrt(3/4 * 1/4 + 1/4 * 1) = sqrt(0.4375) = 0.6614 (0.5
    against e_z alone). Spread 1: the ratio 2 is out of reach, T = e_z e_z^T and the
    seed is not spread. A flat patch: T = e_z e_z^T."""
    from clearcli.perception.supervoxels import _tensor_alignment, seed_normal_tensors

    u = 4e-6  # m^2: a_x = 7.5 mm, all 7 within 15 mm
    t, spread = seed_normal_tensors(_star((4 * u, 2 * u, u)), np.array([0]), 0.015, 2.0)
    # (xx, xy, xz, yy, yz, zz)
    np.testing.assert_allclose(t[0], [0.0, 0.0, 0.0, 1 / 4, 0.0, 1.0], atol=1e-12)
    assert spread.tolist() == [True]
    n = (np.array([0.0]), np.array([np.sin(np.radians(60))]), np.array([np.cos(np.radians(60))]))
    np.testing.assert_allclose(_tensor_alignment(t, np.array([0]), n), [np.sqrt(0.4375)], atol=1e-12)
    t, spread = seed_normal_tensors(_star((4 * u, 2 * u, u)), np.array([0]), 0.015, 1.0)
    np.testing.assert_allclose(t[0], [0.0, 0.0, 0.0, 0.0, 0.0, 1.0], atol=1e-12)
    assert spread.tolist() == [False]

    g = np.arange(-2, 3) * 0.002
    x, y = np.meshgrid(g, g, indexing="ij")
    flat = np.stack([x.ravel(), y.ravel(), np.full(25, 0.7)], axis=1)
    centre = int(np.flatnonzero((x.ravel() == 0) & (y.ravel() == 0))[0])
    t, spread = seed_normal_tensors(flat, np.array([centre]), 0.015, 1.0)
    np.testing.assert_allclose(t[0], [0, 0, 0, 0, 0, 1], atol=1e-9)
    assert spread.tolist() == [False]


def test_seed_normal_tensor_is_continuous_where_the_normal_is_not() -> None:
    """Issue 37 (gqcnn_primesense_4 perturbed: a seed's two least eigenvalues 1.48 and
    1.74e-5 m^2, its normal turned 17 degrees): two neighbourhoods whose least variances
    swap, 1 and 1.01 against 1.01 and 1 (and 5): the least eigenvector turns 90 degrees,
    the tensor at spread 1 by its entries (1 - 0.01) ** 2 = 0.9801 and 1, 0.02 apart."""
    from clearcli.perception.supervoxels import seed_normal_tensors, smallest_eigenvectors

    u = 4e-6
    a, b = _star((u, 1.01 * u, 5 * u)), _star((1.01 * u, u, 5 * u))
    ta, tb = (seed_normal_tensors(p, np.array([0]), 0.015, 1.0)[0][0] for p in (a, b))
    na, nb = (smallest_eigenvectors((p.T @ p / 7.0)[None])[0] for p in (a, b))
    assert abs(float(na @ nb)) < 1e-9  # the normal: x, then y
    np.testing.assert_allclose(ta, [1.0, 0.0, 0.0, 0.99**2, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(tb, [0.99**2, 0.0, 0.0, 1.0, 0.0, 0.0], atol=1e-9)
    assert np.abs(ta - tb).max() < 0.021


def test_seed_normal_spread_serves_the_first_assignment_of_spread_seeds_only(monkeypatch: pytest.MonkeyPatch) -> None:
    """Off (0) no tensor is computed; on, the seeds of a flat slab (no crease) give the
    same labels bit for bit, and those of a blob (every neighbourhood near isotropic)
    meet their tensors in the first of 3 assignments only."""
    from clearcli.perception import supervoxels
    from clearcli.perception.supervoxels import supervoxel_labels, voxelize
    from clearcli.settings.segment import SegmentSettings

    calls: list[int] = []
    alignment = supervoxels._tensor_alignment

    def counted(seed_tensor: np.ndarray, nb: np.ndarray, voxel_nrm: tuple[np.ndarray, ...]) -> np.ndarray:
        calls.append(nb.shape[0])
        return alignment(seed_tensor, nb, voxel_nrm)

    monkeypatch.setattr(supervoxels, "_tensor_alignment", counted)
    rng = np.random.default_rng(0)
    on = SegmentSettings(seed_normal_spread=1.0, supervoxel_iterations=3)
    slab = voxelize(rng.uniform(0.0, 0.1, size=(20000, 3)) * (1.0, 1.0, 0.0) + (0.0, 0.0, 0.7), 0.005)
    normals = np.tile([0.0, 0.0, -1.0], (slab.n_voxels, 1))
    off_labels = supervoxel_labels(slab, normals, SegmentSettings(supervoxel_iterations=3))
    assert np.array_equal(off_labels, supervoxel_labels(slab, normals, on))
    assert calls == []
    blob = voxelize(rng.uniform(0.0, 0.06, size=(20000, 3)) + (0.0, 0.0, 0.7), 0.005)
    normals = rng.normal(size=(blob.n_voxels, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    supervoxel_labels(blob, normals, SegmentSettings(supervoxel_iterations=3))
    assert calls == []
    supervoxel_labels(blob, normals, on)
    assert len(calls) == 1 and calls[0] > 0


def test_the_trace_of_the_assignments_changes_nothing() -> None:
    """supervoxel_labels' trace (benchmarks/stability.supervoxel_decisions): the seed
    voxels, then per assignment each voxel's seed and its cost margin to the runner-up;
    the labels are those without it. Two seeds on a flat strip of voxels, all normals
    alike: the margin is the difference of the distances to the two / 3 cm, and inf
    where the other seed lies 4.5 cm away or more (beyond the search)."""
    from clearcli.perception.supervoxels import supervoxel_labels, voxelize
    from clearcli.settings.segment import SegmentSettings

    x = np.arange(0.0, 0.06, 0.001)
    g = np.arange(0.0, 0.005, 0.001)
    xx, yy = np.meshgrid(x, g, indexing="ij")
    pts = np.stack([xx.ravel(), yy.ravel(), np.full(xx.size, 0.7)], axis=1)
    vox = voxelize(pts, 0.005)
    normals = np.tile([0.0, 0.0, -1.0], (vox.n_voxels, 1))
    settings = SegmentSettings()
    trace: list[np.ndarray] = []
    labels = supervoxel_labels(vox, normals, settings, trace=trace)
    assert np.array_equal(labels, supervoxel_labels(vox, normals, settings))
    assert len(trace) == 1 + 2 * settings.supervoxel_iterations
    seeds, first, margin = trace[0], trace[1], trace[2]
    assert seeds.shape == (2,) and first.shape == margin.shape == (vox.n_voxels,)
    assert set(first.tolist()) == {0, 1} and (margin >= 0).all()
    d = np.linalg.norm(vox.centroids[:, None, :] - vox.centroids[seeds][None], axis=2) / 0.03
    # the search's bound (1.5 seeds) leaves out 4.5 cm itself: the ends lie 1 and 8 cells
    # from the seeds (cells 2 and 9 of 12, centroids 5 mm apart)
    beyond = d.max(axis=1) > 1.5 - 1e-9
    np.testing.assert_allclose(margin, np.where(beyond, np.inf, np.abs(d[:, 0] - d[:, 1])), atol=1e-12)
    assert np.isinf(margin).sum() == 2  # the strip's two ends
