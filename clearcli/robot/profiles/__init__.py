"""The robot profiles: a registry of interchangeable arms (base.py: what one is).

A new profile is a module with a ``PROFILE`` and one line here, plus its [robot] and
[gripper] defaults in clearcli/settings/profiles.py (whose names must match).
"""

from __future__ import annotations

from clearcli.errors import SettingsError
from clearcli.robot.profiles import panda, ur5e, wam
from clearcli.robot.profiles.base import Kinematics, RobotProfile
from clearcli.settings.profiles import PROFILE_NAMES

PROFILES: dict[str, RobotProfile] = {p.name: p for p in (wam.PROFILE, panda.PROFILE, ur5e.PROFILE)}
assert tuple(PROFILES) == PROFILE_NAMES

__all__ = ["PROFILES", "Kinematics", "RobotProfile", "kinematics_from_settings", "profile", "robot_block"]


def profile(name: str) -> RobotProfile:
    """The profile called ``name``; an unknown name lists the known ones."""
    try:
        return PROFILES[name]
    except KeyError:
        raise SettingsError(f"robot {name!r} is not a profile; known: {', '.join(PROFILES)} (`clear robots`)") from None


def kinematics_from_settings(robot: object) -> Kinematics:
    """The kinematics of ``[robot] name``'s profile with the IK search of ``[robot]``
    (`RobotSettings`): the WAM's analytic solver, or the generic one of another arm."""
    return profile(getattr(robot, "name", "wam")).kinematics(robot)


def robot_block(settings: object) -> dict[str, object]:
    """What a plan says of its robot: the profile, a digest of its description, its base
    and tool frames, its joints' names (the order of every joint vector) and the gripper's
    widths."""
    import hashlib

    robot, gripper = settings.robot, settings.gripper  # type: ignore[attr-defined]
    p = profile(robot.name)
    from clearcli.robot.urdf_joints import joint_names

    return {
        "name": p.name,
        "urdf_sha256": hashlib.sha256(p.urdf.read_bytes()).hexdigest(),
        "base_frame": p.base_frame,
        "tcp_frame": p.tcp_frame,
        "joint_names": list(joint_names(p.urdf)),
        "gripper": {"name": p.gripper, "opening_width_m": gripper.opening_width_m, "closing_width_m": gripper.closing_width_m},
    }
