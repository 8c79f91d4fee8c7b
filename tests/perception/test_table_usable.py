"""Tests of ransac_plane's ``usable`` mask (clearcli/perception/table.py, issue 37)."""

from __future__ import annotations

import numpy as np


def _two_planes(seed: int) -> np.ndarray:
    """A 1 m x 1 m plane z = 0 (600 points) and a smaller plane z = 0.3 (400 points),
    both with 1 mm noise, then 20 far scattered points."""
    rng = np.random.default_rng(seed)
    a = np.c_[rng.uniform(0, 1, (600, 2)), rng.normal(0, 0.001, 600)]
    b = np.c_[rng.uniform(0, 0.5, (400, 2)), 0.3 + rng.normal(0, 0.001, 400)]
    c = rng.uniform(2, 3, (20, 3))
    return np.vstack([a, b, c])


def test_all_usable_draws_as_without_a_mask() -> None:
    from clearcli.perception.table import ransac_plane

    pts = _two_planes(1)
    r1, r2 = np.random.default_rng(5), np.random.default_rng(5)
    n1, d1 = ransac_plane(pts, 0.005, 500, r1)
    n2, d2 = ransac_plane(pts, 0.005, 500, r2, np.ones(pts.shape[0], dtype=bool))
    assert np.array_equal(n1, n2) and d1 == d2
    # the same number of draws consumed: the next draw is the same
    assert r1.integers(0, 1 << 30) == r2.integers(0, 1 << 30)


def _equal_planes() -> np.ndarray:
    """One far point first, then 4 parallel planes z = 0.1 k of 150 points each (1 mm
    noise): which plane wins depends on the draws alone."""
    rng = np.random.default_rng(7)
    planes = [np.c_[rng.uniform(0, 1, (150, 2)), 0.1 * k + rng.normal(0, 0.001, 150)] for k in range(4)]
    return np.vstack([[[5.0, 5.0, 5.0]], *planes])


def test_the_plane_on_the_remaining_points_ignores_a_far_point_removed() -> None:
    """Removing the far point from the usable ones (as a rounding-sized change of an earlier
    plane does) changes no draw but those that hit it, so the plane found is bit-identical
    for every seed; drawing over the usable subset shifted every draw after it (issue 37)."""
    from clearcli.perception.table import ransac_plane

    pts = _equal_planes()
    usable = np.ones(pts.shape[0], dtype=bool)
    usable[1:151] = False  # the plane z = 0 taken by an earlier plane
    fewer = usable.copy()
    fewer[0] = False
    for seed in range(12):
        n1, d1 = ransac_plane(pts, 0.005, 100, np.random.default_rng(seed), usable)
        n2, d2 = ransac_plane(pts, 0.005, 100, np.random.default_rng(seed), fewer)
        assert abs(abs(n1[2]) - 1) < 1e-3 and abs(d1) > 0.05  # a usable plane
        assert np.array_equal(n1, n2) and d1 == d2, seed


def test_unusable_points_are_never_in_the_plane() -> None:
    """With the larger plane unusable, the plane found is the smaller one."""
    from clearcli.perception.table import ransac_plane

    pts = _two_planes(3)
    usable = np.abs(pts[:, 2]) > 0.005
    n, d = ransac_plane(pts, 0.005, 500, np.random.default_rng(0), usable)
    assert abs(abs(n[2]) - 1) < 1e-3 and abs(abs(d) - 0.3) < 2e-3
