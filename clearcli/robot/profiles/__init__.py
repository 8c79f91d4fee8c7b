"""The robot profiles (base.py: what one is), loaded from the registry.

The registry is clearcli/settings/profiles.py `REGISTRY`: each profile's name, the module
that holds its ``PROFILE`` and its [robot] and [gripper] defaults. It lives at the bottom
of the layers so that the settings tree can check `[robot] name` against it and apply a
profile's defaults; this package imports each registered module when its profile is
first asked for, and gives the profile its registered name. A new profile is its module,
its description (URDF) and one entry there: nothing here changes.

A command resolves its robot once (clearcli/robot/arm.py `resolve_arm`): the stages
receive that, never a name.
"""

from __future__ import annotations

import dataclasses
import functools
import importlib
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from clearcli.errors import SettingsError
from clearcli.robot.profiles.base import Kinematics, RobotProfile
from clearcli.settings.profiles import PROFILE_NAMES, REGISTRY, ProfileEntry
from clearcli.settings.robot import RobotSettings

if TYPE_CHECKING:
    from clearcli.robot.generic import UrdfKinematics

__all__ = ["PROFILES", "Kinematics", "RobotProfile", "kinematics_from_settings", "profile", "profile_of"]


def profile(name: str) -> RobotProfile:
    """The profile registered as ``name``; an unknown name lists the known ones."""
    entry = REGISTRY.get(name)
    if entry is None:
        raise SettingsError(f"robot {name!r} is not a profile; known: {', '.join(PROFILE_NAMES)} (`clear robots`)")
    return _load(name, entry)


@functools.cache
def _load(name: str, entry: ProfileEntry) -> RobotProfile:
    """The ``PROFILE`` of ``entry``'s module, named ``name`` (once per registry entry)."""
    found = importlib.import_module(entry.module).PROFILE
    if not isinstance(found, RobotProfile):
        raise TypeError(f"{entry.module}.PROFILE is not a RobotProfile")
    return dataclasses.replace(found, name=name)


class _Profiles(Mapping[str, RobotProfile]):
    """name -> profile, in the registry's order, as the registry holds it now."""

    def __getitem__(self, name: str) -> RobotProfile:
        if name not in REGISTRY:
            raise KeyError(name)
        return profile(name)

    def __iter__(self) -> Iterator[str]:
        return iter(tuple(REGISTRY))

    def __len__(self) -> int:
        return len(REGISTRY)


PROFILES: Mapping[str, RobotProfile] = _Profiles()


def profile_of(robot: RobotSettings) -> RobotProfile:
    """The profile ``[robot]`` describes: ``name``'s, or, with ``urdf`` set, the user's
    own arm from that file."""
    if not robot.urdf:
        return profile(robot.name)
    return _user_profile(robot)


def _urdf_kinematics(path: Path, s: RobotSettings) -> UrdfKinematics:
    """The generic kinematics of a user's URDF with the frames, tool-centre offset and IK
    search of ``[robot]``."""
    from clearcli.robot.generic import UrdfKinematics  # noqa: PLC0415  (~20 ms measured; only an arm built from a URDF needs it, not the WAM or `clear robots`)

    return UrdfKinematics(
        path,
        s.base_frame,
        "",
        flange_frame=s.flange_frame,
        tcp_xyz_m=s.tcp_xyz_m,
        tcp_yaw_deg=s.tcp_yaw_deg,
        damping=s.ik_damping,
        max_iterations=s.ik_max_iterations,
        tolerance_m=s.ik_tolerance_m,
        tolerance_rad=s.ik_tolerance_rad,
        n_seeds=s.ik_seeds,
    )


@functools.lru_cache(maxsize=8)
def _user_profile(robot: RobotSettings) -> RobotProfile:
    """The user's own arm from ``[robot] urdf`` (frames and tool-centre offset from
    ``[robot]``, the generic IK); the file is read once per settings."""
    path = Path(robot.urdf).expanduser().resolve()
    kin = _urdf_kinematics(path, robot)  # reads the file: a bad one is one line, before any frame

    def make(settings: RobotSettings) -> Kinematics:
        # the model read above, a new search on it; other settings read the file again
        return kin.fresh() if settings == robot else _urdf_kinematics(path, settings)

    x, y, z = (float(v) for v in kin.shoulder_bound)
    return RobotProfile(
        name="urdf",
        summary=f"your arm from {path}",
        urdf=path,
        base_frame=robot.base_frame or "(root link)",
        flange_frame=kin.flange_frame,
        tcp_frame="clear_tcp",
        shoulder_base=(x, y, z),
        reach_m=kin.stretch_m,
        tcp_past_flange_m=float(sum(v * v for v in robot.tcp_xyz_m) ** 0.5),
        base_above_footprint_m=0.0,
        gripper="[gripper]",
        make=make,
        joint_names=tuple(kin.joint_names),
    )


def kinematics_from_settings(robot: RobotSettings) -> Kinematics:
    """The kinematics of ``[robot]``'s profile (or its own URDF) with the IK search of
    ``[robot]`` (`RobotSettings`): the WAM's analytic solver, or the generic one. (The
    stages take a command's resolved arm instead: clearcli/robot/arm.py.)"""
    return profile_of(robot).kinematics(robot)
