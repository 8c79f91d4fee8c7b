"""Tests of clearcli/perception/rings.py: the rim circle of a container, by hand."""

from __future__ import annotations

import numpy as np
import pytest


def _arc(radius: float, deg0: float, deg1: float, n: int, centre=(0.3, -0.1)) -> np.ndarray:
    a = np.radians(np.linspace(deg0, deg1, n))
    return np.column_stack([centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)])


def test_a_handle_in_the_rim_band_is_left_out_of_the_circle() -> None:
    from clearcli.perception.rings import fit_circle, fit_rim

    rim = _arc(0.04, 0, 330, 100)
    # a handle: 15 points 1.5-3 cm outside the rim over 30 degrees
    a = np.radians(np.linspace(-20, 10, 15))
    r = np.linspace(0.055, 0.07, 15)
    handle = np.column_stack([0.3 + r * np.cos(a), -0.1 + r * np.sin(a)])
    band = np.vstack([rim, handle])
    centre, radius = fit_circle(band)
    resid = np.linalg.norm(band - centre, axis=1) - radius
    assert np.sqrt(np.mean(resid**2)) > 0.1 * radius  # the plain fit fails the 0.1 test
    fitted = fit_rim(band, 0.15, 0.1, max_off_share=0.2)
    assert fitted is not None
    centre, radius, inlier = fitted
    assert radius == pytest.approx(0.04, abs=1e-6) and centre == pytest.approx([0.3, -0.1], abs=1e-6)
    assert inlier[:100].all() and not inlier[100:].any()
    # 15 of 115 is 13 % off the circle: not allowed when none may be
    assert fit_rim(band, 0.15, 0.1, max_off_share=0.0) is None


def test_a_filled_top_is_no_rim() -> None:
    from clearcli.perception.rings import fit_rim

    rng = np.random.default_rng(0)
    r = 0.04 * np.sqrt(rng.uniform(size=400))  # a disc sampled evenly: a can's top
    a = rng.uniform(0, 2 * np.pi, 400)
    assert fit_rim(np.column_stack([r * np.cos(a), r * np.sin(a)]), 0.15, 0.1, max_off_share=0.2) is None


def _kasa_fit(xy: np.ndarray) -> tuple[np.ndarray, float]:
    """Kasa's fit as fit_circle wrote it before its rows were built once a refit loop:
    the oracle of the same numbers."""
    a = np.empty((xy.shape[0], 3))
    np.multiply(xy, 2.0, out=a[:, :2])
    a[:, 2] = 1.0
    sol, *_ = np.linalg.lstsq(a, (xy**2).sum(axis=1), rcond=None)
    centre = sol[:2]
    return centre, float(np.sqrt(max(float(sol[2] + centre @ centre), 0.0)))


def test_a_fit_to_a_subset_of_the_rows_is_the_fit_to_the_subset() -> None:
    """`fit_circle_rows` of a mask's rows of `kasa_rows` (what fit_rim's and
    vessels.find_rim's refits solve) is the very circle of a fit to the masked points:
    a circle by hand, then random bands and masks against the direct fit."""
    from clearcli.perception.rings import fit_circle, fit_circle_rows, kasa_rows

    # 40 points of a 4 cm circle round (0.3, -0.1), and 10 far off it the mask drops
    band = np.vstack([_arc(0.04, 0, 300, 40), [[1.0, 1.0]] * 10])
    keep = np.arange(50) < 40
    rows, sq = kasa_rows(band)
    assert rows[:, 2].tolist() == [1.0] * 50 and rows[0, :2] == pytest.approx(2 * band[0])
    centre, radius = fit_circle_rows(np.compress(keep, rows, axis=0), np.compress(keep, sq))
    assert centre == pytest.approx([0.3, -0.1], abs=1e-9) and radius == pytest.approx(0.04, abs=1e-9)
    rng = np.random.default_rng(3)
    for _ in range(200):
        n = int(rng.integers(3, 400))
        xy = rng.normal(0.0, 0.2, (n, 2)) + rng.normal(0.0, 1.0, 2)
        mask = rng.uniform(size=n) < rng.uniform(0.3, 1.0)
        mask[:3] = True
        rows, sq = kasa_rows(xy)
        got = fit_circle_rows(np.compress(mask, rows, axis=0), np.compress(mask, sq))
        want = _kasa_fit(xy[mask])
        assert np.array_equal(got[0], want[0]) and got[1] == want[1]
        assert np.array_equal(fit_circle(xy)[0], _kasa_fit(xy)[0])
