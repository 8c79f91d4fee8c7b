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
