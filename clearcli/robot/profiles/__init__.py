"""The robot profiles: a registry of interchangeable arms (base.py: what one is).

A new profile is a module with a ``PROFILE`` and one line here, plus its [robot] and
[gripper] defaults in clearcli/settings/profiles.py (whose names must match).
"""

from __future__ import annotations

import functools

from clearcli.errors import SettingsError
from clearcli.robot.profiles import panda, ur5e, wam
from clearcli.robot.profiles.base import Kinematics, RobotProfile
from clearcli.settings.profiles import PROFILE_NAMES

PROFILES: dict[str, RobotProfile] = {p.name: p for p in (wam.PROFILE, panda.PROFILE, ur5e.PROFILE)}
assert tuple(PROFILES) == PROFILE_NAMES

__all__ = ["PROFILES", "Kinematics", "RobotProfile", "kinematics_from_settings", "profile", "profile_of", "robot_block"]


def profile(name: str) -> RobotProfile:
    """The profile called ``name``; an unknown name lists the known ones."""
    try:
        return PROFILES[name]
    except KeyError:
        raise SettingsError(f"robot {name!r} is not a profile; known: {', '.join(PROFILES)} (`clear robots`)") from None


def profile_of(robot: object) -> RobotProfile:
    """The profile ``[robot]`` describes: ``name``'s, or, with ``urdf`` set, the user's
    own arm from that file."""
    if not getattr(robot, "urdf", ""):
        return profile(getattr(robot, "name", "wam"))
    return _user_profile(robot)


@functools.lru_cache(maxsize=8)
def _user_profile(robot: object) -> RobotProfile:
    """The user's own arm from ``[robot] urdf`` (frames and tool-centre offset from
    ``[robot]``, the generic IK); the file is read once per settings."""
    from pathlib import Path

    path = Path(robot.urdf).expanduser().resolve()  # type: ignore[attr-defined]

    def make(settings: object) -> Kinematics:
        from clearcli.robot.generic import UrdfKinematics

        s = settings
        return UrdfKinematics(
            path, s.base_frame, "", flange_frame=s.flange_frame,  # type: ignore[attr-defined]
            tcp_xyz_m=s.tcp_xyz_m, tcp_yaw_deg=s.tcp_yaw_deg,  # type: ignore[attr-defined]
            damping=s.ik_damping, max_iterations=s.ik_max_iterations,  # type: ignore[attr-defined]
            tolerance_m=s.ik_tolerance_m, tolerance_rad=s.ik_tolerance_rad, n_seeds=s.ik_seeds,  # type: ignore[attr-defined]
        )

    kin = make(robot)  # reads the file: a bad one is one line, before any frame
    return RobotProfile(
        name="urdf", summary=f"your arm from {path}", urdf=path, base_frame=str(robot.base_frame or "(root link)"),  # type: ignore[attr-defined]
        flange_frame=kin.flange_frame, tcp_frame="clear_tcp", shoulder_base=tuple(kin.shoulder_bound),  # type: ignore[arg-type]
        reach_m=kin.stretch_m, tcp_past_flange_m=float(sum(v * v for v in robot.tcp_xyz_m) ** 0.5),  # type: ignore[attr-defined]
        base_above_footprint_m=0.0, gripper="[gripper]", make=make,
    )


def kinematics_from_settings(robot: object) -> Kinematics:
    """The kinematics of ``[robot]``'s profile (or its own URDF) with the IK search of
    ``[robot]`` (`RobotSettings`): the WAM's analytic solver, or the generic one."""
    return profile_of(robot).kinematics(robot)


def robot_block(settings: object) -> dict[str, object]:
    """What a plan says of its robot: the profile, a digest of its description, its base
    and tool frames, its joints' names (the order of every joint vector) and the gripper's
    widths."""
    import hashlib

    robot, gripper = settings.robot, settings.gripper  # type: ignore[attr-defined]
    p = profile_of(robot)
    from clearcli.robot.urdf_joints import joint_names

    names = list(joint_names(p.urdf)) if p.name != "urdf" else list(p.kinematics(robot).joint_names)
    return {
        "name": p.name,
        "urdf_sha256": hashlib.sha256(p.urdf.read_bytes()).hexdigest(),
        "base_frame": p.base_frame,
        "tcp_frame": p.tcp_frame,
        "joint_names": names,
        "gripper": {"name": p.gripper, "opening_width_m": gripper.opening_width_m, "closing_width_m": gripper.closing_width_m},
    }
