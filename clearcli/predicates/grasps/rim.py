"""The rim grasp of an open container: the fingers straddle its wall at the rim.

Approach straight down over a point of the rim; the closing direction radial (across
the wall); the fingers open to the wall's thickness and ``RIM_CLEARANCE_M`` on either
side; the fingertips ``RIM_GRIP_DEPTH_M`` below the rim (or less where the finger is
shorter), the closing point half the closing region above them. Eight points around
the rim are candidates; the neighbours each one's open gripper would hit (its boxes and
the closing region, as for the pinch's ``block_grasp``) are its blockers; the planner
gets the candidates that are blocked least, and their blockers as ``block_rim`` facts.
What stands inside the container is ``on`` it and goes first (the domain says so), so
the inner finger meets nothing there once the grasp is planned.

Offered when segmentation saw a rim (`clearcli.perception.openings`), the gripper
closes across the wall (its fully closed gap, ``[gripper] closed_gap_m``, is narrower
than the wall: the WAM's IRI gripper stops at 3 cm and cannot), opens to it, the inner
finger fits inside the rim and the inside is seen deep enough for the fingertips.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from clearcli.geometry.poses import _pose
from clearcli.predicates import relations as rel
from clearcli.predicates.grasps.base import KindFacts, KindModule, Offer, Scene, SimWorld

if TYPE_CHECKING:
    from clearcli.geometry.gripper import GripperModel
    from clearcli.settings import Settings

RIM_CLEARANCE_M = 0.006
RIM_GRIP_DEPTH_M = 0.02
RIM_N_POINTS = 8
UP = np.array([0.0, 0.0, 1.0])


class RimGrasp(KindModule):
    name = "rim"
    label = "rim grasp"
    facts = KindFacts("grasp_rim", "rim_graspable", "block_rim", "ik_unfeasible_rim", 2)
    instead = "its rim is grasped instead"

    def offers(self, scene: Scene, gripper: GripperModel, settings: Settings) -> list[Offer]:
        g = gripper.settings
        out: list[Offer] = []
        n = len(scene.objects)
        allowed = rel._allowed(n, scene.exclude) if n else np.zeros((0, 0), dtype=bool)
        for i in range(n):
            opening = scene.openings[i] if i < len(scene.openings) else None
            rim = getattr(opening, "rim", None)
            if rim is None:
                out.append(Offer(why_not=f"no rim: {getattr(opening, 'why', 'not an open container')}"))
                continue
            wall = float(rim.wall_m)
            gap = min(g.closed_gap_m, g.closing_width_m)
            if wall <= gap:
                out.append(Offer(why_not=f"its wall ({wall:.3f} m) is thinner than the gripper closes ({gap:.3f} m)"))
                continue
            opening_m = min(g.opening_width_m, wall + 2.0 * RIM_CLEARANCE_M)
            if wall + 0.002 > g.opening_width_m:
                out.append(Offer(why_not=f"its wall ({wall:.3f} m) is thicker than the gripper opens"))
                continue
            inner_r = rim.radius_m - wall / 2.0
            # the inner finger's far face from the axis, and the chord it needs there
            finger_far = rim.radius_m - opening_m / 2.0 - g.finger_thickness_m
            half_chord = math.sqrt(max(inner_r**2 - max(finger_far, 0.0) ** 2, 0.0))
            if finger_far < -inner_r + 0.005 or half_chord < g.finger_width_m / 2.0 + 0.002:
                out.append(Offer(why_not=f"the inner finger does not fit inside the rim ({2 * inner_r:.3f} m across)"))
                continue
            grip = min(RIM_GRIP_DEPTH_M, g.finger_depth_m - 0.005)
            if rim.inside_depth_m < grip + 0.005:
                out.append(
                    Offer(
                        why_not=f"the inside is seen only {rim.inside_depth_m:.3f} m deep (the fingers need {grip + 0.005:.3f} m)"
                    )
                )
                continue
            c = scene.tf.to_table(np.asarray(rim.center, dtype=float)[None])[0]
            half = g.closing_region_height_m / 2.0
            z_cp = rim.height_m - grip + half
            seqs, grasps = [], []
            for k in range(RIM_N_POINTS):
                a = 2.0 * math.pi * k / RIM_N_POINTS
                radial = np.array([math.cos(a), math.sin(a), 0.0])
                point = np.array([c[0], c[1], 0.0]) + rim.radius_m * radial
                point[2] = z_cp
                T = _pose(radial, -UP, point)
                pre, lift = T.copy(), T.copy()
                pre[:3, 3] += settings.push.approach_m * UP
                lift[:3, 3] += settings.push.approach_m * UP
                seqs.append((pre, T, lift))
                grasps.append(T)
            hits = rel._grasp_hits(
                gripper,
                np.stack(grasps),
                [opening_m] * len(grasps),
                scene.objects,
                np.repeat(allowed[i][None], len(grasps), axis=0),
            )
            by_pose: list[set[int]] = [set() for _ in grasps]
            for p, a in hits:
                by_pose[p].add(a)
            best = min(by_pose, key=len)
            keep = tuple(s for s, b in zip(seqs, by_pose) if b == best)
            out.append(
                Offer(
                    candidates=keep,
                    blockers=frozenset(best),
                    detail={
                        "center": c.tolist(),
                        "radius_m": float(rim.radius_m),
                        "height_m": float(rim.height_m),
                        "wall_m": wall,
                        "inside_depth_m": float(rim.inside_depth_m),
                        "opening_m": float(opening_m),
                    },
                )
            )
        return out

    def world_holds(self, obj: Any, gripper: Any, rules: Any) -> bool:
        """The world's rule: an open cylinder whose wall the fingers close on (thicker than
        the gripper's fully closed gap, at most its opening less 2 mm on either side) with
        room inside for a finger."""
        if not rules.open_container(obj):
            return False
        gap = min(float(getattr(gripper, "closed_gap_m", gripper.closing_width_m)), gripper.closing_width_m)
        room = obj.radius_m - obj.wall_m - gripper.finger_thickness_m
        return bool(gap < obj.wall_m <= gripper.opening_width_m - 0.004 and room >= 0.01)

    def simulate(self, world: SimWorld) -> str:
        """The world's fingers at the pose the arm went to (`physics.world_rim_grasp`)."""
        gripper = world.gripper
        detail = world.model.kind_details.get(self.name, {})
        T_camera_grasp = world.chosen_pose(world.model.kind_candidates.get(self.name, ()))
        if T_camera_grasp is None:
            return "missed: no rim pose"
        ok, why = world.rules.world_rim_grasp(
            world.scene,
            world.k,
            world.T_table_camera @ T_camera_grasp,
            float(detail.get("opening_m", gripper.opening_width_m)),
            gripper.finger_thickness_m,
            gripper.finger_width_m,
            gripper.finger_depth_m,
            fingertip_z_m=gripper.closing_region_height_m / 2.0,
        )
        if not ok:
            return f"rim grasp failed: {why}"
        world.take()
        return "removed"


KIND = RIM = RimGrasp()
