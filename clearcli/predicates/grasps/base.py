"""The grasp kinds' protocol and the values they share.

A grasp kind takes an object off the table in its own way: the thesis's pinch from
above across the narrow side (`pinch`), a container's rim straddled by the fingers
(`rim`), a flat object slid to the table's edge and pinched where it overhangs
(`slide`). Each is one PDDL action with its own static "offered" fact, its own
blocking predicate (computed like the thesis's ``block_grasp``/``block_dir``, against
the volumes that kind sweeps) and its own IK fact; the planner prefers the cheapest by
action cost. A kind that is not offered for an object says why (the object's reason).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, Sequence

import numpy as np

if TYPE_CHECKING:
    from clearcli.geometry.gripper import GripperModel
    from clearcli.geometry.models import ObjectGeometry, TableFrame
    from clearcli.settings import Settings


@dataclass(frozen=True)
class KindFacts:
    """The names a kind uses in the domain (``pinch`` keeps the thesis's)."""

    action: str  # PDDL action name: grasp | grasp_rim | slide_grasp
    offered: str  # static fact: the kind is offered for ?o ("" = offered unless ungraspable)
    block: str  # blocking fact (?x blocks this kind's grasp of ?o)
    ik: str  # IK fact learnt by backtracking
    cost: int  # action cost: cheaper = surer, preferred


@dataclass(frozen=True, eq=False)
class Offer:
    """One kind's grasp of one object (table frame), or why there is none."""

    candidates: tuple[tuple[np.ndarray, ...], ...] = ()  # pose sequences T_table_gripper
    blockers: frozenset[int] = frozenset()  # indices of the objects in the way
    why_not: str = ""  # non-empty: not offered, and why
    detail: dict[str, Any] | None = None  # what the JSON tells (rim, slide path)
    # a slide: the object's translation along the table before the pinch (table frame)
    slide_translation: np.ndarray | None = None


@dataclass(frozen=True)
class Scene:
    """What every kind may look at (table frame)."""

    objects: Sequence["ObjectGeometry"]
    points_table: Sequence[np.ndarray]  # each object's points, table frame
    openings: Sequence[Any]  # perception.openings.Opening per object
    edges_table: Sequence[tuple[np.ndarray, np.ndarray, bool, str]]  # (a, b, seen, why)
    exclude: set[tuple[int, int]]  # (a, b) related by `on`: never block each other
    touching: set[tuple[int, int]]
    ungraspable: set[int]  # the pinch's verdict
    tf: "TableFrame"
    rim_offered: frozenset[int] = frozenset()  # objects a rim grasp is offered for


class KindModule:
    """What every kind's module shares: its name, and its facts from the registry."""

    name = ""

    @property
    def facts(self) -> KindFacts:
        from clearcli.predicates.grasps import KIND_FACTS

        return KIND_FACTS[self.name]


class GraspKind(Protocol):
    name: str
    facts: KindFacts

    def offers(self, scene: Scene, gripper: "GripperModel", settings: "Settings") -> list[Offer]:
        """One Offer per object of ``scene`` (the kind's poses, its blockers, or why not)."""
        ...
