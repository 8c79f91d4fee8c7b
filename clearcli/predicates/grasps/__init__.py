"""Grasp kinds: a protocol (base.py), one module per kind (pinch.py, rim.py, slide.py),
each with one object ``KIND``, and the registry (clearcli/settings/kinds.py, read by
registry.py) that lists them in preference order: the pinch (the thesis's, cheapest and
surest), then the rim of an open container, then the slide to the table's edge.
``[plan] grasps`` chooses which the planner may use; ``pinch`` alone is the thesis's
behaviour exactly.

A new kind is its module and one registry entry; nothing else names it.
"""

from __future__ import annotations

from clearcli.predicates.grasps.base import GraspKind, KindFacts, KindModule, Offer, Scene, SimWorld
from clearcli.predicates.grasps.registry import kind, kind_names, kind_of_action, kinds, parse_kinds

__all__ = [
    "GraspKind",
    "KindFacts",
    "KindModule",
    "Offer",
    "Scene",
    "SimWorld",
    "kind",
    "kind_names",
    "kind_of_action",
    "kinds",
    "parse_kinds",
]
