"""Connected components of an undirected graph given by its edges, in NumPy.

This replaces ``scipy.sparse.csgraph.connected_components``: the stages only ever ask
for the components of an edge list, and importing ``scipy.sparse`` and its ``csgraph``
costs a cold call 0.15-0.17 s (SciPy's sparse linear algebra and array-API layer come
with it), more than every component search of a frame together.

The labels are the ones csgraph gives: 0..C-1 numbered in order of each component's
lowest node, so every caller's output is unchanged.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np


def dense_labels(labels: np.ndarray) -> np.ndarray:
    """(N,) int64: each of the integer ``labels`` (N,) numbered by its rank among the
    distinct ones, what ``np.unique(labels, return_inverse=True)[1]`` gives, by counting
    the labels present instead of sorting them (labels are 0..G-1 with gaps here); it
    falls back on np.unique for negative labels or ones far above their count."""
    if labels.size == 0:
        return np.unique(labels, return_inverse=True)[1].astype(np.int64)
    top, low = int(labels.max()), int(labels.min())
    if low < 0 or top >= 8 * labels.size + 4096:
        return np.unique(labels, return_inverse=True)[1].astype(np.int64)
    present = np.zeros(top + 1, dtype=bool)
    present[labels] = True
    return (np.cumsum(present, dtype=np.int64) - 1)[labels]


def components(n: int, edges: np.ndarray) -> np.ndarray:
    """(n,) int64 component label of each of the ``n`` nodes joined by ``edges`` ((E, 2)
    ints in [0, n)), numbered 0..C-1 in order of each component's lowest node.

    Union by hooking: each round, every edge whose ends lie in different trees hooks the
    larger root under the smaller one; then every node is pointed straight at its root.
    Pointers only ever go to a lower node of the same component, so there are no cycles,
    the lowest node stays a root, and when no edge joins two trees each component is one
    tree whose root is its lowest node. Edges found inside one tree are dropped for good,
    so later rounds cost only what is still being joined."""
    root = np.arange(n, dtype=np.int64)
    e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    r = e  # the roots of each edge's ends: every node is its own root at first
    while e.shape[0]:
        apart = r[:, 0] != r[:, 1]
        # no filtering pass when every edge still joins two trees (the first round, with
        # no self-loops): keeping all rows is the same; rows by a mask with np.compress,
        # several times faster than boolean indexing of rows
        if not apart.all():
            if not apart.any():
                break
            e, r = np.compress(apart, e, axis=0), np.compress(apart, r, axis=0)
        ru, rv = r[:, 0], r[:, 1]
        np.minimum.at(root, np.maximum(ru, rv), np.minimum(ru, rv))
        while True:  # point every node at its root (pointer jumping)
            up = root[root]
            if np.array_equal(up, root):
                break
            root = up
        r = root[e]
    # the roots are the components' lowest nodes: numbering them in node order numbers
    # the components as csgraph does, without a sort
    return dense_labels(root)


class ApartSets:
    """Disjoint sets of ``n`` nodes joined a pair at a time, where some pairs must never
    end in one set: the greedy joins of colors.py (pieces of one colour) and learned.py
    (segments the model finds one object), where two objects a rule told apart must not
    be joined, directly or through a chain of joins. A union-find whose roots carry the
    nodes their set must stay apart from (``apart``: pairs of nodes)."""

    def __init__(self, n: int, apart: Iterable[tuple[int, int]]) -> None:
        self._parent = list(range(n))
        self._enemies: dict[int, set[int]] = {}
        for a, b in apart:
            self._enemies.setdefault(a, set()).add(b)
            self._enemies.setdefault(b, set()).add(a)
        self.joined: list[tuple[int, int]] = []  # (kept root, joined root), in join order

    def root(self, i: int) -> int:
        parent = self._parent
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    def kept_apart(self, r: int) -> bool:
        """Whether the set of root ``r`` must stay apart from some other set."""
        return bool(self._enemies.get(r))

    def join_roots(self, ra: int, rb: int) -> None:
        """Join the set of root ``rb`` into that of root ``ra`` (no check: see `join`)."""
        self._parent[rb] = ra
        mine = self._enemies.pop(rb, set())
        for x in mine:
            self._enemies[x].discard(rb)
            self._enemies[x].add(ra)
        self._enemies.setdefault(ra, set()).update(mine)
        self.joined.append((ra, rb))

    def join(self, a: int, b: int) -> bool:
        """Join the sets of ``a`` and ``b`` unless they are one already or must stay
        apart; whether they were joined."""
        ra, rb = self.root(a), self.root(b)
        if ra == rb or rb in self._enemies.get(ra, ()):
            return False
        self.join_roots(ra, rb)
        return True
