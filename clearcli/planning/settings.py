"""Planner settings (section [plan])."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class PlanSettings:
    time_limit_s: float = 30.0
    optimal_max_objects: int = 20
    max_backtracks: int = 200
