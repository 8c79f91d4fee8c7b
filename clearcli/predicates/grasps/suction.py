"""The suction grasp: a vacuum cup on a flat patch of the object, from above or the side.

Offered where the robot profile's tool has a cup (clearcli/settings/profiles.py
``tools``). Each object's seen faces are searched for a place where the cup seals and
holds (`clearcli.geometry.suction`: covered, alone, flat within the bellows' compliance,
facing the approach; the weight from the modelled volume and ``[suction]
density_kg_m3``, its pull and moment within the holding force over the safety factor).
Of the places that seal and hold (the best 8 by margin, best first), the planner gets
the first the tool's swept volume meets nothing at, else the one it meets fewest other
objects at; what it meets are its ``block_suction`` facts. The tool's volume: the stem carrying the cup (the cup's radius
and 3 mm, ``stem_length_m`` long) and the tool's body behind it (``body_radius_m``,
``body_length_m``), swept along the approach from ``[push] approach_m`` out.

Its poses put the cup's lip on the contact, its axis along the face's normal (z of the
pose into the face), at four turns about that axis (the IK check takes the first the arm
reaches); the profile's tool centre point, where the IK aims, is ``lip_past_tcp_m``
behind the lip. A push moves the object and its poses with it (its IK fact and blocks
cleared, as for the rim).

Not offered, with the reason of the candidate that came closest: no face the size of the
cup seen; a curved, rough or tilted face; a hole or an edge under the cup; another object
under it; too heavy for the cup (pull, shear and moment against the holding force).

Preference: its action costs 1, as the thesis's pinch does (one motion, nothing moved
first); the rim (2) and the slide (3) stay dearer. Where both the pinch and suction take
an object the plan may use either; the IK check and backtracking then fall back to the
other (each has its own ``ik_unfeasible_*`` fact).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from clearcli.predicates.grasps.base import KindFacts, KindModule, Offer, Scene, SimWorld
from clearcli.transforms import cross3

if TYPE_CHECKING:
    # clearcli.geometry.suction is imported where it is used: every plan imports this
    # module for its KIND, and only a robot whose tool has a cup uses it (its 8
    # dataclasses, ~4 ms of a cold `clear plan` on a quiet machine; issue 39)
    from clearcli.geometry.gripper import GripperModel
    from clearcli.geometry.suction import CupSpec
    from clearcli.settings import Settings
    from clearcli.settings.suction import SuctionSettings

UP = np.array([0.0, 0.0, 1.0])
STEM_CLEARANCE_M = 0.003  # the stem's radius beyond the cup's
TURNS_DEG = (0.0, 180.0, 90.0, 270.0)  # half turns first, as the pinch's candidates
# a point this far (m, and m^2 for squared distances) inside or outside every bound of
# the tool's volume in the contact's axes is in or out by the exact test too (the two
# computations differ by rounding, ~1e-16 m at a metre)
SURE_M = 1e-9
BLOCK_STRIDE = 4  # every 4th point of a neighbour is checked against the tool's volume
# the places' blockers: the best place alone, then the others together (`swept_hits`)
FIRST_THEN_REST = (slice(0, 1), slice(1, None))


def cup_spec(s: SuctionSettings) -> CupSpec:
    from clearcli.geometry.suction import CupSpec  # noqa: PLC0415  (see the top)

    return CupSpec(
        diameter_m=s.cup_diameter_m,
        compliance_m=s.bellows_compliance_m,
        holding_force_n=s.holding_force_n,
        safety_factor=s.safety_factor,
        lip_friction=s.lip_friction,
        max_tilt_deg=s.max_tilt_deg,
        gap_m=s.hole_gap_m,
    )


def swept_mask(
    points: np.ndarray, point: np.ndarray, normal: np.ndarray, s: SuctionSettings, approach_m: float
) -> np.ndarray:
    """Which of ``points`` (table frame) lie in the volume the tool sweeps coming to the
    contact (``point``, outward ``normal``) from ``approach_m`` out: the stem, then the
    body. Points within the bellows' stroke of the face belong to the seal test."""
    out = np.zeros(len(points), dtype=bool)
    out[_swept_pairs(points, point[None, :], normal[None, :], s, approach_m)[0]] = True
    return out


def swept_hits(
    points: np.ndarray,
    labels: np.ndarray,
    at: np.ndarray,
    normals: np.ndarray,
    s: SuctionSettings,
    approach_m: float,
    parts: Sequence[slice] = (slice(None),),
) -> Iterator[frozenset[int]]:
    """The labels of ``points`` in the tool's volume (`swept_mask`) at each of C
    contacts (``at``, ``normals``: (C, 3)), in order, made part by part (``parts``:
    consecutive slices of the C, each made when the first of it is asked for: a search
    that stops at the first contact makes no more). Each point is placed in the contact's
    own axes (`_box_parts`' product); a point farther than `SURE_M` inside or outside
    every bound there is in or out as the exact test (`_inside`) would say (the two differ
    by rounding, ~1e-16 m), and only the points nearer a bound are tested exactly."""
    n_labels = int(labels.max()) + 1 if len(labels) else 1
    r_stem = s.cup_diameter_m / 2.0 + STEM_CLEARANCE_M
    stem = (s.bellows_compliance_m, s.stem_length_m + approach_m, r_stem**2)
    body = (s.stem_length_m, s.stem_length_m + s.body_length_m + approach_m, s.body_radius_m**2)
    for asked, q in _axes_parts(points, at, normals, s, approach_m, parts):
        hits: dict[int, set[int]] = {k: set() for k in asked}
        if q is not None:
            depth = q[:, 0]
            radial2 = q[:, 1] * q[:, 1] + q[:, 2] * q[:, 2]
            sure = _zone(depth, radial2, *stem, SURE_M) | _zone(depth, radial2, *body, SURE_M)
            near = (_zone(depth, radial2, *stem, -SURE_M) | _zone(depth, radial2, *body, -SURE_M)) & ~sure
            first = np.asarray(asked)
            hit = np.zeros(len(at) * n_labels, dtype=bool)
            c_in, m_in = np.nonzero(sure)
            hit[first[c_in] * n_labels + labels[m_in]] = True
            c_near, m_near = np.nonzero(near)
            if len(m_near):
                c_near = first[c_near]
                ok = _inside(points, at, normals, m_near, c_near, s, approach_m)
                hit[c_near[ok] * n_labels + labels[m_near[ok]]] = True
            for k in np.flatnonzero(hit).tolist():
                hits[k // n_labels].add(k % n_labels)
        yield from (frozenset(hits[k]) for k in asked)


def _zone(depth: np.ndarray, radial2: np.ndarray, lo: float, hi: float, r2: float, e: float) -> np.ndarray:
    """Where a depth along the normal lies in (lo + e, hi - e] and a squared distance
    from the axis is at most r2 - e (``e`` < 0: grown by as much)."""
    out: np.ndarray = (depth > lo + e) & (depth <= hi - e) & (radial2 <= r2 - e)
    return out


def _swept_pairs(
    points: np.ndarray, at: np.ndarray, normals: np.ndarray, s: SuctionSettings, approach_m: float
) -> tuple[np.ndarray, np.ndarray]:
    """(point, contact) index pairs: each of ``points`` in the tool's volume at each of
    C contacts (`_swept_parts` in one part)."""
    return next(_swept_parts(points, at, normals, s, approach_m, (slice(None),)))[1]


def _swept_parts(
    points: np.ndarray,
    at: np.ndarray,
    normals: np.ndarray,
    s: SuctionSettings,
    approach_m: float,
    parts: Sequence[slice],
) -> Iterator[tuple[range, tuple[np.ndarray, np.ndarray]]]:
    """Per part (a slice of the C contacts) its contacts and its (point, contact) index
    pairs: each of ``points`` in the tool's volume at each of them (the pairs in the
    boxes, `_box_parts`, that pass the exact test, `_inside`). Each part's pairs are made
    when it is asked for."""
    for asked, (m, c) in _box_parts(points, at, normals, s, approach_m, parts):
        inside = _inside(points, at, normals, m, c, s, approach_m)
        yield asked, (m[inside], c[inside])


def _box_parts(
    points: np.ndarray,
    at: np.ndarray,
    normals: np.ndarray,
    s: SuctionSettings,
    approach_m: float,
    parts: Sequence[slice],
) -> Iterator[tuple[range, tuple[np.ndarray, np.ndarray]]]:
    """Per part (a slice of the C contacts) its contacts and the (point, contact) index
    pairs of ``points`` in the box around the tool's volume at each of them, in the
    contact's own axes (`_axes_parts`), a micrometre wide: most points lie beside the
    tool; only those left are tested (`_inside`). Each part's pairs are made when it is
    asked for."""
    none = np.zeros(0, dtype=np.int64)
    w_min = min(s.bellows_compliance_m, s.stem_length_m)
    w_max = max(s.stem_length_m + approach_m, s.stem_length_m + s.body_length_m + approach_m)
    across = max(s.cup_diameter_m / 2.0 + STEM_CLEARANCE_M, s.body_radius_m) + 1e-6
    for asked, q in _axes_parts(points, at, normals, s, approach_m, parts):
        if q is None:
            yield asked, (none, none)
            continue
        # the elementwise tests below give each contact's pairs alike in any part
        depth = q[:, 0]
        box = (depth > w_min - 1e-6) & (depth <= w_max + 1e-6)
        box &= np.abs(q[:, 1]) <= across
        box &= np.abs(q[:, 2]) <= across
        c, m = np.nonzero(box)
        yield asked, (m, np.asarray(asked)[c])


def _axes_parts(
    points: np.ndarray,
    at: np.ndarray,
    normals: np.ndarray,
    s: SuctionSettings,
    approach_m: float,
    parts: Sequence[slice],
) -> Iterator[tuple[range, np.ndarray | None]]:
    """Per part (a slice of the C contacts) its contacts and ``points`` in each one's own
    axes ((part's C, 3, n): the depth along the normal, two directions across it; None
    where there are no points or no contacts), from one matrix product for all C,
    whatever the parts (a product's rounding may depend on its shape)."""
    if not len(points) or not len(at):
        for part in parts:
            yield range(len(at))[part], None
        return
    # per contact: the normal, a unit direction across it, and the third
    n = normals
    ref = np.where((np.abs(n[:, 0]) < 0.9)[:, None], np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    a = np.stack(
        [
            n[:, 1] * ref[:, 2] - n[:, 2] * ref[:, 1],
            n[:, 2] * ref[:, 0] - n[:, 0] * ref[:, 2],
            n[:, 0] * ref[:, 1] - n[:, 1] * ref[:, 0],
        ],
        axis=1,
    )
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.stack(
        [
            n[:, 1] * a[:, 2] - n[:, 2] * a[:, 1],
            n[:, 2] * a[:, 0] - n[:, 0] * a[:, 2],
            n[:, 0] * a[:, 1] - n[:, 1] * a[:, 0],
        ],
        axis=1,
    )
    axes = np.stack([n, a, b], axis=1).reshape(-1, 3)  # (3C, 3)
    q_all = points @ axes.T - np.einsum("ck,ck->c", axes, np.repeat(at, 3, axis=0))
    # per contact its three rows, each contiguous: the tests run along the points
    q_rows = np.ascontiguousarray(q_all.T).reshape(len(at), 3, len(points))
    for part in parts:
        asked = range(len(at))[part]
        yield asked, (q_rows[part] if len(asked) else None)


def _inside(
    points: np.ndarray,
    at: np.ndarray,
    normals: np.ndarray,
    m: np.ndarray,
    c: np.ndarray,
    s: SuctionSettings,
    approach_m: float,
) -> np.ndarray:
    """Which (point ``m``, contact ``c``) pairs lie in the tool's volume: the stem, then
    the body (row by row: a pair's answer is the same whichever pairs come with it)."""
    r_stem = s.cup_diameter_m / 2.0 + STEM_CLEARANCE_M
    rel = points[m] - at[c]
    w = np.einsum("ij,ij->i", rel, normals[c])
    radial2 = np.einsum("ij,ij->i", rel, rel) - w * w
    stem = (w > s.bellows_compliance_m) & (w <= s.stem_length_m + approach_m) & (radial2 <= r_stem**2)
    body = (
        (w > s.stem_length_m) & (w <= s.stem_length_m + s.body_length_m + approach_m) & (radial2 <= s.body_radius_m**2)
    )
    out: np.ndarray = stem | body
    return out


def swept_boxes(at: np.ndarray, normals: np.ndarray, s: SuctionSettings, approach_m: float) -> np.ndarray:
    """(C, 2, 3) the box (table frame: smallest, largest corner) around the tool's swept
    volume at each of C contacts (``at``, outward ``normals``), a micrometre wide: a
    cylinder along the normal as long as the stem and the body, as wide as the wider
    (its end discs reach sqrt(1 - n_k^2) times the radius along axis k)."""
    w_min = min(s.bellows_compliance_m, s.stem_length_m)
    w_max = max(s.stem_length_m + approach_m, s.stem_length_m + s.body_length_m + approach_m)
    across = max(s.cup_diameter_m / 2.0 + STEM_CLEARANCE_M, s.body_radius_m)
    a, b = at + w_min * normals, at + w_max * normals
    r = across * np.sqrt(np.clip(1.0 - normals * normals, 0.0, 1.0)) + 1e-6
    return np.stack([np.minimum(a, b) - r, np.maximum(a, b) + r], axis=1)


def contact_poses(
    point: np.ndarray, normal: np.ndarray, across: np.ndarray, s: SuctionSettings, approach_m: float
) -> tuple[tuple[np.ndarray, ...], ...]:
    """Pose sequences T_table_tcp (pre, contact, lift) at each of `TURNS_DEG` about the
    cup's axis: the lip on ``point``, z into the face."""
    z = -normal
    x0 = across - (across @ z) * z
    if np.linalg.norm(x0) < 1e-6:
        x0 = cross3(z, np.array([1.0, 0.0, 0.0]))
    x0 = x0 / np.linalg.norm(x0)
    y0 = cross3(z, x0)  # np.cross costs ~20 us for 3-vectors (the same products)
    # every turn at once, elementwise as `_pose` makes each: x, y = z cross x, z, the TCP
    cos = np.array([math.cos(math.radians(turn)) for turn in TURNS_DEG])[:, None]
    sin = np.array([math.sin(math.radians(turn)) for turn in TURNS_DEG])[:, None]
    x = cos * x0 + sin * y0
    y = np.stack(
        [z[1] * x[:, 2] - z[2] * x[:, 1], z[2] * x[:, 0] - z[0] * x[:, 2], z[0] * x[:, 1] - z[1] * x[:, 0]], axis=1
    )
    tcp = point - s.lip_past_tcp_m * z  # the TCP behind the lip, on the cup's axis
    T = np.zeros((len(TURNS_DEG), 3, 4, 4))
    T[:, :, 3, 3] = 1.0
    T[:, :, :3, 0] = x[:, None, :]
    T[:, :, :3, 1] = y[:, None, :]
    T[:, :, :3, 2] = z
    T[:, 0, :3, 3] = tcp + approach_m * normal  # pre
    T[:, 1, :3, 3] = tcp
    T[:, 2, :3, 3] = tcp + approach_m * UP  # lift
    return tuple((T[k, 0].copy(), T[k, 1].copy(), T[k, 2].copy()) for k in range(len(TURNS_DEG)))


def _within(points: np.ndarray, p_lo: np.ndarray, p_hi: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Those of ``points`` (their box ``p_lo``, ``p_hi``: `bounds`) in the box [lo, hi]
    (`in_box`): all of them, not tested one by one, where their box lies in it."""
    from clearcli.geometry.suction import in_box  # noqa: PLC0415  (see the top)

    if bool(np.all(p_lo >= lo)) and bool(np.all(p_hi <= hi)):
        return points
    # x first over all of them, then y and z over those left (the same points, in order)
    x = points[:, 0]
    first = np.flatnonzero((x >= lo[0]) & (x <= hi[0]))
    if len(first) * 2 > len(points):
        return points[in_box(points, lo, hi)]
    rest = points[first]
    return rest[in_box(rest, lo, hi)]


class SuctionGrasp(KindModule):
    name = "suction"
    label = "suction grasp"
    facts = KindFacts("grasp_suction", "suctionable", "block_suction", "ik_unfeasible_suction", 1)
    instead = "it is taken by suction instead"
    # a cup that did not seal or hold left its object where it stood: the same face
    # meets the same again (a porous top stays porous), so the closed loop gives it up
    give_up_unmoved = True
    # a top that did not seal (porous, ribbed) may leave a side that does
    faces = ("top", "side")

    def offers(self, scene: Scene, gripper: GripperModel, settings: Settings) -> list[Offer]:
        from clearcli.geometry.suction import (  # noqa: PLC0415  (see the top)
            MAX_POINTS,
            Judged,
            ObjectJob,
            bounds,
            judge_objects,
            volume_above,
        )

        s = settings.suction
        spec = cup_spec(s)
        approach_m = settings.push.approach_m
        n = len(scene.objects)
        full = [np.asarray(p, dtype=float).reshape(-1, 3) for p in scene.points_table]
        # each object's points at most MAX_POINTS, every k-th (as `judge_object` takes its
        # own): the seal tests' cells of 4 mm need no more, and a RealSense close up gives
        # 50,000 an object
        pts = [p[:: max(1, math.ceil(len(p) / MAX_POINTS))] for p in full]
        empty = np.zeros((0, 3))
        m = min(n, len(pts))
        box = [bounds(p) if len(p) else (np.full(3, np.inf), np.full(3, -np.inf)) for p in pts[:m]]
        b_lo = np.array([b[0] for b in box]).reshape(-1, 3)
        b_hi = np.array([b[1] for b in box]).reshape(-1, 3)
        # how far from an object another can be under the cup or in the tool's way: the
        # body's radius across, the tool's length and the approach along the normal
        reach = max(s.body_radius_m, s.cup_diameter_m) + s.stem_length_m + s.body_length_m + approach_m
        # ... and how far under its cup (the seal test's box)
        seal_reach = spec.radius_m + spec.compliance_m + max(spec.compliance_m, 0.01)

        def overlaps(r: float) -> np.ndarray:
            """(m, m) object j's box meets object i's grown by ``r``."""
            return np.all(
                (b_hi[None, :, :] >= b_lo[:, None, :] - r) & (b_lo[None, :, :] <= b_hi[:, None, :] + r), axis=2
            )

        # objects related by `on` never block each other (as for every kind): what
        # stands on one goes first, what it stands on is under it
        related = np.zeros((m, m), dtype=bool)
        for a, b in scene.exclude:
            if a < m and b < m:
                related[a, b] = related[b, a] = True
        np.fill_diagonal(related, True)
        near_all = overlaps(reach) & ~related
        close_all = overlaps(seal_reach) & ~related
        # the neighbours' points every BLOCK_STRIDE-th, once (an object in the tool's way
        # shows with hundreds of points; a stride by index moves with no rounding)
        sample = [p[::BLOCK_STRIDE] for p in full[:m]]
        s_box = [bounds(p) if len(p) else (np.full(3, np.inf), np.full(3, -np.inf)) for p in sample]
        s_lo = np.array([b[0] for b in s_box]).reshape(-1, 3)
        s_hi = np.array([b[1] for b in s_box]).reshape(-1, 3)
        # every object's places judged at once (`judge_objects`), then each one's offer
        jobs: dict[int, ObjectJob] = {}
        masses: dict[int, float] = {}
        for i, g in enumerate(scene.objects):
            own = pts[i] if i < len(pts) else empty
            close = (
                [
                    _within(pts[j], b_lo[j], b_hi[j], b_lo[i] - seal_reach, b_hi[i] + seal_reach)
                    for j in np.flatnonzero(close_all[i])
                ]
                if i < m
                else []
            )
            others = np.concatenate(close) if close else empty
            # an object standing on another weighs what lies above its bottom
            stands_on = any(a == i for a, _b in scene.on)
            volume, com = volume_above(
                np.asarray(g.hull_vertices),
                np.asarray(g.hull_faces),
                np.asarray(g.footprint),
                g.bottom_height_m if stands_on else 0.0,
            )
            mass = volume * s.density_kg_m3
            min_side = max(spec.radius_m, s.body_radius_m) + 0.005  # the tool clears the table
            # what stands on it is taken first: where it hides the top, the top goes on
            above = [pts[a] for a, b in scene.on if b == i and a != i and a < len(pts)]
            hidden_by = np.concatenate(above) if above else None
            skip = scene.avoid_faces.get(i, frozenset())
            if skip >= frozenset(self.faces):
                continue
            masses[i] = mass
            jobs[i] = ObjectJob(
                own,
                others,
                g.axes2d,
                g.top_height_m,
                mass,
                com,
                min_side,
                hidden_by,
                scene.tf.T_camera_table,
                skip,
                others_near=True,  # kept within the seal test's reach above
            )
        all_judged = dict(zip(jobs, judge_objects(list(jobs.values()), spec)))
        out: list[Offer] = []
        for i, g in enumerate(scene.objects):
            if i not in all_judged:
                out.append(Offer(why_not="the cup did not seal on any of its faces (top, sides) when tried"))
                continue
            judged: Judged = all_judged[i]
            mass = masses[i]
            if judged.best is None:
                out.append(Offer(why_not=judged.why_not(spec)))
                continue
            # the neighbours' sampled points within the tool's reach of this object and
            # near enough the kept places to be in the tool's volume at one of them
            pieces: list[np.ndarray] = []
            owners: list[np.ndarray] = []
            if i < m and len(judged.points):
                boxes = swept_boxes(judged.points, judged.normals, s, approach_m)
                lo = np.maximum(b_lo[i] - reach, boxes[:, 0].min(axis=0))
                hi = np.minimum(b_hi[i] + reach, boxes[:, 1].max(axis=0))
                meets = (s_lo <= hi) & (s_hi >= lo)  # (m, 3): each neighbour's box, per axis
                for j in np.flatnonzero(near_all[i] & meets[:, 0] & meets[:, 1] & meets[:, 2]):
                    pieces.append(_within(sample[j], s_lo[j], s_hi[j], lo, hi))
                    owners.append(np.full(len(pieces[-1]), j))
            cloud = np.concatenate(pieces) if pieces else empty
            labels = np.concatenate(owners) if owners else np.zeros(0, int)
            # up to 8 places that seal and hold, best first: the first that nothing
            # blocks ends the search, else the one fewest do
            pick, blockers = 0, frozenset[int]()
            # the best place alone first: where nothing blocks it the rest are not looked
            # at (each judged as among all, `_swept_parts`: the same hits)
            hits = swept_hits(cloud, labels, judged.points, judged.normals, s, approach_m, FIRST_THEN_REST)
            for rank, hit in enumerate(hits):
                if rank == 0 or len(hit) < len(blockers):
                    pick, blockers = rank, hit
                if not blockers:
                    break
            best = judged.best if pick == 0 or judged.make is None else judged.make(judged.order[pick])
            across = np.array([g.axes2d[0][0], g.axes2d[0][1], 0.0]) if best.face == "top" else UP
            out.append(
                Offer(
                    candidates=contact_poses(best.point, best.normal, across, s, approach_m),
                    blockers=blockers,
                    detail={
                        "face": best.face,
                        "point": best.point.tolist(),
                        "normal": best.normal.tolist(),
                        "cup_diameter_m": s.cup_diameter_m,
                        "sag_m": round(best.sag_m, 6),
                        "spread_m": round(best.spread_m, 6),
                        "tilt_deg": round(best.tilt_deg, 3),
                        "mass_kg": round(mass, 4),
                        "margin": round(best.margin, 4),
                    },
                )
            )
        return out

    def world_holds(self, obj: Any, gripper: Any, rules: Any) -> bool:
        """The world's rule (`physics.world_suction_holds`): some true face of the object
        seals under the cup and holds its true mass."""
        return bool(rules.world_suction_holds(obj))

    def simulate(self, world: SimWorld) -> str:
        """The world's cup at the pose the arm went to (`physics.world_suction`)."""
        T_camera_tcp = world.chosen_pose(world.model.kind_candidates.get(self.name, ()))
        if T_camera_tcp is None:
            return "missed: no suction pose"
        s = world.settings.suction
        T_table_tcp = world.T_table_camera @ T_camera_tcp
        axis = T_table_tcp[:3, 2]
        lip = T_table_tcp[:3, 3] + s.lip_past_tcp_m * axis
        ok, why, k = world.rules.world_suction(world.scene, lip, axis, s)  # the pose's z: into the face
        if k is not None and k != world.k:
            world.aim(k)
        if not ok:
            return f"suction failed: {why}"
        world.take()
        return "removed"


KIND = SUCTION = SuctionGrasp()
