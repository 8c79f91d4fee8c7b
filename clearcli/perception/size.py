"""The sizes segmentation counts in, worked out once per frame: `SegmentSize`.

The settings give lengths and areas in metres (settings/segment.py), so that their
meaning does not change with the sensor. The stages count voxels and supervoxels. On a
cloud sparser than the voxel grid (an unorganized cloud thinned on a coarser grid) the
voxel, the supervoxel seed and the normal radius grow with the point spacing
(`SegmentSize.of`), and every count below follows from the grown voxel. Every stage
reads its sizes here, from the one value `segment()` builds; no stage reads
``voxel_m``, ``seed_m`` or ``normal_radius_m`` from the settings itself.

Some stages have always compared a count with the smallest object's area in voxels
rounded down (``min_object_voxels``), others with it unrounded
(``min_object_voxels_unrounded``: a count passes from the next whole number up), and
the final size filter and LCCP's "small object standing on the table" compare areas
(`holds_object_area`). On the default 5 mm voxel all three are 40 voxels; on a grown
voxel or another ``voxel_m`` they differ by one voxel, so each stage keeps the one it
had (outputs unchanged).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clearcli.settings.segment import SegmentSettings

# a voxel spans at least this many point spacings, or voxels have no neighbours
_SPACINGS_PER_VOXEL = 1.5
# points whose spacing is probed (a sample judges the whole cloud)
_PROBE = 2000


@dataclass(frozen=True)
class SegmentSize:
    """Sizes of one frame's segmentation, in metres and in voxels (module docstring)."""

    voxel_m: float  # the voxel grid's cell (grown on a sparse cloud)
    seed_m: float  # the supervoxel seed spacing (grows with the voxel)
    normal_radius_m: float  # the neighbourhood of a voxel's normal (grows with the voxel)
    voxel_area_m2: float  # voxel_m ** 2: the surface one voxel stands for
    seed_voxels: float  # (seed_m / voxel_m) ** 2: voxels in a seed cell's square
    min_object_area_m2: float  # the smallest object's visible area (the setting)
    # the smallest object in voxels, rounded down (at least 1): what the occlusion
    # merge, the colour splits, the rings and the vessels leave alone below
    min_object_voxels: int
    # ... unrounded: the stacks' lower level and the steps' tops must reach it (a count
    # passes from the next whole number up); rounding it would change their outputs
    # where it is not whole
    min_object_voxels_unrounded: float
    min_segment_supervoxels: int  # LCCP's smallest segment in supervoxels (the setting)
    min_segment_voxels: int  # ... and in voxels: that many seed cells' squares
    # a planar cut's or a step's side holds cut_min_side_m2 and LCCP's smallest segment
    min_side_voxels: float
    # the stacks' sides hold cut_min_side_m2 only, without LCCP's smallest segment (as
    # they always have; the larger minimum would change their outputs)
    min_side_voxels_stacks: float
    min_edge_piece_voxels: int  # a depth edge's side (depth_edge_min_piece_m2), at least 1
    min_seed_voxels: int  # a seed cell holds a tenth of its square to seed a supervoxel

    @classmethod
    def of(cls, settings: SegmentSettings, points: np.ndarray | None = None) -> SegmentSize:
        """The sizes for ``settings``; with ``points`` (an unorganized cloud's points
        above the table), the voxel grown to 1.5 point spacings where the cloud is
        sparser than the grid, and the seed and the normal radius with it."""
        voxel, seed, radius = settings.voxel_m, settings.seed_m, settings.normal_radius_m
        grown = _grown_voxel(points, settings.voxel_m) if points is not None else None
        if grown is not None:
            scale = grown / settings.voxel_m
            voxel, seed, radius = grown, settings.seed_m * scale, settings.normal_radius_m * scale
        area = voxel**2
        seed_voxels = (seed / voxel) ** 2
        min_segment_voxels = int(settings.min_segment_supervoxels * seed_voxels)
        return cls(
            voxel_m=voxel,
            seed_m=seed,
            normal_radius_m=radius,
            voxel_area_m2=area,
            seed_voxels=seed_voxels,
            min_object_area_m2=settings.min_object_area_m2,
            min_object_voxels=max(1, int(settings.min_object_area_m2 / area)),
            min_object_voxels_unrounded=settings.min_object_area_m2 / area,
            min_segment_supervoxels=settings.min_segment_supervoxels,
            min_segment_voxels=min_segment_voxels,
            min_side_voxels=max(settings.cut_min_side_m2 / area, min_segment_voxels),
            min_side_voxels_stacks=settings.cut_min_side_m2 / area,
            min_edge_piece_voxels=max(1, int(settings.depth_edge_min_piece_m2 / area)),
            min_seed_voxels=max(1, int(0.1 * seed_voxels)),
        )

    def holds_object_area(self, n_voxels: np.ndarray) -> np.ndarray:
        """Do segments of ``n_voxels`` voxels show at least the smallest object's area?
        (The area compared, not the count: the final size filter and LCCP's small
        standing objects always have.)"""
        return np.asarray(n_voxels) * self.voxel_area_m2 >= self.min_object_area_m2


def _grown_voxel(points: np.ndarray, voxel_m: float) -> float | None:
    """The voxel for a cloud sparser than ``voxel_m``: 1.5 times its median point
    spacing, or None when the grid is fine as it is."""
    from scipy.spatial import cKDTree

    if points.shape[0] < 10:
        return None
    probe = points[:: max(1, points.shape[0] // _PROBE)]
    spacing = float(np.median(cKDTree(points).query(probe, k=2)[0][:, 1]))
    voxel = max(voxel_m, _SPACINGS_PER_VOXEL * spacing)
    return voxel if voxel > voxel_m else None
