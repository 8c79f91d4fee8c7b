"""The suction tool (section [suction]): the cup, what it holds, and the tool's shape.

Read only where the robot profile's tool has a cup (clearcli/settings/profiles.py
``tools``); a profile's own values come from its entry there. The defaults are a
Robotiq EPick vacuum gripper with one 30 mm bellows cup:

* ``cup_diameter_m`` 0.03: the cup's lip, what must seal on the object's face;
* ``bellows_compliance_m`` 0.005: how far a 1.5-fold bellows lip follows a surface that
  is not flat (its stroke is about a third of its diameter, rounded down);
* ``holding_force_n`` 57: the EPick's vacuum (80 % below atmosphere, 81 kPa) over the
  cup's area (7.07 cm^2); what a lip leaks is the safety factor's to cover;
* ``safety_factor`` 2: the factor vacuum makers ask for a lift from above (at least 1.5,
  2 with a moving arm);
* ``lip_friction`` 0.5: a rubber lip on cardboard or plastic; a load across the cup (a
  side face held) slides when it exceeds this share of the holding force;
* ``density_kg_m3`` 650: the objects' mass estimated from their modelled volume: the
  median of twelve YCB household objects' masses over their boxes' volumes (a cracker
  box 0.17 g/cm^3, boxed food 0.5-0.75, bottles 0.6-0.7, cans 0.9-1.0, a Rubik's cube
  1.4), so a box is not refused for a can's weight and a full can is checked at most
  35 % light (the safety factor covers it);
* the tool's shape, in the frame of the profile's tool centre point (TCP: where the
  arm's IK puts its target; the cup on its axis): the lip ``lip_past_tcp_m`` past it
  along the approach, a stem ``stem_length_m`` long carrying the cup, then the tool's
  body, a cylinder of ``body_radius_m`` and ``body_length_m``: the volume a suction
  approach sweeps. The EPick on a Panda (its TCP 0.1034 m past the flange, the EPick's
  body ~0.09 m and its cup ~0.04 m: the lip 0.13 m past the flange): 0.027 m.
"""

from __future__ import annotations

from dataclasses import dataclass

from clearcli.settings.fields import Section, param


@dataclass(frozen=True)
class SuctionSettings(Section):
    NAME = "suction"

    cup_diameter_m: float = param(0.03, ge=0.005, le=0.2)
    bellows_compliance_m: float = param(0.005, gt=0, le=0.05)
    holding_force_n: float = param(57.0, gt=0, le=5000)
    safety_factor: float = param(2.0, ge=1, le=10)
    lip_friction: float = param(0.5, gt=0, le=2)
    # the fitted face's normal within this of the approach (straight down for a top,
    # horizontal for a side): a cup pressed at a slant peels at its low side
    max_tilt_deg: float = param(20.0, gt=0, le=60)
    # a sample of the cup's disc farther than this from every point of the object (seen
    # along the normal) is a hole or lies past an edge: about 2 point spacings of a Kinect
    # at 1 m (~1.7 mm), so that a whole face seen at that range is not refused; a hole
    # wider than twice this (8 mm) is found
    hole_gap_m: float = param(0.004, gt=0, le=0.05)
    density_kg_m3: float = param(650.0, gt=0, le=20000)
    lip_past_tcp_m: float = param(0.027, ge=-0.5, le=0.5)
    stem_length_m: float = param(0.04, ge=0, le=1)
    body_radius_m: float = param(0.04, gt=0, le=0.5)
    body_length_m: float = param(0.09, gt=0, le=1)

    def cross_checks(self) -> None:
        if self.bellows_compliance_m >= self.cup_diameter_m:
            self.fail("bellows_compliance_m", f"must be less than cup_diameter_m ({self.cup_diameter_m:g})")
