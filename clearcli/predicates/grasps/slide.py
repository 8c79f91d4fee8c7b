"""Slide to the table's edge, then pinch: for a flat object too wide for every grasp
from above (a book, a flat box, a plate).

The object is pushed, as a push of the thesis is (closed fingers behind it, the
fingertips ``[push] fingertips_above_table_m`` above the table), straight towards the
nearest side of the table the camera sees end (`clearcli.perception.openings.seen_edges`)
until it overhangs that side by ``SLIDE_OVERHANG_M``; then the gripper comes from beyond
the edge, level with the table, its fingers above and below the overhang (the lower one
below the table's top, ``SLIDE_EDGE_CLEARANCE_M`` short of the edge), closes across the
object's thickness and lifts. One candidate: the side that needs the shortest slide.

Offered when the object is too wide for the pinch, has no rim grasp, is thin enough for
the opening (its height and ``SLIDE_CLEARANCE_M`` on either side) and no thinner than the
gripper closes, a seen side is long enough to take it, and the overhang leaves its
centre over the table by ``SLIDE_KEEP_ON_M`` (or it tips off). Its blockers
(``block_slide``): what its swept volume meets along the slide, what the closed gripper
behind it meets at the start (as ``block_dir``), and what the open gripper at the edge
meets. A side seen only as the image's border, or a wall or an object beyond it, is no
edge: the object's reason says so.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from clearcli.predicates.grasps.base import KindFacts, Offer, Scene

if TYPE_CHECKING:
    from clearcli.geometry.gripper import GripperModel
    from clearcli.settings import Settings

SLIDE_OVERHANG_M = 0.035
SLIDE_EDGE_CLEARANCE_M = 0.005
SLIDE_CLEARANCE_M = 0.005
SLIDE_KEEP_ON_M = 0.01
SLIDE_MAX_M = 0.6
# how far below the horizontal the edge pinch approaches (deg): level, none of the wam,
# panda and ur5e reached a pose 1.5 cm above the table beyond its edge; 45: all three
SLIDE_TILT_DEG = 45.0
UP = np.array([0.0, 0.0, 1.0])


class SlideGrasp:
    name = "slide"

    @property
    def facts(self) -> KindFacts:
        from clearcli.predicates.grasps import KIND_FACTS

        return KIND_FACTS["slide"]

    def offers(self, scene: Scene, gripper: "GripperModel", settings: "Settings") -> list[Offer]:
        from clearcli.geometry.poses import PushGeometry, _pose, _push_sequence
        from clearcli.predicates import relations as rel

        g = gripper.settings
        push = settings.push
        n = len(scene.objects)
        seen = [(a[:2], b[:2]) for a, b, ok, _ in scene.edges_table if ok]
        why_unseen = sorted({why for *_, ok, why in scene.edges_table if not ok})
        table_mid = (
            np.mean([a[:2] for a, *_ in scene.edges_table], axis=0) if scene.edges_table else np.zeros(2)
        )
        offers: list[Offer | None] = [None] * n
        plans: dict[int, tuple[np.ndarray, float, tuple[np.ndarray, ...], float]] = {}
        for i, obj in enumerate(scene.objects):
            if i not in scene.ungraspable:
                offers[i] = Offer(why_not="the pinch from above fits it")
                continue
            if i in scene.rim_offered:
                offers[i] = Offer(why_not="its rim is grasped instead")
                continue
            thick = float(obj.top_height_m)
            if thick + 2.0 * SLIDE_CLEARANCE_M > g.opening_width_m:
                offers[i] = Offer(why_not=f"{thick:.3f} m thick: too thick to pinch at the edge (the gripper opens to {g.opening_width_m:.3f} m)")
                continue
            if thick < g.closing_width_m:
                offers[i] = Offer(why_not=f"{thick:.3f} m thick: thinner than the gripper closes")
                continue
            if not seen:
                offers[i] = Offer(why_not="no side of the table is seen to end (" + "; ".join(why_unseen) + ")")
                continue
            fp = np.asarray(obj.footprint, dtype=float)
            best: tuple[float, np.ndarray, float, np.ndarray] | None = None
            why = "no seen side of the table is long enough to take it"
            for a, b in seen:
                length = float(np.linalg.norm(b - a))
                along = (b - a) / length
                out_dir = np.array([along[1], -along[0]])
                if out_dir @ (a - table_mid) < 0:
                    out_dir = -out_dir
                lat = fp @ along - a @ along
                if lat.min() < 0.01 or lat.max() > length - 0.01:
                    continue
                proj = fp @ out_dir
                extent = float(proj.max() - proj.min())
                if SLIDE_OVERHANG_M > extent / 2.0 - SLIDE_KEEP_ON_M:
                    why = f"{extent:.3f} m long towards the edge: too short to overhang {SLIDE_OVERHANG_M:.3f} m without tipping"
                    continue
                dist = float(a @ out_dir - proj.max() + SLIDE_OVERHANG_M)
                if dist > SLIDE_MAX_M:
                    why = f"the nearest seen edge is {dist:.2f} m away"
                    continue
                dist = max(dist, 0.0)
                if best is None or dist < best[0]:
                    best = (dist, out_dir, float(a @ out_dir), along)
            if best is None:
                offers[i] = Offer(why_not=why)
                continue
            dist, out_dir, edge_at, along = best
            d3 = np.array([out_dir[0], out_dir[1], 0.0])
            c = np.asarray(obj.center, dtype=float).copy()
            c[2] = 0.0
            rear = float((fp @ out_dir).min())
            lateral = c - (c @ d3) * d3
            # the push part: closed fingers behind the object, closing along the slide
            steps_n = max(1, math.ceil(max(dist, 1e-3) / push.path_resolution_m - 1e-9))
            translations = (max(dist, 1e-3) * np.arange(1, steps_n + 1) / steps_n)[:, None] * d3[None, :]
            half_along = gripper.finger_half_extent_along_x(closed=True)
            start = lateral + (rear - push.gripper_behind_m - half_along) * d3
            start[2] = push.fingertips_above_table_m + g.closing_region_height_m / 2.0
            push_seq = _push_sequence(d3, start, push.approach_m * UP, translations, steps_n)[0]
            # the pinch at the edge: from beyond it and above, the approach tilted
            # SLIDE_TILT_DEG below the horizontal (level, no arm here reached it: the
            # wrist would be at the table's height), closing in the vertical plane of the
            # slide; the fingertips SLIDE_EDGE_CLEARANCE_M short of the edge, at the
            # object's mid-height, the lower finger out beyond the edge
            half = g.closing_region_height_m / 2.0
            tilt = math.radians(SLIDE_TILT_DEG)
            approach = -math.cos(tilt) * d3 - math.sin(tilt) * UP
            tip = lateral + (edge_at + SLIDE_EDGE_CLEARANCE_M) * d3
            tip[2] = thick / 2.0
            point = tip - half * approach
            x = np.cross(np.cross(UP, d3), approach)  # in the vertical plane through d3
            x /= np.linalg.norm(x)
            T = _pose(x, approach, point)
            pre, lift = T.copy(), T.copy()
            pre[:3, 3] -= push.approach_m * approach
            lift[:3, 3] += push.approach_m * UP
            seq = tuple(push_seq) + (pre, T, lift)
            geometry = PushGeometry("slide", d3, dist, translations, (tuple(push_seq),))
            plans[i] = (d3 * dist, dist, seq, thick)
            offers[i] = Offer(
                candidates=(seq,),
                detail={
                    "direction": d3.tolist(),
                    "slide_m": float(dist),
                    "overhang_m": SLIDE_OVERHANG_M,
                    "edge": [float(edge_at)],
                    "thickness_m": thick,
                },
                slide_translation=d3 * dist,
            )
            offers[i] = _with_geometry(offers[i], geometry, T, thick)  # type: ignore[arg-type]
        # blockers: the swept volume and the pusher (as block_dir), the open gripper at the edge
        if plans:
            keys = sorted(plans)
            pushes = [{"slide": offers[i].detail["_geometry"]} if i in plans else {} for i in range(n)]  # type: ignore[union-attr,index]
            triples = rel.block_dir_triples(list(scene.objects), pushes, gripper, scene.exclude, scene.touching, settings.predicates.touching_block_angle_deg)
            blockers: dict[int, set[int]] = {i: set() for i in keys}
            for a, b, _ in triples:
                blockers[b].add(a)
            allowed = rel._allowed(n, scene.exclude)
            poses = np.stack([offers[i].detail["_edge_pose"] for i in keys])  # type: ignore[union-attr,index]
            openings = [min(g.opening_width_m, plans[i][3] + 2.0 * SLIDE_CLEARANCE_M) for i in keys]
            for p, a in rel._grasp_hits(gripper, poses, openings, list(scene.objects), allowed[keys]):
                blockers[keys[p]].add(a)
            for i in keys:
                o = offers[i]
                assert o is not None and o.detail is not None
                detail = {k: v for k, v in o.detail.items() if not k.startswith("_")}
                offers[i] = Offer(o.candidates, frozenset(blockers[i]), "", detail, o.slide_translation)
        return [o if o is not None else Offer(why_not="not modelled") for o in offers]


def _with_geometry(offer: Offer, geometry: object, T_edge: np.ndarray, thick: float) -> Offer:
    detail = dict(offer.detail or {})
    detail["_geometry"] = geometry
    detail["_edge_pose"] = T_edge
    return Offer(offer.candidates, offer.blockers, offer.why_not, detail, offer.slide_translation)


SLIDE = SlideGrasp()
