"""What a robot profile is: the arm's description and frames, its reach and placement,
its gripper, and the kinematics (IK, collision capsules) the planner checks against.

A profile is a module with one ``PROFILE``, registered by one entry in the registry
(clearcli/settings/profiles.py), which names it and holds its [robot] and [gripper]
defaults (a user's values override them). A profile says what differs between arms in
its fields (the plan picture's label, whether the thesis's camera pose is its, the base
frame a simulated log names, the simulated world's solver); nothing outside the profiles
tests an arm's name.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from clearcli.robot.kinematics import Kinematics
from clearcli.robot.urdf_joints import joint_names
from clearcli.settings.profiles import REGISTRY
from clearcli.settings.robot import RobotSettings

__all__ = ["Kinematics", "RobotProfile", "WorldSolver", "generic_profile"]

# The simulated world judges reach with a solver the planner does not use for the arm:
# damped least squares (on an arm planned in closed form), or SciPy's bounded least
# squares (clearcli/sim/reach.py).
WorldSolver = Literal["damped_least_squares", "least_squares"]


@dataclass(frozen=True, kw_only=True)
class RobotProfile:
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
    make: Callable[[RobotSettings], Kinematics]  # [robot] settings -> kinematics
    # its registered name: given by the registry (clearcli/settings/profiles.py), "urdf"
    # for a user's own description
    name: str = ""
    label: str = ""  # on the plan picture ("" = the name in capitals)
    # `--camera-pose thesis` (the thesis's camera, measured from this arm's base) applies
    thesis_camera: bool = False
    log_base_frame: str = ""  # the base frame a simulated log's /tf_static names ("" = base_frame)
    world_solver: WorldSolver = "least_squares"  # the simulated world's own IK for this arm
    # its joints' names in the order of every joint vector; () = the description's movable
    # joints (a user's URDF names its arm's own, without the joints held at 0)
    joint_names: tuple[str, ...] = ()

    def kinematics(self, robot_settings: RobotSettings) -> Kinematics:
        """The arm's kinematics with the IK search of ``robot_settings`` ([robot])."""
        return self.make(robot_settings)

    def arm_joint_names(self) -> tuple[str, ...]:
        """The joints' names, the order of every joint vector (read from the description
        with the standard library when the profile does not list them)."""
        return self.joint_names or joint_names(self.urdf)

    @property
    def picture_label(self) -> str:
        return self.label or self.name.upper()

    @property
    def tf_base_frame(self) -> str:
        """The base frame's name on a simulated log's /tf_static."""
        return self.log_base_frame or self.base_frame

    def facts(self) -> dict[str, Any]:
        """What `clear robots NAME` prints."""
        entry = REGISTRY.get(self.name)
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
            # what its tool has: "fingers", "cup" (the grasp kinds each take one)
            "tools": list(entry.tools if entry is not None else ("fingers",)),
            "defaults": {k: dict(v) for k, v in (entry.defaults if entry is not None else {}).items()},
        }


def generic_profile(
    *,
    summary: str,
    urdf: Path,
    base_frame: str,
    flange_frame: str,
    tcp_frame: str,
    shoulder_base: tuple[float, float, float],
    reach_m: float,
    tcp_past_flange_m: float,
    gripper: str,
    rest: tuple[float, ...],
    closed_form: Callable[[], tuple[Any, str, str]] | None = None,
    label: str = "",
) -> RobotProfile:
    """A profile whose kinematics are the generic solver's on its shipped URDF (or a
    closed form, ``closed_form()`` -> (solver, its base frame, its end frame)), its base
    frame on the table's plane."""

    def make(robot: RobotSettings) -> Kinematics:
        from clearcli.robot.generic import UrdfKinematics  # noqa: PLC0415  (~20 ms measured; only an arm built from a URDF needs it, not the WAM or `clear robots`)

        return UrdfKinematics(
            urdf,
            base_frame,
            tcp_frame,
            flange_frame=flange_frame,
            closed_form=closed_form() if closed_form is not None else None,
            rest=rest,
            damping=robot.ik_damping,
            max_iterations=robot.ik_max_iterations,
            tolerance_m=robot.ik_tolerance_m,
            tolerance_rad=robot.ik_tolerance_rad,
            n_seeds=robot.ik_seeds,
        )

    return RobotProfile(
        summary=summary,
        urdf=urdf,
        base_frame=base_frame,
        flange_frame=flange_frame,
        tcp_frame=tcp_frame,
        shoulder_base=shoulder_base,
        reach_m=reach_m,
        tcp_past_flange_m=tcp_past_flange_m,
        base_above_footprint_m=0.0,
        gripper=gripper,
        make=make,
        label=label,
    )
