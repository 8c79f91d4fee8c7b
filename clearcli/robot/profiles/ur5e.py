"""Universal Robots UR5e with a Robotiq 2F-85; IK in closed form (ur_ik.py)."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from pathlib import Path

import numpy as np

from clearcli.robot.profiles.base import generic_profile
from clearcli.robot.ur_ik import UR5E, solutions


def _closed_form() -> tuple[Callable[[np.ndarray], list[np.ndarray]], str, str]:
    """The UR family's closed form (ur_ik.py) with the UR5e's DH table; the description's
    base_link_inertia is its base frame, wrist_3_link its frame 6."""
    return partial(solutions, UR5E), "base_link_inertia", "wrist_3_link"


PROFILE = generic_profile(
    summary="Universal Robots UR5e, 6 joints, with a Robotiq 2F-85 (0.085 m opening)",
    urdf=Path(__file__).resolve().parent.parent / "ur5e.urdf",
    base_frame="base_link",
    flange_frame="tool0",
    tcp_frame="robotiq_tcp",
    shoulder_base=(0.0, 0.0, 0.1625),  # the shoulder lift joint's axis above the base
    reach_m=0.85,  # the maker's figure
    tcp_past_flange_m=0.1443,  # the 2F-85's pads closed, on tool0's axis (ur5e.urdf)
    gripper="Robotiq 2F-85 (0.085 m open)",
    rest=(0.0, -1.571, 1.571, -1.571, -1.571, 0.0),  # shoulder up, elbow bent, wrist down
    closed_form=_closed_form,
    label="UR5e",
)
