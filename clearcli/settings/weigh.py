"""Weighing on the lift: the suction settings to plan with once more when nothing can be
done while a cup's load was judged on an estimated mass.

[suction] density_kg_m3 (650, the median household object's) times the modelled volume,
held with [suction] safety_factor (2): a big light box of 5 l is estimated at 3.5 kg and
may truly weigh 0.2, so a table of boxes can be refused whole. The closed loop (the
replay session) and a single plan (the plan task) then plan once more as if the objects
were as light as a household object plausibly is, against the cup's own hold (factor
1): the cup seals and the arm lifts, which weighs it, as the Amazon Robotics Challenge
systems tried suction first and checked the vacuum. Shared here, below both layers.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

from clearcli.settings.profiles import tools_of

if TYPE_CHECKING:
    from clearcli.settings.tree import Settings

# The lightest density a household object plausibly has (kg/m^3): a cracker box's 170,
# the lightest of the twelve YCB objects [suction] density_kg_m3's default (their
# median) was taken from (clearcli/settings/suction.py).
LIGHTEST_DENSITY_KG_M3 = 170.0


def lightest_plausible(settings: Settings) -> Settings | None:
    """``settings`` with [suction] density_kg_m3 at most `LIGHTEST_DENSITY_KG_M3` and
    safety_factor 1, or None where a cup's load was not judged on a margin this relaxes:
    the profile's tool has no cup, suction is not among [plan] grasps, or the safety
    factor is 1 already (the user's own factor 1 is taken as meant)."""
    kinds = {k.strip() for k in str(settings.plan.grasps).split(",")}
    if settings.suction.safety_factor <= 1.0 or "suction" not in kinds or "cup" not in tools_of(settings.robot.name):
        return None
    lightest = min(settings.suction.density_kg_m3, LIGHTEST_DENSITY_KG_M3)
    cup = dataclasses.replace(settings.suction, safety_factor=1.0, density_kg_m3=lightest)
    return dataclasses.replace(settings, suction=cup)
