"""Segmentation settings (section [segment] of the settings file).

Starting values from the original method (parameters.md, deployed column); sizes in
metres so that the meaning does not change with the sensor's density.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class SegmentSettings:
    # statistical outlier removal
    outlier_k: int = 10
    outlier_std: float = 1.0
    # table plane (RANSAC)
    plane_distance_m: float = 0.01
    # polygonal prism: heights above the table kept as object points
    prism_min_height_m: float = 0.01
    prism_max_height_m: float = 2.0
    # supervoxels (VCCS)
    voxel_m: float = 0.005
    seed_m: float = 0.02
    color_importance: float = 0.0
    spatial_importance: float = 1.0
    normal_importance: float = 4.0
    # LCCP
    concavity_tolerance_deg: float = 15.0
    smoothness_threshold: float = 0.1
    sanity_criterion: bool = True
    min_segment_supervoxels: int = 5
    # final filter
    min_object_points: int = 200
