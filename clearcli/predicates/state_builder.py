"""The predicates stage: `compute_state(frame, seg, settings) -> SymbolicState`.

Objects are renamed o0..oN-1 by position: sorted by their centroid in the table frame
(`clearcli.geometry.models.TableFrame`), nearest to the camera first (table x), then by
table y. Objects that cannot be modelled (too few points, all on a line) are left out
with a warning (logger ``clearcli.predicates``) and listed in ``SymbolicState.skipped``.
"""

from __future__ import annotations

import logging
import time
from typing import TYPE_CHECKING, Sequence

import numpy as np

from clearcli.io.frames import Frame
from clearcli.perception.types import Segmentation
from clearcli.predicates.state import DIRECTIONS, Fact, ObjectModel, PushModel, SymbolicState

if TYPE_CHECKING:
    from clearcli.geometry.models import ObjectGeometry, TableFrame
    from clearcli.geometry.poses import GraspGeometry, PushGeometry
    from clearcli.settings import Settings

log = logging.getLogger("clearcli.predicates")


def compute_state(frame: Frame, seg: Segmentation, settings: "Settings | None" = None) -> SymbolicState:
    """Model the segmented objects and compute every fact the planner needs (no IK)."""
    from clearcli.geometry.gripper import gripper_model
    from clearcli.geometry.models import DegenerateObject, TableFrame, build_from_columns, object_columns
    from clearcli.geometry.poses import grasp_geometry, push_geometry
    from clearcli.predicates import relations as rel
    from clearcli.settings import Settings

    s = settings if settings is not None else Settings()
    ps = s.predicates
    timings: dict[str, float] = {}
    t_all = time.perf_counter()

    t0 = time.perf_counter()
    tf = TableFrame.from_plane(seg.table)
    gripper = gripper_model(s.gripper)
    geoms = []
    skipped: list[tuple[int, str]] = []
    columns = object_columns(frame.points, [o.indices for o in seg.objects], tf, ps.model_cell_m)
    for k, cols in enumerate(columns):
        try:
            if cols is None:
                raise DegenerateObject("no finite points")
            geoms.append(
                build_from_columns(cols, k, ps)
            )
        except DegenerateObject as exc:
            log.warning("segment %d left out: %s", k, exc)
            skipped.append((k, str(exc)))
    # stable names by position, not by segmentation order
    if geoms:
        cents = np.stack([g.centroid for g in geoms])
        order = np.lexsort((cents[:, 1], cents[:, 0]))
        geoms = [geoms[int(i)] for i in order]
    timings["models"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    grasps = [grasp_geometry(g, gripper, s.push, ps.max_grasp_tilt_deg, ps.grasp_offcentre_fraction) for g in geoms]
    pushes = [push_geometry(g, gripper, s.push) for g in geoms]
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
    facts.update(("on", names[a], names[b]) for a, b in on)
    timings["on"] = time.perf_counter() - t0
    exclude = rel.related(on)
    # the gripper yaw of each grasp and push that the neighbours block least
    grasps = rel.least_blocked_grasps(geoms, grasps, gripper, exclude, ps.grasp_opening_clearance_m)
    pushes = rel.least_blocked_pushes(geoms, pushes, gripper, exclude)

    t0 = time.perf_counter()
    facts.update(("block_grasp", names[a], names[b]) for a, b in rel.block_grasp_pairs(geoms, grasps, gripper, exclude, ps.grasp_opening_clearance_m))
    timings["block_grasp"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    touching = rel.start_overlaps(geoms)
    triples = rel.block_dir_triples(geoms, pushes, gripper, exclude, touching, ps.touching_block_angle_deg)
    facts.update(("block_dir", names[a], names[b], d) for a, b, d in triples)
    timings["block_dir"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    facts.update(("ungraspable", names[i]) for i in rel.ungraspable(grasps, gripper, ps.grasp_width_margin_m))
    table_xy = tf.to_table(np.asarray(seg.table_polygon, dtype=float).reshape(-1, 3))[:, :2]
    facts.update(("push_off_table", names[i], d) for i, d in rel.push_off_table(geoms, pushes, table_xy))
    timings["static"] = time.perf_counter() - t0

    costs: dict[tuple[str, str], int] = {}
    if ps.clearance_cost:
        t0 = time.perf_counter()
        dist = rel.clearance_distances(geoms, pushes, gripper, exclude, ps.clearance_cost_distance_m)
        costs = {
            (names[i], d): rel.clearance_cost(v, ps.clearance_cost_distance_m, ps.clearance_cost_gain_per_m)
            for (i, d), v in dist.items()
        }
        timings["costs"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    objects = tuple(_object_model(names[i], g, grasps[i], pushes[i], tf) for i, g in enumerate(geoms))
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


def _object_model(
    name: str, g: "ObjectGeometry", grasp: "GraspGeometry", pushes: "dict[str, PushGeometry]", tf: "TableFrame"
) -> ObjectModel:
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
        grasp_candidates=tuple(poses(c) for c in grasp.candidates),
        pushes=push_models,
        grasp_width_m=float(grasp.width_m),
        height_m=float(g.top_height_m),
    )
