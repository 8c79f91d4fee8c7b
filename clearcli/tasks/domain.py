"""`domain`: the lifted PDDL domain the plans are for."""

from __future__ import annotations


def domain_text(clearance_costs: bool = False, grasps: str = "pinch") -> str:
    """The domain with the actions of the grasp kinds in ``grasps`` ("pinch,rim"):
    a bad list is a SettingsError (one line, exit 3)."""
    from clearcli.planning.pddl import domain_text as text
    from clearcli.predicates.grasps import parse_kinds

    return text(clearance_costs=clearance_costs, kinds=parse_kinds(grasps))
