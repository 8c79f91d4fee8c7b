"""Helpers that several test modules share (from the tests of tasks)."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def truth_centroids(pcd: Path) -> dict[int, np.ndarray]:
    """Centroid (camera frame) of each true object (label >= 10) of a fixture."""
    from pypcd4 import PointCloud

    cloud = PointCloud.from_path(pcd)
    labels = cloud.numpy(("label",)).ravel().astype(np.int64)
    xyz = cloud.numpy(("x", "y", "z")).astype(np.float64)
    ok = np.isfinite(xyz).all(axis=1)
    return {int(k): xyz[ok & (labels == k)].mean(axis=0) for k in np.unique(labels[ok]) if k >= 10}
