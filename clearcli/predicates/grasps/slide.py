"""Slide to the table's edge, then pinch: for a flat object too wide for every grasp
from above (a book, a flat box, a plate).

The object is pushed, as a push of the thesis is (closed fingers behind it, the
fingertips ``[push] fingertips_above_table_m`` above the table), straight towards the
side of the table the camera sees end (`clearcli.perception.openings.seen_edges`)
until it overhangs that side by ``SLIDE_OVERHANG_M``; then the gripper comes from beyond
the edge, level with the table, its fingers above and below the overhang (the lower one
below the table's top, ``SLIDE_EDGE_CLEARANCE_M`` short of the edge), closes across the
object's thickness and lifts. One candidate per seen side, the shortest slide first;
the planner gets those blocked least (the IK check takes the first the arm reaches).

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
from typing import TYPE_CHECKING, Any

import numpy as np

from clearcli.geometry.poses import PushGeometry, _pose, _push_sequence
from clearcli.predicates import relations as rel
from clearcli.predicates.grasps.base import KindFacts, KindModule, Offer, Scene, SimWorld

if TYPE_CHECKING:
    from clearcli.geometry.gripper import GripperModel
    from clearcli.geometry.models import ObjectGeometry
    from clearcli.predicates.state import ObjectModel
    from clearcli.settings import Settings

SLIDE_OVERHANG_M = 0.035
SLIDE_EDGE_CLEARANCE_M = 0.005
SLIDE_CLEARANCE_M = 0.005
SLIDE_KEEP_ON_M = 0.01
SLIDE_MAX_M = 0.6
# how far below the horizontal the edge pinch approaches (deg): 45 where the slab fits the
# opening so (level, none of the wam, panda and ur5e reached a pose 1.5 cm above the table
# beyond its edge; from 45 all three did); a thicker slab spans thick / cos(tilt) across
# the fingers, so it is pinched from as steep a tilt as the opening allows, down to
# SLIDE_MIN_TILT_DEG (below it the wrist comes near the table's height)
SLIDE_TILT_DEG = 45.0
SLIDE_MIN_TILT_DEG = 20.0
UP = np.array([0.0, 0.0, 1.0])
# the simulated world: how much of a slid object's overhang its fingers need to hold it (m)
EDGE_GRIP_M = 0.025


class SlideGrasp(KindModule):
    name = "slide"
    label = "slide grasp"
    facts = KindFacts("slide_grasp", "slidable", "block_slide", "ik_unfeasible_slide", 3)
    # a slide is made for where the object stands, to one side of the table: a push
    # moves it out of the others' slide paths but tells nothing of its own slide (its
    # blocks and IK fact stay), and its poses do not move with it
    push_clears_ik = False
    push_clears_blocks = False
    after_push = "a slide is planned from where the object stands, not after a push"
    on_table = True  # slid along the table: nothing under it either
    # a slide that did not move the object met something the model did not: the same
    # slide would meet it again (a pinch that slips may hold the next time)
    give_up_unmoved = True

    def offers(self, scene: Scene, gripper: GripperModel, settings: Settings) -> list[Offer]:
        g = gripper.settings
        n = len(scene.objects)
        seen = [(a[:2], b[:2]) for a, b, ok, _ in scene.edges_table if ok]
        why_unseen = sorted({why for *_, ok, why in scene.edges_table if not ok})
        table_mid = np.mean([a[:2] for a, *_ in scene.edges_table], axis=0) if scene.edges_table else np.zeros(2)
        offers: list[Offer] = [Offer(why_not="not modelled")] * n
        # (object, its candidates: one per seen side it can be slid to, nearest first)
        cands: dict[int, list[dict[str, Any]]] = {}
        for i, obj in enumerate(scene.objects):
            # for what a kind before it takes (the pinch, a rim grasp): that one
            taken = next((kind.instead for kind, offered in scene.offered_before if i in offered), "")
            if taken:
                offers[i] = Offer(why_not=taken)
                continue
            thick = float(obj.top_height_m)
            tilt_deg = pinch_tilt_deg(thick, g.opening_width_m)
            if tilt_deg is None:
                least = _pinch_opening(thick, SLIDE_MIN_TILT_DEG)
                offers[i] = Offer(
                    why_not=f"{thick:.3f} m thick: too thick to pinch at the edge even from {SLIDE_MIN_TILT_DEG:.0f} deg "
                    f"below the horizontal (needs {least:.3f} m, the gripper opens to {g.opening_width_m:.3f} m)"
                )
                continue
            if thick < g.closing_width_m + SLIDE_CLEARANCE_M:
                # (the modelled height is the top's, noise included: 5 mm to be sure the
                # fingers close on it, as a failed slide leaves it at the edge)
                offers[i] = Offer(
                    why_not=f"{thick:.3f} m thick: too thin for the gripper to close on (it closes to {g.closing_width_m:.3f} m)"
                )
                continue
            if not seen:
                offers[i] = Offer(why_not="no side of the table is seen to end (" + "; ".join(why_unseen) + ")")
                continue
            found, why = [], "no seen side of the table is long enough to take it"
            for side_a, side_b in seen:
                plan, why_side = _slide_to(obj, side_a, side_b, table_mid)
                if plan is None:
                    why = why_side or why
                    continue
                found.append(_candidate(obj, plan, gripper, settings, tilt_deg))
            if not found:
                offers[i] = Offer(why_not=why)
                continue
            cands[i] = sorted(found, key=lambda c: c["slide_m"])
        if not cands:
            return offers
        # blockers of every candidate: its swept volume and the pusher behind it (as
        # block_dir: relations.block_dir_triples), and the open gripper at the edge
        keys = [(i, j) for i in sorted(cands) for j in range(len(cands[i]))]
        pushes: list[dict[str, PushGeometry]] = [{} for _ in range(n)]
        for i, j in keys:
            pushes[i][f"slide{j}"] = cands[i][j]["geometry"]
        blockers: dict[tuple[int, int], set[int]] = {k: set() for k in keys}
        triples = rel.block_dir_triples(
            list(scene.objects),
            pushes,
            gripper,
            scene.exclude,
            scene.touching,
            settings.predicates.touching_block_angle_deg,
        )
        for a, b, name in triples:
            blockers[(b, int(name[5:]))].add(a)
        allowed = rel._allowed(n, scene.exclude)
        poses = np.stack([cands[i][j]["T_edge"] for i, j in keys])
        openings = [
            min(g.opening_width_m, _pinch_opening(cands[i][j]["thickness_m"], cands[i][j]["tilt_deg"])) for i, j in keys
        ]
        rows = allowed[[i for i, _ in keys]]
        for p, a in rel._grasp_hits(gripper, poses, openings, list(scene.objects), rows):
            blockers[keys[p]].add(a)
        for i, found in cands.items():
            # the candidates blocked least, nearest first: the IK check takes the first
            # the arm reaches; their blockers are the object's block_slide facts
            sets = [blockers[(i, j)] for j in range(len(found))]
            best = min(sets, key=len)
            keep = [c for c, b in zip(found, sets) if b == best]
            first = keep[0]
            offers[i] = Offer(
                candidates=tuple(c["sequence"] for c in keep),
                blockers=frozenset(best),
                detail={
                    "direction": first["direction"].tolist(),
                    "slide_m": float(first["slide_m"]),
                    "overhang_m": SLIDE_OVERHANG_M,
                    "thickness_m": float(first["thickness_m"]),
                    "tilt_deg": float(first["tilt_deg"]),
                    # every candidate's slide, in the order of the pose sequences
                    "slides": [{"direction": c["direction"].tolist(), "slide_m": float(c["slide_m"])} for c in keep],
                },
                slide_translation=first["direction"] * first["slide_m"],
            )
        return offers

    def moved_before(self, obj: ObjectModel) -> np.ndarray | None:
        return obj.slide_translation

    def world_holds(self, obj: Any, gripper: Any, rules: Any) -> bool:
        """The world's rule: a box or a closed cylinder whose height the gripper spans at
        an edge (from its closing width to `physics.edge_pinch_span_m`) and whose
        narrowest side can overhang the fingers' grip without tipping."""
        if rules.open_container(obj):
            return False
        return bool(
            gripper.closing_width_m
            <= obj.height_m
            <= rules.edge_pinch_span_m(gripper.opening_width_m, rules.EDGE_PINCH_MIN_TILT_DEG)
            and rules.grasp_width_m(obj) >= 0.08
        )

    def simulate(self, world: SimWorld) -> str:
        """The slide of the candidate the IK check chose (one per seen side; a single one
        comes with its half-turn, the same slide), as far as the world lets the object go
        (`physics.world_slide`), then the pinch at the edge (`physics.world_edge_pinch`)."""
        rules, gripper, model = world.rules, world.gripper, world.model
        detail = model.kind_details.get(self.name, {})
        slides = list(detail.get("slides") or [detail])
        chosen = world.chosen_candidate()
        chosen = chosen if chosen is not None and len(slides) > 1 else 0
        slide = slides[min(int(chosen), len(slides) - 1)]
        direction = world.T_table_camera[:3, :3] @ np.asarray(slide.get("direction", (1.0, 0.0, 0.0)), dtype=float)
        world.scene, travelled = rules.world_slide(
            world.scene, world.k, direction[:2], float(slide.get("slide_m", 0.0))
        )
        # the pinch's pose as the arm went there (its tilt sets the span the jaws take);
        # the world's own figure: fingers need EDGE_GRIP_M of the overhang to hold it
        T_camera_edge = world.chosen_pose(model.kind_candidates.get(self.name, ()), pose=-2, candidate=int(chosen))
        tilt_deg = (
            rules.EDGE_PINCH_TILT_DEG
            if T_camera_edge is None
            else rules.approach_tilt_deg(world.T_table_camera @ T_camera_edge)
        )
        ok, why = rules.world_edge_pinch(
            world.scene, world.k, direction[:2], EDGE_GRIP_M, gripper.opening_width_m, gripper.closing_width_m, tilt_deg
        )
        if not ok:
            if "tipped" in why:
                world.take()
                return f"slid {travelled:.3f} m, fell off the table"
            return f"slid {travelled:.3f} m, then the pinch failed: {why}"
        world.take()
        return "removed"


def _pinch_opening(thick_m: float, tilt_deg: float) -> float:
    """How far the fingers open to pinch a slab ``thick_m`` thick from ``tilt_deg``
    below the horizontal: across the fingers the slab is thick / cos(tilt) (m)."""
    return thick_m / math.cos(math.radians(tilt_deg)) + 2.0 * SLIDE_CLEARANCE_M


def pinch_tilt_deg(thick_m: float, opening_m: float) -> float | None:
    """The steepest tilt below the horizontal, SLIDE_TILT_DEG at most, from which a slab
    ``thick_m`` thick fits an ``opening_m`` opening; None when not even from
    SLIDE_MIN_TILT_DEG. (Steeper keeps the wrist higher above the table's edge.)"""
    room = opening_m - 2.0 * SLIDE_CLEARANCE_M
    if thick_m <= 0.0 or room <= 0.0 or thick_m > room * math.cos(math.radians(SLIDE_MIN_TILT_DEG)):
        return None if thick_m > 0.0 else SLIDE_TILT_DEG
    # 0.1 deg below the bound, so that the opening needed stays within the opening
    return min(SLIDE_TILT_DEG, math.floor(10.0 * math.degrees(math.acos(thick_m / room))) / 10.0)


def _slide_to(
    obj: ObjectGeometry, a: np.ndarray, b: np.ndarray, table_mid: np.ndarray
) -> tuple[tuple[float, np.ndarray, float] | None, str]:
    """(slide length, outward unit (2,), the side's offset along it) to side a-b, or
    (None, why not)."""
    fp = np.asarray(obj.footprint, dtype=float)
    length = float(np.linalg.norm(b - a))
    along = (b - a) / length
    out_dir = np.array([along[1], -along[0]])
    if out_dir @ (a - table_mid) < 0:
        out_dir = -out_dir
    lat = fp @ along - a @ along
    if lat.min() < 0.01 or lat.max() > length - 0.01:
        return None, ""
    proj = fp @ out_dir
    extent = float(proj.max() - proj.min())
    if SLIDE_OVERHANG_M > extent / 2.0 - SLIDE_KEEP_ON_M:
        return (
            None,
            f"{extent:.3f} m long towards the edge: too short to overhang {SLIDE_OVERHANG_M:.3f} m without tipping",
        )
    dist = float(a @ out_dir - proj.max() + SLIDE_OVERHANG_M)
    if dist > SLIDE_MAX_M:
        return None, f"the nearest seen edge is {dist:.2f} m away"
    return (max(dist, 0.0), out_dir, float(a @ out_dir)), ""


def _candidate(
    obj: ObjectGeometry,
    plan: tuple[float, np.ndarray, float],
    gripper: GripperModel,
    settings: Settings,
    tilt_deg: float,
) -> dict[str, Any]:
    """The pose sequence of one slide: the push along the table, then the pinch at the edge."""
    g, push = gripper.settings, settings.push
    dist, out_dir, edge_at = plan
    thick = float(obj.top_height_m)
    fp = np.asarray(obj.footprint, dtype=float)
    d3 = np.array([out_dir[0], out_dir[1], 0.0])
    c = np.asarray(obj.center, dtype=float).copy()
    c[2] = 0.0
    rear = float((fp @ out_dir).min())
    lateral = c - (c @ d3) * d3
    # the push part: closed fingers behind the object, closing along the slide
    travel = max(dist, 1e-3)
    steps_n = max(1, math.ceil(travel / push.path_resolution_m - 1e-9))
    translations = (travel * np.arange(1, steps_n + 1) / steps_n)[:, None] * d3[None, :]
    start = lateral + (rear - push.gripper_behind_m - gripper.finger_half_extent_along_x(closed=True)) * d3
    start[2] = push.fingertips_above_table_m + g.closing_region_height_m / 2.0
    push_seq = _push_sequence(d3, start, push.approach_m * UP, translations, steps_n)[0]
    # the pinch at the edge: from beyond it and above, the approach tilted ``tilt_deg``
    # below the horizontal (level, no arm here reached it: the wrist would be at the
    # table's height), closing in the vertical plane of the slide; the
    # fingertips SLIDE_EDGE_CLEARANCE_M short of the edge, at the object's mid-height,
    # the lower finger out beyond the edge
    half = g.closing_region_height_m / 2.0
    tilt = math.radians(tilt_deg)
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
    return {
        "sequence": tuple(push_seq) + (pre, T, lift),
        "geometry": PushGeometry("slide", d3, dist, translations, (tuple(push_seq),)),
        "T_edge": T,
        "direction": d3,
        "slide_m": float(dist),
        "thickness_m": thick,
        "tilt_deg": float(tilt_deg),
    }


KIND = SLIDE = SlideGrasp()
