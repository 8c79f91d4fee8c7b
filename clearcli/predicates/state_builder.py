"""The predicates stage: `compute_state(frame, seg, settings) -> SymbolicState`.

Objects are renamed o0..oN-1 by position: sorted by their centroid in the table frame
(`clearcli.geometry.models.TableFrame`), nearest to the camera first (table x), then by
table y. Objects that cannot be modelled (too few points, all on a line) are left out
with a warning (logger ``clearcli.predicates``) and listed in ``SymbolicState.skipped``.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from clearcli.geometry.gripper import GripperModel, gripper_model, push_tool_model
from clearcli.geometry.models import (
    DegenerateObject,
    ObjectGeometry,
    TableFrame,
    build_from_columns,
    groups_table_rows,
    object_columns,
)
from clearcli.geometry.poses import PushGeometry, push_geometry
from clearcli.io.frames import Frame
from clearcli.perception.openings import TableEdge, rim_of, seen_edges
from clearcli.perception.types import Segmentation
from clearcli.predicates import relations as rel
from clearcli.predicates.grasps import Scene as GraspScene
from clearcli.predicates.grasps import kind as grasp_kind
from clearcli.predicates.grasps import kinds as grasp_kinds
from clearcli.predicates.grasps.base import Offer
from clearcli.predicates.state import DIRECTIONS, Fact, ObjectModel, PushModel, SymbolicState
from clearcli.settings import Settings
from clearcli.settings.kinds import tool_of as kind_tool
from clearcli.settings.profiles import tools_of

LOGGER = "clearcli.predicates"  # where a segment left out is reported


def _warn(message: str, *args: object) -> None:
    """A warning on LOGGER. logging (and the string module it imports) is imported here,
    for a segment left out, not by every `clear plan`: no other module of a plan imports
    it (issue 39: ~2-4 ms of a cold plan)."""
    import logging  # noqa: PLC0415  (see above)

    logging.getLogger(LOGGER).warning(message, *args)


def compute_state(
    frame: Frame,
    seg: Segmentation,
    settings: Settings | None = None,
    avoid_faces: Mapping[int, frozenset[str]] | None = None,
) -> SymbolicState:
    """Model the segmented objects and compute every fact the planner needs (no IK).
    ``avoid_faces``: segment index -> the faces a kind with faces must not use there (a
    closed loop's memory of a cup that did not seal)."""
    s = settings if settings is not None else Settings()
    ps = s.predicates
    timings: dict[str, float] = {}
    t_all = time.perf_counter()

    t0 = time.perf_counter()
    tf = TableFrame.from_plane(seg.table)
    gripper = gripper_model(s.gripper)
    # what pushes: the fingers, or a tool with a cup alone its cup (the same model as
    # ``gripper`` for a tool with fingers)
    pusher = push_tool_model(s.gripper, s.suction, tools_of(s.robot.name))
    geoms = []
    skipped: list[tuple[int, str]] = []
    tools = tools_of(s.robot.name)
    groups = [o.indices for o in seg.objects]
    # a cup judges its seal on the objects' own points (table frame; fingers need none):
    # transformed once, for the models too
    rows = (
        groups_table_rows(frame.points, groups, tf.T_table_camera)
        if "cup" in tools and groups and sum(len(g) for g in groups)
        else None
    )
    columns = object_columns(frame.points, groups, tf, ps.model_cell_m, rows)
    for k, cols in enumerate(columns):
        try:
            if cols is None:
                raise DegenerateObject("no finite points")
            geoms.append(build_from_columns(cols, k, ps))
        except DegenerateObject as exc:
            _warn("segment %d left out: %s", k, exc)
            skipped.append((k, str(exc)))
    # stable names by position, not by segmentation order
    if geoms:
        cents = np.stack([g.centroid for g in geoms])
        order = np.lexsort((cents[:, 1], cents[:, 0]))
        geoms = [geoms[int(i)] for i in order]
    timings["models"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    pushes = [push_geometry(g, pusher, s.push) for g in geoms]
    timings["poses"] = time.perf_counter() - t0

    names = [f"o{i}" for i in range(len(geoms))]
    facts: set[Fact] = set()

    t0 = time.perf_counter()
    on = rel.on_pairs(
        geoms,
        ps.on_threshold_points,
        ps.on_margin_m,
        min_lift_m=ps.on_min_lift_m,
        height_gap_m=ps.on_height_gap_m,
        support_band_m=ps.on_support_band_m,
    )
    # what stands in an open container is on it (relations.inside_rims)
    openings, edges = _openings_and_edges(frame, seg)
    rims: list[tuple[float, float, float] | None] = []
    for g in geoms:
        rim = getattr(openings[g.segment_index], "rim", None)
        if rim is None:
            rims.append(None)
        else:
            c = tf.to_table(np.asarray(rim.center, dtype=float)[None])[0]
            rims.append((float(c[0]), float(c[1]), float(rim.radius_m - rim.wall_m / 2.0)))
    # (not where the container stands on the other: then the other is under it)
    on = set(on) | {(a, b) for a, b in rel.inside_rims(geoms, rims) if (b, a) not in on}
    facts.update(("on", names[a], names[b]) for a, b in on)
    timings["on"] = time.perf_counter() - t0
    exclude = rel.related(on)
    # the gripper yaw of each push that the neighbours block least
    pushes = rel.least_blocked_pushes(geoms, pushes, pusher, exclude)

    t0 = time.perf_counter()
    touching = rel.start_overlaps(geoms)
    triples = rel.block_dir_triples(geoms, pushes, pusher, exclude, touching, ps.touching_block_angle_deg)
    facts.update(("block_dir", names[a], names[b], d) for a, b, d in triples)
    timings["block_dir"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    table_xy = tf.to_table(np.asarray(seg.table_polygon, dtype=float).reshape(-1, 3))[:, :2]
    facts.update(("push_off_table", names[i], d) for i, d in rel.push_off_table(geoms, pushes, table_xy))
    timings["static"] = time.perf_counter() - t0

    # every grasp kind, in preference order (the thesis's pinch first: block_grasp,
    # ungraspable), each offered where it takes the object, with its blockers
    t0 = time.perf_counter()
    points_table = (
        _points_table(rows, [len(g) for g in groups], [g.segment_index for g in geoms]) if "cup" in tools else []
    )
    by_index = {g.segment_index: i for i, g in enumerate(geoms)}
    avoid = {by_index[k]: v for k, v in (avoid_faces or {}).items() if k in by_index and v}
    kinds = _grasp_offers(geoms, openings, edges, tf, gripper, s, exclude, touching, tools, points_table, on, avoid)

    for name, offers in kinds.items():
        f = grasp_kind(name).facts
        for i, offer in enumerate(offers):
            static = f.unoffered if offer.why_not else f.offered
            if static:
                facts.add((static, names[i]))
            facts.update((f.block, names[a], names[i]) for a in offer.blockers)
    timings["grasp_kinds"] = time.perf_counter() - t0

    costs: dict[tuple[str, str], int] = {}
    if ps.clearance_cost:
        t0 = time.perf_counter()
        dist = rel.clearance_distances(geoms, pushes, pusher, exclude, ps.clearance_cost_distance_m)
        costs = {
            (names[i], d): rel.clearance_cost(v, ps.clearance_cost_distance_m, ps.clearance_cost_gain_per_m)
            for (i, d), v in dist.items()
        }
        timings["costs"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    objects = tuple(
        _object_model(names[i], g, pushes[i], tf, {k: v[i] for k, v in kinds.items()}) for i, g in enumerate(geoms)
    )
    timings["export"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t_all
    return SymbolicState(
        objects=objects,
        table=seg.table,
        table_polygon=np.asarray(seg.table_polygon, dtype=float).reshape(-1, 3),
        facts=frozenset(facts),
        push_costs=costs,
        timings_s=timings,
        source=seg.source or frame.source,
        skipped=tuple(skipped),
    )


def _openings_and_edges(frame: Frame, seg: Segmentation) -> tuple[tuple[Any, ...], tuple[Any, ...]]:
    """Per segment its rim or why not, and the table's sides seen to end: what
    segmentation saw, or (a segmentation from labels) worked out here."""
    openings = (
        seg.openings
        if len(seg.openings) == len(seg.objects)
        else tuple(rim_of(frame.points[o.indices], seg.table) for o in seg.objects)
    )
    edges = seg.table_edges or seen_edges(frame.points, frame.shape, seg.table, seg.table_polygon)
    return tuple(openings), tuple(edges)


def _grasp_offers(
    geoms: Sequence[ObjectGeometry],
    openings: Sequence[Any],
    edges: Sequence[TableEdge],
    tf: TableFrame,
    gripper: GripperModel,
    settings: Settings,
    exclude: set[tuple[int, int]],
    touching: set[tuple[int, int]],
    tools: Sequence[str] = ("fingers",),
    points_table: Sequence[np.ndarray] = (),
    on: Iterable[tuple[int, int]] = (),
    avoid_faces: Mapping[int, frozenset[str]] | None = None,
) -> dict[str, list[Offer]]:
    """kind name -> one `Offer` per object (table frame), every registered kind the
    robot's tool takes (``tools``: clearcli/settings/profiles.py) in preference order,
    each seeing which objects the kinds before it are offered for. The thesis's pinch is
    always there (the domain's own grasp): a tool without fingers offers it nothing."""
    edges_table = [(*tf.to_table(np.stack([e.start, e.end])), e.seen, e.why) for e in edges]
    scene = GraspScene(
        objects=geoms,
        points_table=points_table,
        openings=[openings[g.segment_index] for g in geoms],
        edges_table=edges_table,
        exclude=exclude,
        touching=touching,
        tf=tf,
        on=frozenset(on),
        avoid_faces=dict(avoid_faces or {}),
    )
    out: dict[str, list[Offer]] = {}
    for kind in grasp_kinds():
        part = kind_tool(kind.name)
        if part not in tools and not kind.thesis:
            continue
        offers = kind.offers(scene, gripper, settings)
        if part not in tools:
            # the domain's own grasp, with no fingers to make it: its model (poses, width)
            # stays, offered to nothing
            offers = [dataclasses.replace(o, why_not=f"the robot's tool has no {part}") for o in offers]
        out[kind.name] = offers
        offered = frozenset(i for i, o in enumerate(offers) if not o.why_not)
        scene = dataclasses.replace(scene, offered_before=scene.offered_before + ((kind, offered),))
    return out


def _object_model(
    name: str,
    g: ObjectGeometry,
    pushes: dict[str, PushGeometry],
    tf: TableFrame,
    offers: dict[str, Offer],
) -> ObjectModel:
    """The object as the planner sees it: the thesis's grasp (its poses and width) in its
    own fields, every other kind's poses, detail and refusal under its name."""
    thesis = {k: o for k, o in offers.items() if grasp_kind(k).thesis}
    others = {k: o for k, o in offers.items() if k not in thesis}
    (pinch,) = thesis.values()

    def poses(seq: Sequence[np.ndarray]) -> tuple[np.ndarray, ...]:
        out = np.einsum("ij,njk->nik", tf.T_camera_table, np.asarray(seq))
        return tuple(out)

    # every pose of the object in one product
    seqs = [c for d in DIRECTIONS for c in pushes[d].candidates]
    lengths = [len(c) for c in seqs]
    flat = poses([T for c in seqs for T in c]) if seqs else ()
    cuts = np.cumsum([0, *lengths])
    moved = [tuple(flat[cuts[i] : cuts[i + 1]]) for i in range(len(seqs))]
    push_models = {}
    k = 0
    for d in DIRECTIONS:
        p = pushes[d]
        n_c = len(p.candidates)
        push_models[d] = PushModel(
            direction=d,
            unit_vector=tf.vector_to_camera(p.unit),
            push_length_m=float(p.length_m),
            object_path=tuple(tf.vector_to_camera(p.object_translations)),
            candidates=tuple(moved[k : k + n_c]),
        )
        k += n_c
    return ObjectModel(
        name=name,
        segment_index=g.segment_index,
        centroid=tf.to_camera(g.centroid),
        principal_axes=tf.vector_to_camera(g.principal_axes3),
        extents_m=g.extents.copy(),
        hull_vertices=tf.to_camera(g.hull_vertices),
        hull_faces=g.hull_faces.copy(),
        grasp_candidates=tuple(poses(c) for c in pinch.candidates),
        pushes=push_models,
        grasp_width_m=float((pinch.detail or {})["width_m"]),
        height_m=float(g.top_height_m),
        kind_candidates={k: tuple(poses(c) for c in o.candidates) for k, o in others.items() if not o.why_not},
        kind_details={k: _detail_to_camera(o.detail or {}, tf) for k, o in others.items() if not o.why_not},
        kind_refusals={k: o.why_not for k, o in others.items() if o.why_not},
        # a grasp that first moves it along the table (a slide): by how much
        slide_translation=next(
            (
                tf.vector_to_camera(np.asarray(o.slide_translation))
                for o in others.values()
                if o.slide_translation is not None and not o.why_not
            ),
            None,
        ),
    )


def _points_table(rows: np.ndarray | None, sizes: Sequence[int], order: Sequence[int]) -> list[np.ndarray]:
    """Of the segments' points end to end in the table frame (``rows``: (3, N),
    `table_rows`; ``sizes``: each segment's count), those of the segments ``order``
    names, each (n, 3) C-ordered, its non-finite points dropped (a non-finite coordinate
    makes all three transformed ones non-finite: float32 or float64 input, no finite one
    overflows, so the height alone tells)."""
    if rows is None:
        return [np.zeros((0, 3)) for _ in order]
    cuts = np.cumsum([0, *sizes])
    out = []
    for k in order:
        q = np.ascontiguousarray(rows[:, cuts[k] : cuts[k + 1]].T)
        ok = np.isfinite(q[:, 2])
        out.append(q if ok.all() else q[ok])
    return out


def _detail_to_camera(detail: Any, tf: TableFrame) -> dict[str, Any]:
    # the JSON's points and directions in the sensor frame, as every other pose there
    out = dict(detail)
    if "point" in out:  # a suction cup's contact and the face's normal there
        out["point"] = tf.to_camera(np.asarray(out["point"], dtype=float)[None])[0].tolist()
    if "normal" in out:
        out["normal"] = tf.vector_to_camera(np.asarray(out["normal"], dtype=float)[None])[0].tolist()
    if "center" in out:
        out["center"] = tf.to_camera(np.asarray(out["center"], dtype=float)[None])[0].tolist()
    if "direction" in out:
        out["direction"] = tf.vector_to_camera(np.asarray(out["direction"], dtype=float)[None])[0].tolist()
    if "slides" in out:
        out["slides"] = [
            {**c, "direction": tf.vector_to_camera(np.asarray(c["direction"], dtype=float)[None])[0].tolist()}
            for c in out["slides"]
        ]
    out.pop("edge", None)  # a distance along the table frame's direction: not for readers
    return out
