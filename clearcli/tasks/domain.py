"""`domain`: the lifted PDDL domain the plans are for."""

from __future__ import annotations


def domain_text(clearance_costs: bool = False) -> str:
    from clearcli.planning.pddl import domain_text as text

    return text(clearance_costs=clearance_costs)
