"""Gripper, push and predicate settings (sections [gripper], [push], [predicates])."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class GripperSettings:
    """The IRI parallel gripper (parameters.md). Frame: closing point at the origin,
    approach along +z, closing direction along x."""

    opening_width_m: float = 0.07
    closing_width_m: float = 0.03
    finger_width_m: float = 0.03
    finger_thickness_m: float = 0.01
    gripper_height_m: float = 0.10
    closing_region_height_m: float = 0.045
    finger_depth_m: float = 0.06
    base_width_m: float = 0.11
    base_depth_m: float = 0.06
    base_height_m: float = 0.055


@dataclass(frozen=True)
class PushSettings:
    pushing_step: float = 1.0
    push_length_limit_m: float = 0.6
    path_resolution_m: float = 0.03
    gripper_behind_m: float = 0.03
    fingertips_above_table_m: float = 0.01
    approach_m: float = 0.10


@dataclass(frozen=True)
class PredicateSettings:
    on_threshold_points: int = 20
    clearance_cost: bool = False  # original code's distance-based push cost
