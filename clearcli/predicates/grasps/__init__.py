"""Grasp kinds: a protocol (base.py), one module per kind, and this registry.

Order is preference: the pinch (the thesis's, cheapest and surest), then the rim of an
open container, then the slide to the table's edge. ``[plan] grasps`` chooses which
the planner may use; ``pinch`` alone is the thesis's behaviour exactly.
"""

from __future__ import annotations

from clearcli.errors import SettingsError
from clearcli.predicates.grasps.base import GraspKind, KindFacts, Offer, Scene

# name -> the facts of its PDDL action (the pinch's are the thesis's own)
KIND_FACTS: dict[str, KindFacts] = {
    "pinch": KindFacts("grasp", "", "block_grasp", "ik_unfeasible_grasp", 1),
    "rim": KindFacts("grasp_rim", "rim_graspable", "block_rim", "ik_unfeasible_rim", 2),
    "slide": KindFacts("slide_grasp", "slidable", "block_slide", "ik_unfeasible_slide", 3),
}
KIND_NAMES: tuple[str, ...] = tuple(KIND_FACTS)
EXTRA_KINDS: tuple[str, ...] = KIND_NAMES[1:]  # offered by the modules below


def kind_module(name: str) -> GraspKind:
    """The kind's implementation (imported when first needed)."""
    if name == "rim":
        from clearcli.predicates.grasps.rim import RIM

        return RIM
    if name == "slide":
        from clearcli.predicates.grasps.slide import SLIDE

        return SLIDE
    raise SettingsError(f"settings: no grasp kind {name!r} with its own module; known: {', '.join(EXTRA_KINDS)}")


def parse_kinds(text: str) -> tuple[str, ...]:
    """"rim,pinch" -> ("pinch", "rim"); one line SettingsError for anything else: the
    rule of [plan] grasps itself (`clear domain --grasps` and the settings agree)."""
    from clearcli.settings.fields import range_of, set_of_names
    from clearcli.settings.plan import PlanSettings

    canonical = set_of_names(f"settings: [plan] grasps = {text!r}", text, range_of(PlanSettings, "grasps"))
    return tuple(canonical.split(","))


def kind_of_action(action_name: str) -> str:
    for k, f in KIND_FACTS.items():
        if f.action == action_name:
            return k
    raise KeyError(action_name)


__all__ = ["EXTRA_KINDS", "GraspKind", "KIND_FACTS", "KIND_NAMES", "KindFacts", "Offer", "Scene", "kind_module", "kind_of_action", "parse_kinds"]
