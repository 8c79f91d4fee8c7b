"""The grasp kinds' protocol and the values they share.

A grasp kind takes an object off the table in its own way: the thesis's pinch from
above across the narrow side (`pinch`), a container's rim straddled by the fingers
(`rim`), a flat object slid to the table's edge and pinched where it overhangs
(`slide`). Each is one module with one object (``KIND``) implementing `GraspKind`, and
one entry of the registry (clearcli/settings/kinds.py). The object says everything the
layers above need of it:

* its name, label (reasons, pictures) and action cost (cheaper = surer, preferred);
* the facts it adds to the state (`KindFacts`: a static "offered" fact, its own blocking
  predicate, computed like the thesis's ``block_grasp``/``block_dir`` against the volumes
  that kind sweeps, and its own IK fact learnt by backtracking), from its `offers`;
* how a push of its object affects it (``push_clears_ik``, ``push_clears_blocks``,
  ``after_push``): the domain text, the SAS+ compiler and the planner's progression all
  read these flags, so they cannot disagree;
* its PDDL action (`pddl_action`), made from the same flags;
* its candidate poses in the object model (`candidates`), and the path a picture draws;
* what the simulated world does with it (`world_holds`, `simulate`), on the world's own
  rules, which `clearcli.sim` lends it (`SimWorld`): this package sits below the sim.

A kind that is not offered for an object says why (the object's reason).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

if TYPE_CHECKING:
    from clearcli.geometry.gripper import GripperModel
    from clearcli.geometry.models import ObjectGeometry, TableFrame
    from clearcli.predicates.state import ObjectModel
    from clearcli.settings import Settings


@dataclass(frozen=True)
class KindFacts:
    """The names a kind uses in the domain (``pinch`` keeps the thesis's)."""

    action: str  # PDDL action name: grasp | grasp_rim | slide_grasp
    offered: str  # static fact: the kind is offered for ?o ("" = offered unless `unoffered`)
    block: str  # blocking fact (?x blocks this kind's grasp of ?o)
    ik: str  # IK fact learnt by backtracking
    cost: int  # action cost: cheaper = surer, preferred
    unoffered: str = ""  # static fact: the kind is NOT offered for ?o (the pinch's ungraspable)

    def static(self) -> tuple[str, ...]:
        """The static facts it uses (one of offered / unoffered)."""
        return tuple(f for f in (self.offered, self.unoffered) if f)

    def offered_in(self, facts: Any, obj: str) -> bool:
        """Is the kind offered for ``obj`` by the static facts ``facts``?"""
        if self.offered:
            return (self.offered, obj) in facts
        return not self.unoffered or (self.unoffered, obj) not in facts


@dataclass(frozen=True, eq=False)
class Offer:
    """One kind's grasp of one object (table frame), or why there is none."""

    candidates: tuple[tuple[np.ndarray, ...], ...] = ()  # pose sequences T_table_gripper
    blockers: frozenset[int] = frozenset()  # indices of the objects in the way
    why_not: str = ""  # non-empty: not offered, and why
    detail: dict[str, Any] | None = None  # what the JSON tells (rim, slide path)
    # a grasp that first moves the object along the table (a slide): that translation
    slide_translation: np.ndarray | None = None


@dataclass(frozen=True)
class Scene:
    """What every kind may look at (table frame)."""

    objects: Sequence[ObjectGeometry]
    points_table: Sequence[np.ndarray]  # each object's points, table frame
    openings: Sequence[Any]  # perception.openings.Opening per object
    edges_table: Sequence[tuple[np.ndarray, np.ndarray, bool, str]]  # (a, b, seen, why)
    exclude: set[tuple[int, int]]  # (a, b) related by `on`: never block each other
    touching: set[tuple[int, int]]
    tf: TableFrame
    # the kinds before this one in preference order, each with the objects it is offered
    # for: a kind may leave to them what they take (the slide does)
    offered_before: tuple[tuple[GraspKind, frozenset[int]], ...] = ()
    # (a, b): a stands on (or inside) b, so b is taken after a: what b's top shows where
    # a stands is a's, not a hole in b
    on: frozenset[tuple[int, int]] = frozenset()
    # object index -> the faces a kind with faces must not use (a closed loop's memory:
    # a cup that did not seal on that face)
    avoid_faces: Mapping[int, frozenset[str]] = field(default_factory=dict)


class SimWorld(Protocol):
    """What the simulated world (`clearcli.sim.episode`) lends a kind's `simulate`: the
    scene as it truly is, the world's own rules (``rules``: `clearcli.sim.physics`, never
    the planner's model), the first action's object and how the arm went there."""

    scene: Any  # clearcli.sim.scene.Scene; a kind's simulate replaces it by what it leaves
    k: int  # index of the action's object in scene.objects
    object_id: int  # its world id (the action's label and record)
    model: ObjectModel  # the planner's model of it
    gripper: Any  # settings.gripper
    settings: Settings
    rng: np.random.Generator
    params: Any  # settings.world (WorldParams)
    rules: Any  # clearcli.sim.physics
    T_table_camera: np.ndarray

    def aim(self, k: int) -> None:
        """The action acts on scene.objects[k] instead (what the fingers truly met)."""
        ...

    def take(self) -> None:
        """scene.objects[k] is taken off the table."""
        ...

    def chosen_pose(self, candidates: Any, pose: int = 1, candidate: int = 0) -> np.ndarray | None:
        """The ``pose``-th pose (camera frame) of the candidate the IK check chose, else of
        ``candidates[candidate]``; None without either."""
        ...

    def chosen_candidate(self) -> int | None:
        """Which candidate the IK check chose (None when it checked none)."""
        ...


class GraspKind(Protocol):
    """One grasp kind (see the module's docstring)."""

    name: str  # as [plan] grasps, --grasps and the JSON's grasp_kind say it
    label: str  # in reasons and the plan's left objects: "grasp", "rim grasp", ...
    facts: KindFacts  # its PDDL names and cost
    # the thesis's own grasp: the shipped domain file holds its action, its poses are the
    # object model's grasp_candidates, its width grasp_width_m
    thesis: bool
    # when a later kind leaves an object to this one: the later kind's reason
    instead: str
    # a push of its object: deletes the object's IK fact of this kind (it may be
    # reachable where it ends up); deletes what blocks this kind's grasp of it
    push_clears_ik: bool
    push_clears_blocks: bool
    # "" when its poses move with a pushed object; else why it has none after a push
    after_push: str
    # its object must stand on nothing (slid along the table)
    on_table: bool
    # a try that failed and left the object where it stood meets the same again: the
    # closed loop gives the kind up on that object at once (a slide that moved nothing)
    give_up_unmoved: bool
    # the faces of an object it may take it by (its Offer's detail names the one
    # chosen); a try that failed on one face is tried again on the others before the
    # kind is given up, and what failed stays with the object when it is pushed (a
    # porous top is porous wherever it stands). () : one way only
    faces: tuple[str, ...]

    def offers(self, scene: Scene, gripper: GripperModel, settings: Settings) -> list[Offer]:
        """One Offer per object of ``scene`` (the kind's poses, its blockers, or why not)."""
        ...

    def candidates(self, obj: ObjectModel) -> tuple[tuple[np.ndarray, ...], ...]:
        """Its pose sequences T_camera_gripper in the object model."""
        ...

    def pddl_action(self, blocks: Sequence[str]) -> str:
        """Its action in the lifted domain ("" for the thesis's: the file holds it);
        ``blocks``: every blocking predicate of the other kinds in the domain, which its
        effect deletes for the object taken, as the thesis's grasp deletes its own."""
        ...

    def moved_before(self, obj: ObjectModel) -> np.ndarray | None:
        """The translation (sensor frame) it moves the object by before it grasps it
        (a picture draws it), or None."""
        ...

    def world_holds(self, obj: Any, gripper: Any, rules: Any) -> bool:
        """By the simulated world's own rules (``rules``: clearcli.sim.physics), can this
        kind take the world object ``obj`` at all? (`physics.truly_ungraspable_by`)"""
        ...

    def simulate(self, world: SimWorld) -> str:
        """Carry the grasp out in the simulated world; the outcome ("removed", or what
        went wrong)."""
        ...


UP = np.array([0.0, 0.0, 1.0])


class KindModule:
    """Defaults every kind's object may take: a kind beyond the thesis's, whose push
    clears its IK fact and its blocks (its poses move with the object), offered to any
    object, its candidates the object model's ``kind_candidates[name]``."""

    name = ""
    label = ""
    facts: KindFacts
    thesis = False
    instead = ""
    push_clears_ik = True
    push_clears_blocks = True
    after_push = ""
    on_table = False
    give_up_unmoved = False
    faces: tuple[str, ...] = ()

    def candidates(self, obj: ObjectModel) -> tuple[tuple[np.ndarray, ...], ...]:
        return tuple(obj.kind_candidates.get(self.name, ()))

    def moved_before(self, obj: ObjectModel) -> np.ndarray | None:
        return None

    def pddl_action(self, blocks: Sequence[str]) -> str:
        """As the pinch's ``grasp`` is written: offered by its static fact, blocked by its
        own blocking predicate, ruled out by its own IK fact; its effect the grasp's (the
        object removed, every fact in which it blocks or stands on another deleted), its
        cost its own."""
        f = self.facts
        under = "\n      (not (exists (?x - obj) (on ?o ?x)))" if self.on_table else ""
        effect_dels = "".join(f"\n             (not ({b} ?o ?x))" for b in blocks)
        return f"""
  (:action {f.action}
    :parameters (?o - obj)
    :precondition (and
      (not (removed ?o))
      ({f.offered} ?o)
      (not ({f.ik} ?o))
      (not (exists (?x - obj) (on ?x ?o))){under}
      (not (exists (?x - obj) ({f.block} ?x ?o))))
    :effect (and
      (removed ?o)
      (forall (?x - obj ?e - direction)
        (and (not (on ?o ?x))
             (not (block_grasp ?o ?x))
             (not (block_dir ?o ?x ?e)){effect_dels}))
      (increase (total-cost) {f.cost})))
"""
