"""Universal Robots UR5e with a Robotiq 2F-85; the generic IK."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from clearcli.robot.profiles.base import RobotProfile

URDF = Path(__file__).resolve().parent.parent / "ur5e.urdf"
# the shoulder lift joint's axis, 0.1625 m above the base
SHOULDER = (0.0, 0.0, 0.1625)
# the maker's reach, 0.85 m
REACH_M = 0.85
# shoulder up, elbow bent, wrist down
REST = (0.0, -1.571, 1.571, -1.571, -1.571, 0.0)


def _make(robot: Any):
    from clearcli.robot.generic import UrdfKinematics

    return UrdfKinematics(
        URDF, "base_link", "robotiq_tcp", flange_frame="tool0", shoulder_base=SHOULDER, reach_m=REACH_M,
        rest=REST,
        damping=robot.ik_damping, max_iterations=robot.ik_max_iterations, tolerance_m=robot.ik_tolerance_m,
        tolerance_rad=robot.ik_tolerance_rad, n_seeds=robot.ik_seeds,
    )


PROFILE = RobotProfile(
    name="ur5e",
    summary="Universal Robots UR5e, 6 joints, with a Robotiq 2F-85 (0.085 m opening)",
    urdf=URDF,
    base_frame="base_link",
    flange_frame="tool0",
    tcp_frame="robotiq_tcp",
    shoulder_base=SHOULDER,
    reach_m=REACH_M,
    tcp_past_flange_m=0.1443,  # the 2F-85's pads closed, on tool0's axis (ur5e.urdf)
    base_above_footprint_m=0.0,
    gripper="Robotiq 2F-85 (0.085 m open)",
    make=_make,
)
