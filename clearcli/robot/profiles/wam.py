"""The thesis's Barrett WAM with the IRI gripper (7 cm): the default, its analytic IK."""

from __future__ import annotations

from clearcli.robot.profiles.base import RobotProfile
from clearcli.robot.wam_kinematics import (
    BASE_FRAME,
    REACH_TOOL_PLATE_M,
    SHOULDER_ABOVE_FOOTPRINT_M,
    TCP_FRAME,
    TCP_PAST_TOOL_PLATE_M,
    TOOL_PLATE_FRAME,
    URDF_PATH,
    kinematics_of_wam,
)

PROFILE = RobotProfile(
    summary="Barrett WAM, 7 joints, with the IRI parallel gripper (7 cm opening): the thesis's arm",
    urdf=URDF_PATH,
    base_frame=BASE_FRAME,
    flange_frame=TOOL_PLATE_FRAME,
    tcp_frame=TCP_FRAME,
    shoulder_base=(0.0, 0.0, 0.0),  # the WAM's base frame is at its shoulder
    reach_m=REACH_TOOL_PLATE_M,
    tcp_past_flange_m=TCP_PAST_TOOL_PLATE_M,
    base_above_footprint_m=SHOULDER_ABOVE_FOOTPRINT_M,
    gripper="IRI parallel gripper (0.07 m open)",
    make=kinematics_of_wam,
    thesis_camera=True,  # the thesis's Kinect extrinsic is measured from this arm's base
    log_base_frame="wam_base",  # the thesis's logs' name for it
    # its planner solves in closed form (the swivel sweep): the world runs damped least squares
    world_solver="damped_least_squares",
)
