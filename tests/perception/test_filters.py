"""Tests of clearcli/perception/filters.py."""

from __future__ import annotations

import warnings

import numpy as np
import pytest


# ------------------------------------------------------------------ 1. outliers
def test_depth_radius_keeps_far_surfaces_and_drops_flying_pixels() -> None:
    from clearcli.perception.filters import depth_radius_mask, statistical_mask

    # an organized Kinect view (f = 525 px) of a table 0.6 m below the camera, looking
    # down 37 degrees: the table reaches from 0.6 m to several metres; one pixel moved
    # 20 cm towards the camera (a flying pixel)
    h, w, f = 480, 640, 525.0
    v, u = np.mgrid[0:h, 0:w]
    rays = np.stack([(u - 319.5) / f, (v - 239.5) / f, np.ones((h, w))], axis=-1).reshape(-1, 3)
    n = np.array([0.0, -np.cos(np.radians(37)), -np.sin(np.radians(37))])
    t = -0.6 / (rays @ n)
    pts = np.where((t > 0)[:, None], rays * t[:, None], np.nan).astype(np.float32)
    pts[np.linalg.norm(pts, axis=1) > 4.0] = np.nan
    fly = 400 * w + 320
    pts[fly] *= 0.8
    pts[fly + 1] = np.nan
    keep = depth_radius_mask(pts, (h, w), 0.01, 2)
    finite = np.isfinite(pts).all(axis=1)
    assert not keep[fly] and not keep[fly + 1]
    assert keep.sum() >= finite.sum() - 3  # every surface point stays, near and far
    assert np.linalg.norm(pts[keep], axis=1).max() > 3.0
    # the same without the pixel grid (KD-tree path)
    sub = np.zeros_like(finite)
    sub[::7] = True
    sub[fly] = True
    keep_u = depth_radius_mask(np.where(sub[:, None], pts, np.nan), None, 0.02, 2)
    assert not keep_u[fly] and keep_u.sum() >= (finite & sub).sum() - 3
    # the original statistical filter (fixed k) loses the far, sparse points
    stat = statistical_mask(pts, 10, 1.0)
    far = finite & (np.linalg.norm(pts, axis=1) > 2.5)
    assert stat[far].mean() < 0.5 < keep[far].mean()


def _counts_by_einsum(points: np.ndarray, shape: tuple[int, int], radius_at_1m_m: float) -> np.ndarray:
    """The neighbour counts as einsum on (h, w, 3) float32 rows gave them."""
    h, w = shape
    grid = points.reshape(h, w, 3).astype(np.float32, copy=False)
    rng = np.sqrt(np.einsum("ijk,ijk->ij", grid, grid))
    counts = np.zeros((h, w), dtype=np.int16)
    k2 = np.float32((radius_at_1m_m * 0.5) ** 2)
    for dy, dx in ((0, 1), (1, -1), (1, 0), (1, 1)):
        ya, yb = slice(0, h - dy), slice(dy, h)
        xa, xb = slice(max(0, -dx), w - max(0, dx)), slice(max(0, dx), w - max(0, -dx))
        diff = grid[ya, xa] - grid[yb, xb]
        rr = rng[ya, xa] + rng[yb, xb]
        hit = np.einsum("ijk,ijk->ij", diff, diff) < k2 * rr * rr
        counts[ya, xa] += hit
        counts[yb, xb] += hit
    return counts.reshape(-1)


def test_neighbour_counts_bit_for_bit_as_einsum_gave_them() -> None:
    from clearcli.perception.filters import _organized_neighbor_counts

    gen = np.random.default_rng(3)
    h, w = 40, 50
    # a slanted surface with noise near the radius, holes, and float64 input too
    v, u = np.mgrid[0:h, 0:w]
    z = 0.8 + 0.004 * u + gen.normal(0, 0.003, size=(h, w))
    pts = np.stack([(u - w / 2) * z / 500, (v - h / 2) * z / 500, z], axis=-1).reshape(-1, 3)
    pts[gen.random(h * w) < 0.1] = np.nan
    for p in (pts.astype(np.float32), pts):
        for radius in (0.005, 0.01, 0.02):
            want = _counts_by_einsum(p, (h, w), radius)
            got = _organized_neighbor_counts(p, (h, w), radius)
            assert got.dtype == want.dtype and np.array_equal(got, want)
            assert 0 < got.mean() < 8


def test_finite_mask_by_columns() -> None:
    from clearcli.perception.filters import finite_mask

    p = np.ones((6, 3))
    p[1, 0], p[2, 1], p[3, 2], p[4] = np.nan, np.inf, -np.inf, np.nan
    assert finite_mask(p).tolist() == [True, False, False, False, False, True]
    assert finite_mask(p.astype(np.float32)).tolist() == np.isfinite(p).all(axis=1).tolist()


def test_neighbour_counts_the_same_whatever_the_blocks_of_rows(monkeypatch: pytest.MonkeyPatch) -> None:
    from clearcli.perception import filters

    gen = np.random.default_rng(5)
    h, w = 37, 29
    v, u = np.mgrid[0:h, 0:w]
    z = 0.9 - 0.003 * v + gen.normal(0, 0.003, size=(h, w))
    pts = np.stack([(u - w / 2) * z / 500, (v - h / 2) * z / 500, z], axis=-1).reshape(-1, 3).astype(np.float32)
    pts[gen.random(h * w) < 0.1] = np.nan
    want = _counts_by_einsum(pts, (h, w), 0.01)
    assert 0 < want.mean() < 8
    # one row a block, a few rows (the last block shorter), one row short of all, all
    for pixels in (1, w, 3 * w + 5, (h - 1) * w, h * w, 10**7):
        monkeypatch.setattr(filters, "_BLOCK_PIXELS", pixels)
        got = filters._organized_neighbor_counts(pts, (h, w), 0.01)
        assert np.array_equal(got, want), pixels


def test_points_beyond_float32_squares_have_no_neighbour_and_no_warning() -> None:
    # absurd intrinsics (a principal point at 1e30 pixels) put points ~1e28 m out: their
    # squares overflow float32; they keep no neighbour and NumPy prints nothing
    from clearcli.perception.filters import depth_radius_mask

    grid = np.zeros((4, 5, 3), np.float32)
    grid[..., 0] = np.arange(5, dtype=np.float32) * 0.001
    grid[..., 1] = np.arange(4, dtype=np.float32)[:, None] * 0.001
    grid[..., 2] = 1.0
    grid[0, :, 0] = np.float32(1e28) * np.arange(1, 6, dtype=np.float32)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        kept = depth_radius_mask(grid.reshape(-1, 3), (4, 5), 0.01, 2)
    assert not kept[:5].any() and kept[5:].all()


def test_neighbour_counts_on_the_box_of_finite_pixels_as_on_the_whole_image() -> None:
    """The counts run only over the box of the pixels with a finite depth (rows and
    columns without one have no neighbour): NaN borders of every width, a box one pixel
    wide or tall, and no finite pixel at all give what the whole image gives."""
    from clearcli.perception.filters import _organized_neighbor_counts

    gen = np.random.default_rng(11)
    h, w = 31, 23
    v, u = np.mgrid[0:h, 0:w]
    z = 0.85 + 0.002 * u + gen.normal(0, 0.003, size=(h, w))
    base = np.stack([(u - w / 2) * z / 500, (v - h / 2) * z / 500, z], axis=-1).astype(np.float32)
    boxes = [
        (slice(5, h - 3), slice(4, w)),  # NaN rows above and below, columns on the left
        (slice(0, h), slice(7, 8)),  # one column
        (slice(12, 13), slice(0, w)),  # one row
        (slice(9, 11), slice(w - 2, w)),  # a 2 x 2 corner piece
        (slice(0, 0), slice(0, 0)),  # nothing finite
    ]
    for rows, cols in boxes:
        grid = np.full_like(base, np.nan)
        grid[rows, cols] = base[rows, cols]
        pts = grid.reshape(-1, 3)
        want = _counts_by_einsum(pts, (h, w), 0.01)
        got = _organized_neighbor_counts(pts, (h, w), 0.01)
        assert got.dtype == want.dtype and np.array_equal(got, want), (rows, cols)
    # a box whose every pixel is finite but one column's: its neighbours still count
    grid = base.copy()
    grid[:, 3] = np.nan
    assert np.array_equal(
        _organized_neighbor_counts(grid.reshape(-1, 3), (h, w), 0.01),
        _counts_by_einsum(grid.reshape(-1, 3), (h, w), 0.01),
    )
