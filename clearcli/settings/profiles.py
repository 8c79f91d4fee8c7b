"""The robot profiles' registry: their names, in order (the default first), and per
profile the robot layer's module that holds it, the parts its tool has (fingers, a
suction cup, or both) and the [robot], [gripper], [suction] and [plan] grasps values it
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
    value for [robot], [gripper], [suction] and [plan] (grasps). (Compared and hashed by identity: the robot layer
    keeps what it loaded per entry.)"""

    module: str
    defaults: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    # what its tool has: "fingers" (a parallel gripper) and/or "cup" (a vacuum cup); the
    # grasp kinds each take one (clearcli/settings/kinds.py ``tool``)
    tools: tuple[str, ...] = ("fingers",)
    tool: str = ""  # its tool, named for `clear robots` and the --robot help ("" = its gripper)


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

# Suction tools. The cup and its vacuum are the [suction] section's own defaults (a
# Robotiq EPick with one 30 mm bellows cup: clearcli/settings/suction.py); these say where
# the lip is and what the tool's body sweeps, in the frame of each arm's TCP.
# The Panda's hand replaced by an EPick: the lip 0.13 m past the flange (the EPick's body
# ~0.09 m, its cup ~0.04 m), the description's TCP 0.1034 m past it: 0.027 m on.
PANDA_SUCTION_DEFAULTS: Mapping[str, Mapping[str, Any]] = {
    **PANDA_DEFAULTS,
    "suction": {"lip_past_tcp_m": 0.027, "stem_length_m": 0.04, "body_radius_m": 0.04, "body_length_m": 0.09},
    "plan": {"grasps": "pinch,suction"},
}
# The Franka Hand with a cup on a stem between its fingers, the lip 2 cm past the closed
# fingertips (the fingertips 0.02 m past the TCP: the closing region's half height), as
# the Amazon Robotics Challenge grippers carried one beside their fingers. The body the
# approach sweeps: the closed fingers and the hand, as wide as the hand (0.21 m) over
# the fingers' and the hand's length, erring on the safe side.
PANDA_HYBRID_DEFAULTS: Mapping[str, Mapping[str, Any]] = {
    **PANDA_DEFAULTS,
    "suction": {"lip_past_tcp_m": 0.04, "stem_length_m": 0.02, "body_radius_m": 0.105, "body_length_m": 0.16},
    "plan": {"grasps": "pinch,rim,slide,suction"},
}
# The UR5e with an EPick on its flange (tool0): the lip 0.13 m past it, the description's
# TCP (the 2F-85's) 0.1443 m past it: the lip 0.0143 m short of that TCP.
UR5E_EPICK_DEFAULTS: Mapping[str, Mapping[str, Any]] = {
    **UR5E_DEFAULTS,
    "suction": {"lip_past_tcp_m": -0.0143, "stem_length_m": 0.04, "body_radius_m": 0.04, "body_length_m": 0.09},
    "plan": {"grasps": "pinch,suction"},
}

# name -> its entry, the default profile first.
REGISTRY: dict[str, ProfileEntry] = {
    "wam": ProfileEntry("clearcli.robot.profiles.wam"),
    "panda": ProfileEntry("clearcli.robot.profiles.panda", PANDA_DEFAULTS),
    "ur5e": ProfileEntry("clearcli.robot.profiles.ur5e", UR5E_DEFAULTS),
    "panda-hybrid": ProfileEntry(
        "clearcli.robot.profiles.panda_hybrid",
        PANDA_HYBRID_DEFAULTS,
        tools=("fingers", "cup"),
        tool="Franka Hand with a 30 mm suction cup between its fingers",
    ),
    "panda-suction": ProfileEntry(
        "clearcli.robot.profiles.panda_suction",
        PANDA_SUCTION_DEFAULTS,
        tools=("cup",),
        tool="Robotiq EPick, one 30 mm bellows cup",
    ),
    "ur5e-epick": ProfileEntry(
        "clearcli.robot.profiles.ur5e_epick",
        UR5E_EPICK_DEFAULTS,
        tools=("cup",),
        tool="Robotiq EPick, one 30 mm bellows cup",
    ),
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
    """The [robot], [gripper], [suction] and [plan] defaults of profile ``name`` (KeyError
    if unknown)."""
    return REGISTRY[name].defaults


def tools_of(name: str) -> tuple[str, ...]:
    """What profile ``name``'s tool has ("fingers", "cup"); a user's own URDF keeps its
    profile's."""
    entry = REGISTRY.get(name)
    return entry.tools if entry is not None else ("fingers",)


def profiles_with(tool: str) -> tuple[str, ...]:
    """The profiles whose tool has ``tool`` ("cup": the suction profiles)."""
    return tuple(n for n, e in REGISTRY.items() if tool in e.tools)


def names_text() -> str:
    """ "wam (default), panda, ur5e": the profiles as help texts list them."""
    return ", ".join(f"{n} (default)" if n == DEFAULT_PROFILE else n for n in REGISTRY)
