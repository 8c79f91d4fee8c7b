"""Robot settings (section [robot]): where the WAM stands and how IK is searched."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class RobotSettings:
    # T_base_camera as x y z qx qy qz qw of the points' frame in the WAM base frame;
    # empty = derive from the table (see clearcli/robot/placement.py).
    camera_pose: tuple[float, ...] = ()
    ik_seeds: int = 8
    ik_tolerance_m: float = 0.001
    ik_tolerance_rad: float = 0.01
    # Damped least squares: 0.05 keeps steps bounded near singularities (the straight-up
    # home pose) while still converging in ~20 iterations far from them.
    ik_damping: float = 0.05
    ik_max_iterations: int = 150
    # The default placement puts the WAM footprint this far outside the table edge
    # nearest the camera: about the radius of the WAM base, so the base clears the table.
    base_outside_edge_m: float = 0.10
    # ...and at least this far (on the table plane) from every object's centroid: the
    # visible table edge can be a crop with objects right at it, and a WAM cannot reach
    # down beside its own base (top grasps fail there in IK).
    base_min_object_distance_m: float = 0.30
    # ...and farther back, up to this from the nearest object, while the farthest stays
    # within base_max_object_distance_m: a push towards the base starts 5-15 cm nearer
    # than its object, and top-down poses with the wrist centre within ~0.26 m of the
    # shoulder axis have no IK (measured on the simulated sessions' failures).
    base_preferred_object_distance_m: float = 0.40
    # the WAM's tool plate reaches 0.915 m from the shoulder; top grasps of tall objects
    # need some of it
    base_max_object_distance_m: float = 0.85
    # Arm links must keep this clearance from the table plane and from other objects'
    # hulls (the gripper itself is checked by the predicates: block_grasp, block_dir).
    collision_margin_m: float = 0.01
