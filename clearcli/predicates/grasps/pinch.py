"""The thesis's pinch: from above, the fingers closing across the object's narrow side.

Its poses are `clearcli.geometry.poses.grasp_geometry`'s, each as the gripper yaw the
neighbours block least (`least_blocked_grasps`); its blockers ``block_grasp`` (thesis
4.4.1: the open gripper at the grasp pose hits them, or they reach into the region its
fingers close over, `block_grasp_pairs`); not offered, the static ``ungraspable``, when
the object is wider than the gripper opens or narrower than it closes across the
closing direction (`ungraspable`). Its action is the shipped domain's ``grasp``
(clearcli/data/domain.pddl), and its poses and width are the object model's own
``grasp_candidates`` and ``grasp_width_m``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from clearcli.geometry.gripper import GripperModel, gripper_model
from clearcli.geometry.poses import GraspGeometry, grasp_geometry
from clearcli.predicates.grasps.base import KindFacts, KindModule, Offer, Scene, SimWorld
from clearcli.predicates.relations import _allowed, _grasp_hits, _with_fallbacks, grasp_opening_m

if TYPE_CHECKING:
    from clearcli.geometry.models import ObjectGeometry
    from clearcli.predicates.state import ObjectModel
    from clearcli.settings import Settings


def block_grasp_pairs(
    objects: Sequence[ObjectGeometry],
    grasps: Sequence[GraspGeometry],
    gripper: GripperModel,
    exclude: set[tuple[int, int]],
    clearance_m: float = 0.0,
) -> set[tuple[int, int]]:
    """(a, b): the open gripper at b's grasp pose collides with a, or a reaches into the
    closing region between its fingers (thesis 4.4.1, plus the squeeze)."""
    if not objects:
        return set()
    poses = np.stack([g.T_grasp for g in grasps])
    openings = [grasp_opening_m(g.width_m, gripper, clearance_m) for g in grasps]
    hits = _grasp_hits(gripper, poses, openings, objects, _allowed(len(objects), exclude))
    return {(a, b) for b, a in hits}


def least_blocked_grasps(
    objects: Sequence[ObjectGeometry],
    grasps: Sequence[GraspGeometry],
    gripper: GripperModel,
    exclude: set[tuple[int, int]],
    clearance_m: float = 0.0,
) -> list[GraspGeometry]:
    """Each grasp as the gripper yaw (the grasp or one of its ``alternatives``) whose
    open gripper hits the fewest other objects, the first on ties. The gripper turns
    about its approach at will, so a neighbour that blocks one yaw need not block the
    grasp; the planning model has no disjunction, so the least blocked yaw stands for
    the grasp (its blocking facts), and the IK check sees its candidates first, then
    those of the yaws no more blocked (`relations._with_fallbacks`)."""
    allowed = _allowed(len(objects), exclude)
    out = []
    for b, grasp in enumerate(grasps):
        options = (dataclasses.replace(grasp, alternatives=()), *grasp.alternatives)
        if len(options) > 1:
            poses = np.stack([g.T_grasp for g in options])
            openings = [grasp_opening_m(g.width_m, gripper, clearance_m) for g in options]
            hits = _grasp_hits(gripper, poses, openings, objects, np.repeat(allowed[b : b + 1], len(options), axis=0))
            out.append(_with_fallbacks(options, hits))
        else:
            out.append(options[0])
    return out


def ungraspable(grasps: Sequence[GraspGeometry], gripper: GripperModel, margin_m: float = 0.0) -> set[int]:
    """Objects wider than the opening, or narrower than the closing width, across the
    closing direction of their grasp, by more than ``margin_m`` (the modelled width's
    error: an object within it is tried, and the grasp's outcome tells)."""
    s = gripper.settings
    return {
        i
        for i, g in enumerate(grasps)
        if g.width_m > s.opening_width_m + margin_m or g.width_m < s.closing_width_m - margin_m
    }


class PinchGrasp(KindModule):
    name = "pinch"
    label = "grasp"
    facts = KindFacts("grasp", "", "block_grasp", "ik_unfeasible_grasp", 1, unoffered="ungraspable")
    thesis = True
    instead = "the pinch from above fits it"

    def offers(self, scene: Scene, gripper: GripperModel, settings: Settings) -> list[Offer]:
        """Every object gets its poses (an ungraspable one too: the object model keeps
        them, and its blockers, as the thesis's facts do); not offered when too wide or
        narrow (``detail["width_m"]``: the width across the closing direction)."""
        ps = settings.predicates
        geoms = list(scene.objects)
        grasps = [
            grasp_geometry(g, gripper, settings.push, ps.max_grasp_tilt_deg, ps.grasp_offcentre_fraction) for g in geoms
        ]
        # the gripper yaw of each grasp that the neighbours block least
        grasps = least_blocked_grasps(geoms, grasps, gripper, scene.exclude, ps.grasp_opening_clearance_m)
        blockers: list[set[int]] = [set() for _ in geoms]
        for a, b in block_grasp_pairs(geoms, grasps, gripper, scene.exclude, ps.grasp_opening_clearance_m):
            blockers[b].add(a)
        refused = ungraspable(grasps, gripper, ps.grasp_width_margin_m)
        return [
            Offer(
                candidates=tuple(g.candidates),
                blockers=frozenset(blockers[i]),
                why_not="too wide or narrow for the gripper" if i in refused else "",
                detail={"width_m": float(g.width_m)},
            )
            for i, g in enumerate(grasps)
        ]

    def candidates(self, obj: ObjectModel) -> tuple[tuple[np.ndarray, ...], ...]:
        return tuple(obj.grasp_candidates)

    def pddl_action(self, blocks: Sequence[str]) -> str:
        return ""  # the shipped domain's grasp (clearcli/data/domain.pddl)

    def world_holds(self, obj: Any, gripper: Any, rules: Any) -> bool:
        return not rules.truly_ungraspable(obj, gripper.opening_width_m, gripper.closing_width_m)

    def simulate(self, world: SimWorld) -> str:
        """The world closes the fingers on what lies between them, not on what the
        planner meant: two objects merged into one segment are both in there. The robot
        opens the gripper as the planner's rule says (`relations.grasp_opening_m`)."""
        rules, gripper, model = world.rules, world.gripper, world.model
        held, closing, opening = None, None, gripper.opening_width_m
        T_camera_grasp = world.chosen_pose(model.grasp_candidates)
        if T_camera_grasp is not None:
            T = world.T_table_camera @ T_camera_grasp
            tips_z = float(T[2, 3]) - gripper.closing_region_height_m / 2.0
            clearance = world.settings.predicates.grasp_opening_clearance_m
            opening = grasp_opening_m(float(model.grasp_width_m), gripper_model(gripper), clearance)
            closing = T[:2, 0] / max(float(np.linalg.norm(T[:2, 0])), 1e-12)
            held = rules.grasp_contacts(
                world.scene, T[:3, 3], T[:3, 0], opening, gripper.finger_width_m, tips_z, gripper.finger_thickness_m
            )
        if held is not None and len(held) > 1:
            return (
                "closed on "
                + ", ".join(str(world.scene.objects[i].object_id) for i in held)
                + " at once: nothing taken"
            )
        if held is not None and not held:
            return "missed: nothing between the fingers"
        if held:
            world.aim(held[0])
        # the width the closing fingers square the object to: its side nearest the
        # closing direction (a box's) or its diameter
        across = rules.aligned_width(world.scene.objects[world.k], closing) if closing is not None else 0.0
        if across > opening:
            return f"the fingers, open {opening:.3f} m, came down on it ({across:.3f} m across)"
        world.scene, outcome = rules.world_grasp(
            world.scene, world.k, gripper.opening_width_m, world.rng, world.params, gripper.closing_width_m
        )
        return outcome


KIND = PinchGrasp()
