"""Tests of clearcli/perception/lccp.py."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.segment import S


# ------------------------------------------------------------------ 3. supervoxels + LCCP
def _fold(sign: float) -> np.ndarray:
    """A 20 x 20 cm sheet folded along y at x = 0, seen from the origin: sign +1 a ridge
    towards the camera (convex), -1 a valley (concave). 1.5 mm sampling."""
    x, y = np.meshgrid(np.arange(-0.1, 0.1, 0.0015), np.arange(-0.1, 0.1, 0.0015))
    z = 0.8 + sign * 0.8 * np.abs(x)
    return np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)


@pytest.mark.parametrize("sign, n_segments", [(1.0, 1), (-1.0, 2)])
def test_lccp_joins_convex_and_cuts_concave(sign: float, n_segments: int) -> None:
    from clearcli.perception.lccp import lccp_segments
    from clearcli.perception.supervoxels import compute_supervoxels, voxelize

    vox = voxelize(_fold(sign), S.voxel_m)
    # the 26-neighbourhood on a regular grid: interior voxels have neighbours
    assert vox.edges.shape[0] > vox.n_voxels
    sv = compute_supervoxels(vox, np.zeros(3), S)
    # about one supervoxel per seed cell of the (tilted) sheet
    assert 50 <= sv.centroids.shape[0] <= 300
    assert np.all(np.einsum("ij,ij->i", sv.normals, -sv.centroids) > 0)  # facing the camera
    seg = lccp_segments(sv, S)
    assert int(seg.max()) + 1 == n_segments
    if n_segments == 2:  # the cut is the fold
        xs = sv.centroids[:, 0]
        far = np.abs(xs) > 0.02
        assert len(set(zip((xs[far] > 0).tolist(), seg[far].tolist()))) == 2
