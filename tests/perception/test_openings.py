"""Rims of open containers and seen table edges (clearcli/perception/openings.py), on
points made by hand with known sizes."""

from __future__ import annotations

import numpy as np

from clearcli.perception.openings import rim_of, seen_edges
from clearcli.perception.types import TablePlane

# the table is z = 0 with its normal +z: height = z
TABLE = TablePlane(np.array([0.0, 0.0, 1.0]), 0.0)


def _cup(radius: float, wall: float, height: float, n: int = 4000, seed: int = 0, lid: bool = False) -> np.ndarray:
    """Points of a cup seen from above-ish: its rim's upper face (an annulus), its outer
    wall and its inner wall down to a floor 5 mm up; with ``lid`` a disc at the top."""
    rng = np.random.default_rng(seed)
    a = rng.uniform(0, 2 * np.pi, n)
    part = rng.integers(0, 3, n)
    r = np.where(part == 0, rng.uniform(radius - wall, radius, n), np.where(part == 1, radius, radius - wall))
    z = np.where(part == 0, height, rng.uniform(0.005, height, n))
    pts = np.column_stack([r * np.cos(a), r * np.sin(a), z])
    if lid:
        rr = radius * np.sqrt(rng.uniform(0, 1, n))
        pts = np.vstack([pts, np.column_stack([rr * np.cos(a), rr * np.sin(a), np.full(n, height)])])
    return pts + np.array([0.3, -0.1, 0.0])


def test_a_cups_rim_wall_and_depth_by_construction() -> None:
    op = rim_of(_cup(0.05, 0.005, 0.09), TABLE)
    assert op.rim is not None, op.why
    rim = op.rim
    # the circle through the wall's middle, at the rim's height; the wall 5 mm (the
    # 10th-90th percentile spread of a uniform annulus 5 mm wide is 4 mm, and the outer
    # and inner walls' top points widen it back)
    assert np.allclose(rim.center[:2], [0.3, -0.1], atol=0.002) and abs(rim.center[2] - 0.09) < 0.003
    assert abs(rim.radius_m - 0.0475) < 0.002
    assert abs(rim.wall_m - 0.005) < 0.0015
    assert abs(rim.height_m - 0.09) < 0.003 and rim.inside_depth_m > 0.07
    assert rim.arc_deg == 360.0


def test_a_lid_a_box_and_a_half_seen_rim_are_no_rims() -> None:
    assert "closed" in rim_of(_cup(0.05, 0.005, 0.09, lid=True), TABLE).why
    rng = np.random.default_rng(1)
    box = rng.uniform([0, 0, 0], [0.08, 0.06, 0.05], size=(3000, 3))
    box[:1500, 2] = 0.05  # its top face
    assert rim_of(box, TABLE).rim is None
    cup = _cup(0.05, 0.005, 0.09)
    half = cup[np.arctan2(cup[:, 1] + 0.1, cup[:, 0] - 0.3) > 0.4]  # about 160 deg of it
    op = rim_of(half, TABLE)
    assert op.rim is None and "hidden" in op.why


def test_no_edge_is_seen_without_an_image() -> None:
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    edges = seen_edges(np.zeros((10, 3)), None, TABLE, square)
    assert len(edges) == 4 and not any(e.seen for e in edges)
    assert all("unorganized" in e.why for e in edges)


def test_quantile_is_numpys_linear_quantile_to_the_bit() -> None:
    from clearcli.perception.openings import _quantile

    gen = np.random.default_rng(2)
    for trial in range(300):
        values = gen.normal(size=int(gen.integers(1, 3000))) * 10 ** gen.uniform(-4, 1)
        if trial % 3 == 0:
            values = np.round(values, 3)  # ties
        for q in (0.0, 0.1, 0.5, 0.9, 0.98, 1.0):
            assert _quantile(values, q) == float(np.quantile(values, q))
