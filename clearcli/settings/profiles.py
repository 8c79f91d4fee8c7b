"""The robot profiles' registry: their names, in order (the default first), and per
profile the robot layer's module that holds it and the [robot] and [gripper] values it
supplies as defaults (a user's values override them).

This is the one place a profile is named: the settings' allowed `[robot] name`s, the
`--robot` help and `clear robots` are made from it, and the robot layer
(clearcli/robot/profiles/) loads each profile from the module named here. It lives in the
settings package, the bottom layer, so that both the settings tree and the robot layer
can read it; a profile's module is named by its text, never imported from here (the
tree stays below the robot layer). A new profile is its module, its description (URDF)
and one entry below; the WAM's values are the sections' own defaults.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True, eq=False)
class ProfileEntry:
    """One registered profile: ``module`` (dotted, importable) holds its ``PROFILE``
    (clearcli/robot/profiles/base.py `RobotProfile`); ``defaults`` is section -> key ->
    value for [robot] and [gripper]. (Compared and hashed by identity: the robot layer
    keeps what it loaded per entry.)"""

    module: str
    defaults: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)


# Sources: the makers' published figures (README of ../shared/data/robots) for the openings
# and reaches; finger and body sizes rounded up from the makers' drawings, so that
# collision checks err on the safe side.
PANDA_DEFAULTS: Mapping[str, Mapping[str, Any]] = {
    "gripper": {
        # Franka Hand: 80 mm between the fingers open (40 mm a finger); it closes fully,
        # but the collision model needs a finger gap, and a thinner object than 1 cm
        # lying on the table is not picked from above by the fingertips
        "opening_width_m": 0.08,
        "closing_width_m": 0.01,
        "closed_gap_m": 0.0,
        "finger_width_m": 0.02,
        "finger_thickness_m": 0.015,
        "gripper_height_m": 0.1034,  # flange to the closing point
        "closing_region_height_m": 0.04,
        "finger_depth_m": 0.055,
        "base_width_m": 0.21,
        "base_depth_m": 0.07,
        "base_height_m": 0.06,
    },
    "robot": {
        # reach ~0.855 m (flange from the shoulder, joint 2's axis 0.333 m above the
        # base); tool-down poses over a table leave ~0.75 m in the plane
        "base_outside_edge_m": 0.10,
        "base_min_object_distance_m": 0.30,
        "base_preferred_object_distance_m": 0.45,
        "base_max_object_distance_m": 0.75,
    },
}
UR5E_DEFAULTS: Mapping[str, Mapping[str, Any]] = {
    "gripper": {
        # Robotiq 2F-85: 85 mm open, closes fully (1 cm kept, as for the Franka Hand)
        "opening_width_m": 0.085,
        "closing_width_m": 0.01,
        "closed_gap_m": 0.0,
        "finger_width_m": 0.022,
        "finger_thickness_m": 0.015,
        "gripper_height_m": 0.15,
        "closing_region_height_m": 0.04,
        "finger_depth_m": 0.06,
        "base_width_m": 0.15,
        "base_depth_m": 0.075,
        "base_height_m": 0.09,
    },
    "robot": {
        # reach ~0.85 m from the shoulder (0.163 m above the base)
        "base_outside_edge_m": 0.10,
        "base_min_object_distance_m": 0.25,
        "base_preferred_object_distance_m": 0.45,
        "base_max_object_distance_m": 0.75,
    },
}

# name -> its entry, the default profile first.
REGISTRY: dict[str, ProfileEntry] = {
    "wam": ProfileEntry("clearcli.robot.profiles.wam"),
    "panda": ProfileEntry("clearcli.robot.profiles.panda", PANDA_DEFAULTS),
    "ur5e": ProfileEntry("clearcli.robot.profiles.ur5e", UR5E_DEFAULTS),
}
DEFAULT_PROFILE: str = next(iter(REGISTRY))


class _Names(Sequence[str]):
    """The registered names in order, as the registry holds them now (a test may add a
    profile): what `[robot] name` accepts."""

    def __getitem__(self, index: Any) -> Any:
        return tuple(REGISTRY)[index]

    def __len__(self) -> int:
        return len(REGISTRY)

    def __iter__(self) -> Iterator[str]:
        return iter(tuple(REGISTRY))

    def __contains__(self, name: object) -> bool:
        return name in REGISTRY

    def __repr__(self) -> str:
        return repr(tuple(REGISTRY))


PROFILE_NAMES: Sequence[str] = _Names()


def profile_defaults(name: str) -> Mapping[str, Mapping[str, Any]]:
    """The [robot] and [gripper] defaults of profile ``name`` (KeyError if unknown)."""
    return REGISTRY[name].defaults


def names_text() -> str:
    """ "wam (default), panda, ur5e": the profiles as help texts list them."""
    return ", ".join(f"{n} (default)" if n == DEFAULT_PROFILE else n for n in REGISTRY)
