"""Helpers that several test modules share (from the tests of downward)."""

from __future__ import annotations

from clearcli.planning import solve as solving
from clearcli.settings.plan import PlanSettings


def solve(*args, **given):
    """`solving.solve` with [plan]'s search bounds unless the test gives its own."""
    p = PlanSettings()
    bounds = dict(
        time_limit_s=p.time_limit_s,
        optimal_max_objects=p.optimal_max_objects,
        optimal_time_s=p.optimal_time_s,
        anytime_time_s=p.anytime_time_s,
        formulation=p.formulation,
    )
    return solving.solve(*args, **{**bounds, **given})


def _names(n: int) -> list[str]:
    return [f"o{i}" for i in range(n)]
