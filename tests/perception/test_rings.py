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
