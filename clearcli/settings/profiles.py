"""Robot profiles as the settings tree sees them: their names, and the [robot] and
[gripper] values each supplies as defaults (a user's values override them).

The arm's description, IK and collision model are the robot layer's
(clearcli/robot/profiles/); here is only what a settings file can also say, so that the
tree stays below the robot layer. The WAM's values are the sections' own defaults.
"""

from __future__ import annotations

from typing import Any, Mapping

# The known profiles, the default first.
PROFILE_NAMES: tuple[str, ...] = ("wam", "panda", "ur5e")

# Per profile: section -> key -> default. Sources: the makers' published figures (README of
# ../shared/data/robots) for the openings and reaches; finger and body sizes rounded up
# from the makers' drawings, so that collision checks err on the safe side.
PROFILE_DEFAULTS: Mapping[str, Mapping[str, Mapping[str, Any]]] = {
    "wam": {},
    "panda": {
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
    },
    "ur5e": {
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
    },
}
assert tuple(PROFILE_DEFAULTS) == PROFILE_NAMES
