"""Gripper, push and predicate settings (sections [gripper], [push], [predicates])."""

from __future__ import annotations

from dataclasses import dataclass

from clearcli.settings.fields import Section, param


@dataclass(frozen=True)
class GripperSettings(Section):
    """The IRI parallel gripper (parameters.md). Frame: closing point at the origin,
    approach along +z, closing direction along x.

    The collision model is two fingers and a base box (see `clearcli.geometry.gripper`):
    the fingertips are ``closing_region_height_m / 2`` past the closing point, the fingers
    ``finger_depth_m`` long, the base box behind them. ``gripper_height_m`` is the quoted
    base-to-tip figure and is not used by the collision model.
    Another gripper is a TOML file with a [gripper] table (``--settings FILE``).
    """

    NAME = "gripper"

    opening_width_m: float = param(0.07, gt=0, le=0.5)
    closing_width_m: float = param(0.03, ge=0, le=0.5)
    # The gap between the fingers fully closed (m): what a rim grasp can close on (a
    # container's wall thinner than this slips). The IRI gripper's is its closing width
    # (parameters.md: 0.03 m, fingers apart when closed); the Franka Hand and the
    # Robotiq 2F-85 close fully (0), though their pinch from above keeps 1 cm. Taken as
    # at most closing_width_m.
    closed_gap_m: float = param(0.03, ge=0, le=0.5)
    finger_width_m: float = param(0.03, gt=0, le=0.2)
    finger_thickness_m: float = param(0.01, gt=0, le=0.1)
    gripper_height_m: float = param(0.10, gt=0, le=1)
    closing_region_height_m: float = param(0.045, gt=0, le=0.3)
    finger_depth_m: float = param(0.06, gt=0, le=0.5)
    base_width_m: float = param(0.11, gt=0, le=0.5)
    base_depth_m: float = param(0.06, gt=0, le=0.5)
    base_height_m: float = param(0.055, gt=0, le=0.5)

    def cross_checks(self) -> None:
        # (equal: the closed finger pair, which the push model uses)
        if self.closing_width_m > self.opening_width_m:
            self.fail("closing_width_m", f"must be at most opening_width_m ({self.opening_width_m:g})")


@dataclass(frozen=True)
class PushSettings(Section):
    NAME = "push"

    pushing_step: float = param(1.0, gt=0, le=10)
    push_length_limit_m: float = param(0.6, gt=0, le=2)
    path_resolution_m: float = param(0.03, ge=0.005, le=0.5)
    gripper_behind_m: float = param(0.03, ge=0, le=0.2)
    fingertips_above_table_m: float = param(0.01, ge=0, le=0.2)
    approach_m: float = param(0.10, ge=0, le=0.5)
    # push alternatives with the contact off the middle of the rear face, this far (m)
    # from its ends: the IK check tries them when the centred push has no arm motion.
    # Off by default: on the 40 simulated sessions of benchmarks/replay.py they changed
    # no outcome, and they cost the predicates stage 14 ms on mOSD test57 (42 -> 56 ms).
    lateral_shift: bool = param(False)
    contact_edge_margin_m: float = param(0.005, ge=0, le=0.1)
    # Push alternatives with the fingertips this high above the table (m), tried by the
    # IK check when the standard push's arm hits a neighbour: the wrist capsule's lowest
    # point is ~0.08 m above the fingertips, so beside a box 0.10-0.15 m tall only a
    # raised contact clears it (most deadlocks in simulated rows of boxes: the arm
    # sliding a box along a tall neighbour). Kept where the contact stays on the
    # object's lower half and the object does not tip (``table_friction``). () = off.
    raised_fingertips_m: tuple[float, ...] = param((0.03, 0.05, 0.07), ge=0, le=0.5, max_items=10)
    # friction coefficient of objects on the table (cardboard, plastic on wood ~0.3-0.5),
    # for the tipping rule of raised pushes
    table_friction: float = param(0.4, ge=0, le=5)


@dataclass(frozen=True)
class PredicateSettings(Section):
    NAME = "predicates"

    # th0 = th1 of thesis eq. 4.3; the deployed launch file used 20 (the thesis 100, for
    # denser clouds than the mOSD crops)
    on_threshold_points: int = param(20, ge=0, le=100000)
    # projected points within this distance of the other hull's border are not counted
    # as inside it: coinciding edges of touching objects must not look like "on"
    on_margin_m: float = param(0.005, ge=0, le=0.1)
    # beyond the thesis (see clearcli.predicates.relations.on_pairs): an object whose lowest
    # points are less than this above the table stands on the table (Kinect noise ~5 mm)
    on_min_lift_m: float = param(0.01, ge=0, le=0.2)
    # the lower object's points under the upper one's hull must be this much lower
    on_height_gap_m: float = param(0.01, ge=0, le=0.2)
    # an object stands on the highest objects under it, those within this band of it
    on_support_band_m: float = param(0.02, ge=0, le=0.5)
    clearance_cost: bool = param(False)  # original code's distance-based push cost
    # parameters.md: cost 1 at d >= 0.05 m, else ceil(exp(100 (0.05 - d)))
    clearance_cost_distance_m: float = param(0.05, ge=0, le=1)
    clearance_cost_gain_per_m: float = param(100.0, ge=0, le=1000)
    # the grasp approach follows the third principal axis of the top surface only while it
    # is within this angle of the table's downward normal; beyond it, straight down
    # (a PCA dominated by a visible side must not tilt the gripper into the table)
    max_grasp_tilt_deg: float = param(30.0, ge=0, le=90)
    # Grasp alternatives with the fingers moved along the object's length by up to this
    # fraction of it (and 5 mm short of its ends): beside a short neighbour that blocks
    # the centred grasp of a long box, the other end may be free. 0 = centred only.
    grasp_offcentre_fraction: float = param(0.3, ge=0, le=0.5)
    # Before a grasp the gripper opens to the object's width plus this on either side
    # (rounded up to 5 mm, at most the full opening), not fully: its fingers then fit
    # gaps between neighbours that a fully open gripper hits, and a neighbour in the
    # closing region counts as blocking (it would be squeezed too). 0 = open fully.
    grasp_opening_clearance_m: float = param(0.01, ge=0, le=0.1)
    # points this far below the object's top count as its top surface (Kinect noise ~5 mm)
    top_surface_band_m: float = param(0.01, ge=0, le=0.2)
    # objects are modelled from the highest point of each footprint cell of this size:
    # a few mm changes no fact, and the `on` counts become areas (cells), not densities
    model_cell_m: float = param(0.005, ge=0.001, le=0.1)
    # fewer points than this: too little to model, left out with a warning
    min_object_points: int = param(10, ge=1, le=100000)
    # flatter objects are modelled this tall so that their hull is a solid
    min_object_height_m: float = param(0.005, gt=0, le=0.2)
    # objects whose hulls already overlap (segmentation noise): a push along d counts as
    # blocked by the other only when the other lies within this angle of d
    touching_block_angle_deg: float = param(60.0, ge=0, le=180)
    # an object counts as too wide (narrow) for the gripper only when its modelled width
    # exceeds the opening (falls short of the closing width) by more than this: modelled
    # widths were off by -4..+6 mm in simulated sessions (labels as segmentation), and
    # every "too wide" object there fitted the 7 cm opening; one within the margin is
    # tried rather than given up
    grasp_width_margin_m: float = param(0.005, ge=0, le=0.1)

    def cross_checks(self) -> None:
        # cost = ceil(exp(gain (d0 - d))) must stay an integer Fast Downward takes
        if self.clearance_cost_gain_per_m * self.clearance_cost_distance_m > 20.0:
            self.fail("clearance_cost_gain_per_m", "times clearance_cost_distance_m must be <= 20 (costs up to e^20)")
