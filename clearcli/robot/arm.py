"""The robot of one command, resolved once: `Arm`.

`resolve_arm(settings)` looks the profile up (by [robot] name, or the user's URDF) once
and returns a frozen `Arm`: the profile, the [robot] and [gripper] settings it runs
with, its kinematics (the model read once, on first use; each plan gets a new IK search
on it), where it stands (`place`) and what a plan says of it (`block`). Planning, the
plan's JSON, the picture, the placement and the simulated world all receive this value;
none of them looks a profile up by name again.
"""

from __future__ import annotations

import functools
import hashlib
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from clearcli.robot.placement import TableScene, resolve_T_base_camera
from clearcli.robot.profiles import Kinematics, RobotProfile, profile_of
from clearcli.settings.geometry import GripperSettings
from clearcli.settings.robot import RobotSettings

if TYPE_CHECKING:
    from clearcli.settings import Settings


@dataclass(frozen=True, eq=False)
class Arm:
    """A robot profile with the settings it runs with (see the module's docstring)."""

    profile: RobotProfile
    settings: RobotSettings  # [robot]
    gripper: GripperSettings  # [gripper]

    @property
    def name(self) -> str:
        return self.profile.name

    @functools.cached_property
    def model(self) -> Kinematics:
        """The kinematics built once (the description read, the reach measured); search
        with `kinematics()`, not with this."""
        return self.profile.kinematics(self.settings)

    def kinematics(self) -> Kinematics:
        """A new IK search on the arm's model (an empty cache, no warm starts from
        earlier plans): what each plan and the simulated world solve with."""
        return self.model.fresh()

    def place(
        self, state: TableScene | None, camera_pose: Sequence[float] | str | None = None
    ) -> tuple[np.ndarray, str]:
        """T_base_camera and where it came from: ``camera_pose`` (a command line's) over
        [robot] camera_pose, else placed from the table in ``state`` by the placement
        rule with this arm's distances and mount (clearcli/robot/placement.py)."""
        pose = camera_pose if camera_pose is not None else (self.settings.camera_pose or None)
        return resolve_T_base_camera(pose, state, self.settings, self.profile)

    @property
    def reach_of_tcp_m(self) -> float:
        """The gripper's closing point at full stretch from the shoulder (the picture's circle)."""
        return self.profile.reach_m + self.profile.tcp_past_flange_m

    @functools.cached_property
    def _block(self) -> dict[str, Any]:
        p = self.profile
        names = list(p.arm_joint_names())
        return {
            "name": p.name,
            "urdf_sha256": hashlib.sha256(p.urdf.read_bytes()).hexdigest(),
            "base_frame": p.base_frame,
            "tcp_frame": p.tcp_frame,
            "joint_names": names,
            "gripper": {
                "name": p.gripper,
                "opening_width_m": self.gripper.opening_width_m,
                "closing_width_m": self.gripper.closing_width_m,
            },
        }

    def block(self) -> dict[str, Any]:
        """What a plan says of its robot: the profile, a digest of its description, its
        base and tool frames, its joints' names (the order of every joint vector) and the
        gripper's widths (a new dict each call; computed once)."""
        b = self._block
        return {**b, "joint_names": list(b["joint_names"]), "gripper": dict(b["gripper"])}


def resolve_arm(settings: Settings) -> Arm:
    """The arm ``settings`` describe ([robot], [gripper]); the same value for the same
    sections (a batch's worker resolves once for all its frames). An unknown profile or
    a user's URDF that cannot be used is one line (SettingsError)."""
    return _arm(profile_of(settings.robot), settings.robot, settings.gripper)


@functools.lru_cache(maxsize=8)
def _arm(profile: RobotProfile, robot: RobotSettings, gripper: GripperSettings) -> Arm:
    return Arm(profile, robot, gripper)
