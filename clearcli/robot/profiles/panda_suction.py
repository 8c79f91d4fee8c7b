"""Franka Emika Panda with a Robotiq EPick vacuum gripper (one 30 mm bellows cup) in
place of its hand (the arm and its IK are the panda profile's; the lip is
``[suction] lip_past_tcp_m`` past the description's TCP)."""

from __future__ import annotations

import dataclasses

from clearcli.robot.profiles import panda

PROFILE = dataclasses.replace(
    panda.PROFILE,
    summary="Franka Emika Panda, 7 joints, with a Robotiq EPick vacuum gripper (one 30 mm bellows cup)",
    gripper="Robotiq EPick (30 mm cup)",
    label="PANDA-SUCTION",
)
