"""Tests of clearcli/perception/filters.py."""

from __future__ import annotations

import numpy as np


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
