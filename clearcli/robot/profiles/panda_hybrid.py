"""Franka Emika Panda with the Franka Hand and a suction cup on a stem between its
fingers (the arm and its IK are the panda profile's; the cup's place and the volume the
tool sweeps are the registry's [suction] defaults, clearcli/settings/profiles.py)."""

from __future__ import annotations

import dataclasses

from clearcli.robot.profiles import panda

PROFILE = dataclasses.replace(
    panda.PROFILE,
    summary="Franka Emika Panda, 7 joints, with the Franka Hand (0.08 m opening) and a 30 mm suction cup between "
    "its fingers",
    gripper="Franka Hand (0.08 m open) + 30 mm suction cup",
    label="PANDA-HYBRID",
)
