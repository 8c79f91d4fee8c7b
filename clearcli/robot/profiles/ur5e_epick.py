"""Universal Robots UR5e with a Robotiq EPick vacuum gripper (one 30 mm bellows cup)
on its flange (the arm and its closed-form IK are the ur5e profile's; the lip is
``[suction] lip_past_tcp_m`` past the description's TCP, here 0.0143 m short of it)."""

from __future__ import annotations

import dataclasses

from clearcli.robot.profiles import ur5e

PROFILE = dataclasses.replace(
    ur5e.PROFILE,
    summary="Universal Robots UR5e, 6 joints, with a Robotiq EPick vacuum gripper (one 30 mm bellows cup)",
    gripper="Robotiq EPick (30 mm cup)",
    label="UR5e-EPick",
)
