"""Connected components in NumPy against SciPy's csgraph, which they replace."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from clearcli.perception.graph import components, dense_labels


def _scipy(n: int, edges: np.ndarray) -> np.ndarray:
    graph = coo_matrix((np.ones(edges.shape[0]), (edges[:, 0], edges[:, 1])), shape=(n, n))
    return connected_components(graph, directed=False)[1]


def test_worked_example() -> None:
    # nodes 0..6: {0, 3, 5}, {1}, {2, 6}, {4}; the labels follow each one's lowest node
    edges = np.array([[5, 3], [3, 0], [6, 2]])
    assert components(7, edges).tolist() == [0, 1, 2, 0, 3, 0, 2]


def test_no_edges_and_no_nodes() -> None:
    assert components(3, np.zeros((0, 2), dtype=np.int64)).tolist() == [0, 1, 2]
    assert components(0, np.zeros((0, 2), dtype=np.int64)).tolist() == []


@pytest.mark.parametrize("seed", range(40))
def test_random_graphs_match_csgraph(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 500))
    edges = rng.integers(0, n, size=(int(rng.integers(0, 2 * n)), 2))  # loops and repeats too
    assert np.array_equal(components(n, edges), _scipy(n, edges))


@pytest.mark.parametrize("reverse", [False, True])
def test_long_path_either_way(reverse: bool) -> None:
    # a path is the worst case for hooking by rounds: one component, its root node 0
    n = 20_000
    edges = np.stack([np.arange(n - 1), np.arange(1, n)], axis=1)
    if reverse:
        edges = edges[::-1, ::-1]
    assert not components(n, edges).any()


def test_pixel_grid_matches_csgraph() -> None:
    rng = np.random.default_rng(7)
    h, w = 120, 160
    ids = np.arange(h * w).reshape(h, w)
    on = (rng.random((h, w)) < 0.6).ravel()
    pairs = []
    for a, b in (
        (ids[:, :-1], ids[:, 1:]),
        (ids[:-1], ids[1:]),
        (ids[:-1, :-1], ids[1:, 1:]),
        (ids[:-1, 1:], ids[1:, :-1]),
    ):
        keep = on[a.ravel()] & on[b.ravel()]
        pairs.append(np.stack([a.ravel()[keep], b.ravel()[keep]], axis=1))
    edges = np.concatenate(pairs)
    assert np.array_equal(components(h * w, edges), _scipy(h * w, edges))


# ------------------------------------------------------------------ labels numbered densely
def test_dense_labels_number_labels_as_unique_does() -> None:
    """`dense_labels` numbers labels by counting (no sort): the inverse np.unique gives,
    with gaps, repeats and an empty input, and on the fallbacks (negative labels, labels
    far above their count)."""
    rng = np.random.default_rng(3)
    cases = [
        np.array([5, 2, 2, 9, 5, 0]),
        np.zeros(0, dtype=np.int64),
        np.array([-4, 7, -4, 3]),
        np.array([10**9, 3, 10**9]),
        *(rng.integers(0, 60, 40) for _ in range(20)),
    ]
    for labels in cases:
        got = dense_labels(labels)
        assert got.dtype == np.int64
        assert np.array_equal(got, np.unique(labels, return_inverse=True)[1])
    assert dense_labels(np.array([5, 2, 2, 9])).tolist() == [1, 0, 0, 2]


def test_apart_sets_never_join_two_nodes_kept_apart_even_through_a_chain() -> None:
    from clearcli.perception.graph import ApartSets

    sets = ApartSets(5, [(0, 3)])
    assert sets.join(0, 1)  # {0, 1}
    assert sets.join(3, 2)  # {2, 3}
    assert not sets.join(1, 2)  # would put 0 and 3 in one set
    assert not sets.join(1, 0)  # one set already
    assert sets.kept_apart(sets.root(1)) and sets.kept_apart(sets.root(2))
    assert not sets.kept_apart(4)
    assert sets.join(4, 1)  # nothing keeps 4 apart
    assert sets.root(4) == sets.root(0) != sets.root(3)
    assert sets.joined == [(0, 1), (3, 2), (4, 0)]  # (the first node's root, the other's)
    # join_roots joins without a check (colors.py's far side of one object)
    sets.join_roots(sets.root(0), sets.root(3))
    assert len({sets.root(i) for i in range(5)}) == 1
