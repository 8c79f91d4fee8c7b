"""A `RefineContext` over voxels and supervoxels laid out by hand (tests of the
refinement stages)."""

from __future__ import annotations

import numpy as np

from clearcli.io.frames import Frame
from clearcli.perception.refine import RefineContext
from clearcli.perception.size import SegmentSize
from clearcli.perception.supervoxels import Supervoxels, VoxelCloud
from clearcli.perception.types import TablePlane
from clearcli.settings.segment import SegmentSettings


def hand_context(
    voxels: np.ndarray,
    sv: Supervoxels,
    settings: SegmentSettings,
    voxel_edges: np.ndarray | None = None,
    normal: tuple[float, float, float] = (0.0, 0.0, 1.0),
    offset: float = 0.0,
    rgb: np.ndarray | None = None,
    color_used: bool = False,
) -> RefineContext:
    """Each voxel one point of an unorganized frame, coloured ``rgb`` if given; the table
    the plane ``normal . p + offset = 0`` (by default z = 0, z up); the sizes those of
    ``settings``."""
    n = voxels.shape[0]
    edges = np.zeros((0, 2), dtype=np.int64) if voxel_edges is None else np.asarray(voxel_edges, dtype=np.int64)
    vox = VoxelCloud(
        point_voxel=np.arange(n),
        centroids=voxels,
        counts=np.ones(n, dtype=np.int64),
        keys=np.zeros((n, 3), dtype=np.int64),
        colors=None,
        edges=edges,
    )
    colors = None if rgb is None else np.asarray(rgb, dtype=np.uint8)
    frame = Frame(points=voxels.astype(np.float32), colors=colors, source="by hand")
    plane = TablePlane(normal=np.asarray(normal, dtype=np.float64), offset=offset)
    return RefineContext(frame, False, vox, sv, plane, settings, SegmentSize.of(settings), np.arange(n), color_used)
