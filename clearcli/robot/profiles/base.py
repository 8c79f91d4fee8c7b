"""What a robot profile is: the arm's description and frames, its reach and placement,
its gripper, and the kinematics (IK, collision capsules) the planner checks against.

A profile is a module of this package with one ``PROFILE`` registered in
``clearcli/robot/profiles/__init__.py``; its [robot] and [gripper] defaults live in the
settings tree (clearcli/settings/profiles.py), which a user's values override.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Protocol

import numpy as np


class Kinematics(Protocol):
    """What the planner and the reach checks use of an arm."""

    lower: np.ndarray
    upper: np.ndarray
    joint_names: tuple[str, ...]

    def fk(self, q: np.ndarray, frame: str | None = None) -> np.ndarray: ...

    def ik(self, T_base_tcp: np.ndarray, warm: np.ndarray | None = None) -> np.ndarray | None: ...

    def reachable(self, T_base_tcp: np.ndarray, slack_m: float = 0.005) -> bool: ...

    def capsules(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...


@dataclass(frozen=True)
class RobotProfile:
    name: str
    summary: str  # arm and gripper, one line
    urdf: Path  # the description shipped in the package
    base_frame: str  # T_base_* in the JSON are in this frame
    flange_frame: str
    tcp_frame: str  # the gripper's closing point: z approach, x closing direction
    shoulder_base: tuple[float, float, float]  # the shoulder's centre in the base frame (m)
    reach_m: float  # the flange's farthest distance from the shoulder (m; the maker's figure)
    tcp_past_flange_m: float  # the gripper's closing point past the flange (m)
    base_above_footprint_m: float  # the base frame's origin above the floor of the arm's mount
    gripper: str  # its name
    make: Callable[[Any], Kinematics]  # [robot] settings -> kinematics

    def kinematics(self, robot_settings: Any) -> Kinematics:
        return self.make(robot_settings)

    def facts(self) -> dict[str, Any]:
        """What `clear robots NAME` prints."""
        from clearcli.settings.profiles import PROFILE_DEFAULTS

        return {
            "name": self.name,
            "summary": self.summary,
            "urdf": str(self.urdf),
            "base_frame": self.base_frame,
            "flange_frame": self.flange_frame,
            "tcp_frame": self.tcp_frame,
            "reach_m": self.reach_m,
            "tcp_past_flange_m": self.tcp_past_flange_m,
            "shoulder_base_m": list(self.shoulder_base),
            "base_above_footprint_m": self.base_above_footprint_m,
            "gripper": self.gripper,
            "defaults": {k: dict(v) for k, v in PROFILE_DEFAULTS[self.name].items()},
        }


def generic_profile(
    *, name: str, summary: str, urdf: Path, base_frame: str, flange_frame: str, tcp_frame: str,
    shoulder_base: tuple[float, float, float], reach_m: float, tcp_past_flange_m: float, gripper: str,
    rest: tuple[float, ...],
    closed_form: Callable[[], tuple[Any, str, str]] | None = None,
) -> RobotProfile:
    """A profile whose kinematics are the generic solver's on its shipped URDF (or a
    closed form, ``closed_form()`` -> (solver, its base frame, its end frame)), its base
    frame on the table's plane."""

    def make(robot: Any) -> Kinematics:
        from clearcli.robot.generic import UrdfKinematics

        return UrdfKinematics(
            urdf, base_frame, tcp_frame, flange_frame=flange_frame,
            closed_form=closed_form() if closed_form is not None else None,
            rest=rest, damping=robot.ik_damping, max_iterations=robot.ik_max_iterations,
            tolerance_m=robot.ik_tolerance_m, tolerance_rad=robot.ik_tolerance_rad, n_seeds=robot.ik_seeds,
        )

    return RobotProfile(
        name=name, summary=summary, urdf=urdf, base_frame=base_frame, flange_frame=flange_frame,
        tcp_frame=tcp_frame, shoulder_base=shoulder_base, reach_m=reach_m, tcp_past_flange_m=tcp_past_flange_m,
        base_above_footprint_m=0.0, gripper=gripper, make=make,
    )
