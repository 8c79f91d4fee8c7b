"""Franka Emika Panda (FR3 alike) with the Franka Hand; the generic IK."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from clearcli.robot.profiles.base import RobotProfile

URDF = Path(__file__).resolve().parent.parent / "panda.urdf"
# joint 2's axis, 0.333 m above the base: the shoulder
SHOULDER = (0.0, 0.0, 0.333)
# the maker's reach, 0.855 m: flange from the shoulder at full stretch
REACH_M = 0.855
# the maker's "ready" pose: elbow up, hand down
REST = (0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785)


def _make(robot: Any):
    from clearcli.robot.generic import UrdfKinematics

    return UrdfKinematics(
        URDF, "panda_link0", "panda_tcp", flange_frame="panda_link8", shoulder_base=SHOULDER, reach_m=REACH_M,
        rest=REST,
        damping=robot.ik_damping, max_iterations=robot.ik_max_iterations, tolerance_m=robot.ik_tolerance_m,
        tolerance_rad=robot.ik_tolerance_rad, n_seeds=robot.ik_seeds,
    )


PROFILE = RobotProfile(
    name="panda",
    summary="Franka Emika Panda, 7 joints, with the Franka Hand (0.08 m opening)",
    urdf=URDF,
    base_frame="panda_link0",
    flange_frame="panda_link8",
    tcp_frame="panda_tcp",
    shoulder_base=SHOULDER,
    reach_m=REACH_M,
    tcp_past_flange_m=0.1034,  # Franka's figure
    base_above_footprint_m=0.0,
    gripper="Franka Hand (0.08 m open)",
    make=_make,
)
