"""Not a task: `robots` reads no frame. The robot profiles, or one profile's facts (the
payload of schema ``clear.robots``), and the early check of a user's URDF that every
command's settings go through (clearcli/commands/options.py)."""

from __future__ import annotations

from typing import Any

from clearcli.settings.profiles import DEFAULT_PROFILE
from clearcli.settings.robot import RobotSettings

SCHEMA, VERSION = "robots", 1


def robots_payload(name: str | None = None) -> dict[str, Any]:
    """{profiles: [{name, summary, default}]} or, for ``name``, {profile: facts} with the
    joints and their limits read from the shipped description."""
    # the robot layer pulls NumPy, ~280 ms cold: the commands import this module for
    # check_robot (their options) and beside `clear settings` (commands/basic.py); only
    # the profiles' facts and a user's URDF need it
    from clearcli.robot.profiles import PROFILES, profile  # noqa: PLC0415

    if name is None:
        return {
            "profiles": [
                {"name": p.name, "summary": p.summary, "default": p.name == DEFAULT_PROFILE} for p in PROFILES.values()
            ]
        }
    p = profile(name)
    facts = p.facts()
    import pinocchio as pin

    model = pin.buildModelFromUrdf(str(p.urdf))
    facts["joints"] = [
        {"name": n, "lower_rad": float(lo), "upper_rad": float(hi)}
        for n, lo, hi in zip(list(model.names)[1:], model.lowerPositionLimit, model.upperPositionLimit)
    ]
    return {"profile": facts}


def check_robot(robot: RobotSettings) -> None:
    """Read a user's URDF (``[robot] urdf``) now: a file that does not parse, a joint's
    non-finite numbers, zero axis or lower limit above its upper, a base or flange frame
    that is not a link or makes no arm (the same, not above the flange, fixed to it), a
    chain of fewer than six revolute joints is one line, exit 3, before any frame is read
    (clearcli/robot/urdf_joints.py `checked_urdf`, clearcli/robot/generic.py)."""
    if robot.urdf:
        # the robot layer for a user's URDF alone (~280 ms: see robots_payload)
        from clearcli.robot.profiles import profile_of  # noqa: PLC0415

        profile_of(robot)  # kept (lru_cache): the arm resolved later reads the file no more
