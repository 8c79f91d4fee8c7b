"""Depth-edge pieces on the pixel grid: the runs along rows give the pieces that every
pixel pair gives, numbered alike."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from clearcli.perception.edges import _PIXEL_OFFSETS, pixel_pieces
from clearcli.perception.graph import components


def _every_pair(points: np.ndarray, shape: tuple[int, int], point_index: np.ndarray, rel: float) -> np.ndarray:
    """pixel_pieces by the definition: every 8-neighbour pair of near ranges an edge."""
    height, width = shape
    where = np.full(height * width, -1, dtype=np.int64)
    where[point_index] = np.arange(point_index.size)
    img = where.reshape(height, width)
    rng = np.linalg.norm(points[point_index], axis=1)
    src, dst = [], []
    for dv, du in _PIXEL_OFFSETS:
        a = img[: height - dv, max(0, -du) : width - max(0, du)].ravel()
        b = img[dv:, max(0, du) : width - max(0, -du)].ravel()
        both = (a >= 0) & (b >= 0)
        a, b = a[both], b[both]
        near = np.abs(rng[a] - rng[b]) <= rel * np.minimum(rng[a], rng[b])
        src.append(a[near])
        dst.append(b[near])
    return components(point_index.size, np.stack([np.concatenate(src), np.concatenate(dst)], axis=1))


@pytest.mark.parametrize("seed", range(30))
def test_runs_give_the_pieces_of_every_pair(seed: int) -> None:
    gen = np.random.default_rng(seed)
    height, width = (int(x) for x in gen.integers(1, 12, size=2))
    points = gen.uniform(0.5, 1.5, size=(height * width, 3))
    index = np.flatnonzero(gen.random(height * width) < 0.7)
    if seed % 3 == 0:
        gen.shuffle(index)  # out of raster order: every pair, as before
    for rel in (0.02, 0.2, 1.0):
        want = _every_pair(points, (height, width), index, rel)
        got = pixel_pieces(points, (height, width), index, rel)
        assert got.dtype == np.int64
        assert got.tolist() == want.tolist()


def test_two_surfaces_apart_in_depth() -> None:
    # a 4x6 image: the left three columns at 1 m, the right three at 1.5 m
    height, width = 4, 6
    points = np.zeros((height, width, 3))
    points[:, :3, 2] = 1.0
    points[:, 3:, 2] = 1.5
    index = np.arange(height * width)
    pieces = pixel_pieces(points.reshape(-1, 3), (height, width), index, 0.02).reshape(height, width)
    assert (pieces[:, :3] == 0).all() and (pieces[:, 3:] == 1).all()
    assert pixel_pieces(points.reshape(-1, 3), (height, width), index[:0], 0.02).size == 0


@pytest.mark.parametrize("seed", range(10))
def test_a_set_inside_the_image_gives_the_pieces_of_every_pair(seed: int) -> None:
    """The pairs are looked for within the set's bounding box: a set away from the
    image's borders gives the pieces every pair gives."""
    gen = np.random.default_rng(100 + seed)
    height, width = 30, 40
    points = gen.uniform(0.5, 1.5, size=(height * width, 3))
    rows, cols = np.meshgrid(np.arange(5, 17), np.arange(9, 30), indexing="ij")
    box = (rows * width + cols).ravel()
    index = box[gen.random(box.size) < 0.7]
    if seed % 2:
        gen.shuffle(index)
    for rel in (0.02, 0.2, 1.0):
        want = _every_pair(points, (height, width), index, rel)
        assert pixel_pieces(points, (height, width), index, rel).tolist() == want.tolist()


def _most_counted_by_lexsort(row: np.ndarray, col: np.ndarray, count: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rule _most_counted replaced: sorted by row, descending count, column; the first of each row."""
    order = np.lexsort((col, -count, row))
    first = np.ones(order.shape[0], dtype=bool)
    first[1:] = row[order[1:]] != row[order[:-1]]
    return row[order[first]], col[order[first]]


@pytest.mark.parametrize("seed", range(20))
def test_most_counted_is_the_lexsort_rule(seed: int) -> None:
    from clearcli.perception.edges import _most_counted

    gen = np.random.default_rng(seed)
    n_pieces = int(gen.integers(1, 6))
    keys = np.unique(gen.integers(0, 40 * n_pieces, size=int(gen.integers(1, 200))))
    count = gen.integers(1, 4, size=keys.size)  # few values: many ties
    row, col = keys // n_pieces, keys % n_pieces
    got, want = _most_counted(row, col, count), _most_counted_by_lexsort(row, col, count)
    assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])


def test_most_counted_by_hand() -> None:
    from clearcli.perception.edges import _most_counted

    # row 0: columns 1 and 3 both counted 5 (the lower wins); row 2: column 0 alone; row 7: column 2 (9 > 4)
    row = np.array([0, 0, 0, 2, 7, 7])
    col = np.array([1, 2, 3, 0, 1, 2])
    count = np.array([5, 2, 5, 1, 4, 9])
    rows, cols = _most_counted(row, col, count)
    assert rows.tolist() == [0, 2, 7] and cols.tolist() == [1, 0, 2]


@pytest.fixture(scope="module")
def test55_edge_cut() -> tuple[Any, ...]:
    """The arguments `segment` passes to cut_depth_edges on mOSD test55 (16 objects)."""
    from helpers import shared_path

    from clearcli.io.read import read_frame
    from clearcli.perception import edges
    from clearcli.perception.segment import segment
    from clearcli.settings.segment import SegmentSettings

    frame = read_frame(shared_path("mosd/test/test55.pcd"))
    seen: list[tuple[Any, ...]] = []
    real = edges.cut_depth_edges

    def record(*args: Any, **kwargs: Any) -> Any:
        seen.append(args)  # positional: what pixel_pieces needs (xyz: those points again)
        return real(*args, **kwargs)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr("clearcli.perception.segment.cut_depth_edges", record)
        segment(frame, SegmentSettings())
    return seen[0]


def test_voxel_pieces_on_a_cluttered_frame_are_the_lexsort_rule_s(test55_edge_cut: tuple[Any, ...]) -> None:
    # mOSD test55 (16 objects): each voxel's piece and the small pieces' joins, against
    # those the lexsort rule chose
    from clearcli.perception import edges

    vox, points, shape, point_index, rel, min_piece = test55_edge_cut
    point_piece = pixel_pieces(points, shape, point_index, rel)
    got: list[np.ndarray] = []
    for rule in (edges._most_counted, _most_counted_by_lexsort):
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(edges, "_most_counted", rule)
            piece = edges._voxel_piece(vox.point_voxel, point_piece, vox.n_voxels)
            large = np.bincount(piece) >= min_piece
            got += [piece, edges._join_small(piece, large, vox.edges)]
    assert np.array_equal(got[0], got[2]) and np.array_equal(got[1], got[3])
    # a real comparison: voxels of several pieces, small pieces joined to large ones
    assert np.unique(got[0]).size > 5 and not np.array_equal(got[0], got[1])


def _join_small_both_ways(piece: np.ndarray, large: np.ndarray, edges_: np.ndarray) -> np.ndarray:
    """The rule _join_small keeps, as first written: every adjacency both ways, stacked."""
    from clearcli.perception.edges import _most_counted

    both = np.concatenate([edges_, edges_[:, ::-1]])
    want = ~large[piece[both[:, 0]]] & large[piece[both[:, 1]]]
    if not want.any():
        return piece
    v, p = both[want, 0], piece[both[want, 1]]
    n_pieces = int(piece.max()) + 1
    uniq, count = np.unique(v * n_pieces + p, return_counts=True)
    vv, pp = _most_counted(uniq // n_pieces, uniq % n_pieces, count)
    out = piece.copy()
    out[vv] = pp
    return out


def test_join_small_by_hand() -> None:
    from clearcli.perception.edges import _join_small

    # voxel 2 is piece 1 (small) alone; pieces 0 (voxels 0, 1) and 2 (voxels 3, 4) are large
    piece = np.array([0, 0, 1, 2, 2])
    large = np.array([True, False, True])
    # the small voxel second in one adjacency, first in two: 1 vote for piece 0, 2 for piece 2
    edges_ = np.array([[0, 2], [2, 3], [2, 4]])
    assert _join_small(piece, large, edges_).tolist() == [0, 0, 2, 2, 2]
    # 2 votes each (both of them second in their adjacency): the lower piece
    edges_ = np.array([[0, 2], [1, 2], [3, 2], [2, 4]])
    assert _join_small(piece, large, edges_).tolist() == [0, 0, 0, 2, 2]
    # no small piece touches a large one: the pieces as they were
    assert _join_small(piece, large, np.array([[0, 1], [3, 4]])).tolist() == piece.tolist()


@pytest.mark.parametrize("seed", range(10))
def test_join_small_is_the_rule_both_ways(seed: int) -> None:
    from clearcli.perception.edges import _join_small

    gen = np.random.default_rng(200 + seed)
    n_vox, n_pieces = 60, 8
    piece = gen.integers(0, n_pieces, size=n_vox)
    large = gen.random(n_pieces) < 0.5
    edges_ = gen.integers(0, n_vox, size=(150, 2))
    got, want = _join_small(piece, large, edges_), _join_small_both_ways(piece, large, edges_)
    assert got.tolist() == want.tolist()
    assert not np.array_equal(got, piece)  # a real comparison: some voxel joined


def test_pixel_pieces_on_a_cluttered_frame_are_every_pair_s(test55_edge_cut: tuple[Any, ...]) -> None:
    # mOSD test55 (16 objects): the pieces of the object points against the definition
    # (every near 8-neighbour pair an edge), in float64 as pixel_pieces measures ranges
    _, points, shape, point_index, rel, _ = test55_edge_cut
    got = pixel_pieces(points, shape, point_index, rel)
    want = _every_pair(points.astype(np.float64), shape, point_index, rel)
    assert np.array_equal(got, want)
    assert np.unique(got).size > 16  # the objects and the pieces the depth edges cut


def test_voxel_piece_reads_one_piece_voxels_without_counting(test55_edge_cut: tuple[Any, ...]) -> None:
    """`_voxel_piece` (a voxel of one piece read from its lowest and highest, the rest
    counted) is `_counted_piece` (every voxel counted): on mOSD test55 (every voxel's
    points lie in one piece there: a depth edge lies between voxels), and on random
    points with voxels of one piece, of several (ties too) and of none."""
    from clearcli.perception.edges import _counted_piece, _voxel_piece

    vox, points, shape, point_index, rel, _ = test55_edge_cut
    point_piece = pixel_pieces(points, shape, point_index, rel)
    got = _voxel_piece(vox.point_voxel, point_piece, vox.n_voxels)
    assert np.array_equal(got, _counted_piece(vox.point_voxel, point_piece, vox.n_voxels))
    assert np.unique(got).size > 5
    rng = np.random.default_rng(4)
    for n_pieces in (1, 2, 5, 300):
        point_voxel = rng.integers(0, 200, 1000)  # voxels 200-209: no points
        point_piece = np.where(point_voxel < 120, point_voxel % n_pieces, rng.integers(0, n_pieces, 1000))
        if n_pieces > 1:  # a real comparison: voxels 120-199 of several pieces, most of them
            assert np.unique(point_voxel * n_pieces + point_piece).size > 150
        assert np.array_equal(
            _voxel_piece(point_voxel, point_piece, 210), _counted_piece(point_voxel, point_piece, 210)
        )
    assert _voxel_piece(np.zeros(0, np.int64), np.zeros(0, np.int64), 3).tolist() == [0, 0, 0]
