"""Not a task: `domain` reads no frame. The lifted PDDL domain the plans are for, with the
actions of the grasp kinds asked for: a text the command prints or writes."""

from __future__ import annotations

from clearcli.planning.pddl import domain_text as text
from clearcli.predicates.grasps import parse_kinds


def domain_text(clearance_costs: bool = False, grasps: str = "pinch") -> str:
    """The domain with the actions of the grasp kinds in ``grasps`` ("pinch,rim"):
    a bad list is a SettingsError (one line, exit 3)."""
    return text(clearance_costs=clearance_costs, kinds=parse_kinds(grasps))
