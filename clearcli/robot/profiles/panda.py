"""Franka Emika Panda (FR3 alike) with the Franka Hand; the generic IK."""

from __future__ import annotations

from pathlib import Path

from clearcli.robot.profiles.base import generic_profile

PROFILE = generic_profile(
    summary="Franka Emika Panda, 7 joints, with the Franka Hand (0.08 m opening)",
    urdf=Path(__file__).resolve().parent.parent / "panda.urdf",
    base_frame="panda_link0",
    flange_frame="panda_link8",
    tcp_frame="panda_tcp",
    shoulder_base=(0.0, 0.0, 0.333),  # joint 2's axis, 0.333 m above the base
    reach_m=0.855,  # the maker's figure (flange from the shoulder)
    tcp_past_flange_m=0.1034,  # Franka's figure
    gripper="Franka Hand (0.08 m open)",
    rest=(0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785),  # the maker's "ready" pose: elbow up, hand down
)
