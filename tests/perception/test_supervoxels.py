"""Tests of clearcli/perception/supervoxels.py."""

from __future__ import annotations

import numpy as np


def test_voxel_adjacency_is_the_26_neighbourhood() -> None:
    from clearcli.perception.supervoxels import voxelize

    g = np.stack(np.meshgrid(*[np.arange(3)] * 3, indexing="ij"), -1).reshape(-1, 3) * 0.01 + 0.005
    vox = voxelize(g, 0.01)
    assert vox.n_voxels == 27
    # pairs of a 3x3x3 block at Chebyshev distance 1: (27*26 - non-adjacent) / 2
    d = np.abs(vox.keys[:, None, :] - vox.keys[None, :, :]).max(-1)
    assert vox.edges.shape[0] == int((d == 1).sum()) // 2
