"""Segmentation under rounding-sized changes: which frames flip, and where the flip starts.

    .venv/bin/python benchmarks/stability.py [--sets mosd,uois,fixtures] [--amplitude-um 1]
        [--seeds 1] [--noise-seeds 3] [--no-noise] [--frames NAME,...] [--float32]

Every frame is segmented as read and again with every coordinate moved by a uniform
random amount in [-a, +a] (``--amplitude-um``, 1 micrometre by default: far below any
sensor's noise; float32 rounding of millimetre depth is about 0.1 micrometre), the
perturbation drawn from a fixed seed (``--float32``: the points stored as float32 first,
and the moved copy rounded to float32 as well). Both runs go through `segment`'s steps one at a
time (clearcli.perception.segment.STEPS, the refinements of refine.STAGES one by one), and
after each step the state is compared as partitions of the frame's points:

    filter       the points kept                  table      table / above it / neither
    supervoxels  the voxel of each point above the table (the voxel grid)
    edges        the pieces of the voxel graph after the depth-edge cuts
    supervoxels  the supervoxel of each point     lccp, stacks ... fragments  its segment
    objects      its object                       flat / openings  the objects again

A step "differs" when some group of points (a voxel, a supervoxel, a segment) in one
run has no group in the other at IoU >= 0.95 (groups under 30 points are too small to
judge and are not counted). Per frame it prints whether the objects are the same
(count equal, every object matched at IoU >= 0.95), the first step whose groups
differ, and the points that changed group at each step where any did.

After that, sensor-level noise: depth-proportional Gaussian noise along each pixel's ray
with sigma = 1 mm at 1 m, growing with the square of the depth (sigma(z) = 1 mm (z / 1 m)^2,
as a structured-light or stereo sensor's depth error grows), ``--noise-seeds`` draws per
frame; the share of the objects of the unperturbed frame kept at IoU >= 0.9.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from clearcli.errors import ClearError  # noqa: E402
from clearcli.io.frames import Frame  # noqa: E402
from clearcli.io.read import read_frame  # noqa: E402
from clearcli.perception import segment as seg_mod  # noqa: E402
from clearcli.perception.clock import Clock  # noqa: E402
from clearcli.perception.refine import STAGES, refine  # noqa: E402
from clearcli.perception.size import SegmentSize  # noqa: E402
from clearcli.perception.stability import (  # noqa: E402
    KEPT_IOU,
    MATCH_IOU,
    object_matches,
    perturbed,
    same_objects,
    sensor_noise,
)
from clearcli.perception.supervoxels import Supervoxels  # noqa: E402
from clearcli.settings.segment import SegmentSettings  # noqa: E402

SHARED = REPO.parent / "shared" / "data"
MIN_GROUP = 30  # points: smaller groups are not judged (a voxel, a speck)


def frame_sets(root: Path = SHARED) -> dict[str, list[Path]]:
    """The frames the stability target names: the 50 mOSD frames, the nine uois RealSense
    frames and the fixtures' PCDs; and "scenes", the other labs' frames in
    ../shared/data/scenes (gqcnn, cleargrasp_d435, pcl, industrial), which the target
    does not name but which a user's frames resemble more than mOSD's."""
    mosd = sorted((root / "mosd/learn").glob("*.pcd")) + sorted((root / "mosd/test").glob("*.pcd"))
    return {
        "mosd": mosd,
        "uois": sorted((root / "scenes/uois_realsense").glob("*.pcd")),
        "fixtures": sorted((REPO / "fixtures").glob("*.pcd")),
        "scenes": sorted(
            p for d in ("gqcnn", "cleargrasp_d435", "pcl", "industrial") for p in (root / "scenes" / d).rglob("*.pcd")
        ),
    }


def _partition_diff(a: np.ndarray, b: np.ndarray) -> tuple[int, int]:
    """Two labellings of the same points (-1: in no group): (groups of at least MIN_GROUP
    points, in either, without a partner at IoU >= MATCH_IOU; points whose group changed,
    counted as those outside the best partner of their group in ``a``)."""
    if a.shape != b.shape:
        return -1, -1
    ua, ia = np.unique(a, return_inverse=True)
    ub, ib = np.unique(b, return_inverse=True)
    na, nb = ua.size, ub.size
    pair = ia.astype(np.int64) * nb + ib
    pu, pc = np.unique(pair, return_counts=True)
    pa, pb = pu // nb, pu % nb
    size_a = np.bincount(ia, minlength=na)
    size_b = np.bincount(ib, minlength=nb)
    iou = pc / (size_a[pa] + size_b[pb] - pc)
    best_a = np.zeros(na)
    np.maximum.at(best_a, pa, iou)
    best_b = np.zeros(nb)
    np.maximum.at(best_b, pb, iou)
    judged_a = (size_a >= MIN_GROUP) & (ua >= 0)
    judged_b = (size_b >= MIN_GROUP) & (ub >= 0)
    unmatched = int(((best_a < MATCH_IOU) & judged_a).sum() + ((best_b < MATCH_IOU) & judged_b).sum())
    keep_a = np.zeros(na)
    np.maximum.at(keep_a, pa, pc)
    moved = int(a.size - keep_a.sum())
    return unmatched, moved


def trace(frame: Frame, settings: SegmentSettings) -> Iterator[tuple[str, np.ndarray]]:
    """`segment`'s steps one at a time; after each, (its name, a labelling of the frame's
    points: the groups that step leaves, -1 outside them)."""
    organized = frame.is_organized and frame.shape is not None and frame.shape[0] * frame.shape[1] == frame.n_points
    w = seg_mod._Work(frame, settings, organized, Clock())
    n = frame.n_points

    def over_frame(idx: np.ndarray, labels: np.ndarray) -> np.ndarray:
        out = np.full(n, -1, dtype=np.int64)
        out[idx] = labels
        return out

    def objects() -> np.ndarray:
        out = np.full(n, -1, dtype=np.int64)
        for k, o in enumerate(w.objects):
            out[o.indices] = k
        return out

    def components() -> np.ndarray:
        from clearcli.perception.graph import components as _components

        assert w.vox is not None
        return over_frame(w.obj_idx, _components(w.vox.n_voxels, w.vox.edges)[w.vox.point_voxel])

    views: dict[str, Callable[[], np.ndarray]] = {
        "filter": lambda: over_frame(w.idx, np.zeros(w.idx.size, dtype=np.int64)),
        "table": lambda: over_frame(w.idx, np.where(w.table_mask, 0, np.where(w.prism_mask, 1, -1))),
        "voxels": lambda: over_frame(w.obj_idx, w.vox.point_voxel) if w.vox is not None else np.full(n, -1),
        "edges": components,
        "supervoxels": lambda: (
            over_frame(w.obj_idx, w.sv.voxel_label[w.vox.point_voxel])  # type: ignore[union-attr]
            if w.sv is not None
            else np.full(n, -1)
        ),
        "segments": lambda: over_frame(w.obj_idx, w.seg_of_voxel[w.vox.point_voxel]),  # type: ignore[union-attr]
        "objects": objects,
    }
    for step in seg_mod.STEPS:
        if step.above_table and w.vox is None:
            continue
        if step.run is seg_mod._refine:
            ctx = w.ctx  # _lccp's, as _refine reads it
            assert ctx is not None
            for stage in STAGES:
                w.seg_of_voxel = refine(w.seg_of_voxel, ctx, None, (stage,))
                yield stage.name, views["segments"]()
            continue
        step.run(w)
        name = {
            seg_mod._voxels: "voxels",
            seg_mod._supervoxels: "supervoxels",
            seg_mod._lccp: "lccp",
        }.get(step.run, step.name or "?")
        view = views.get(name, views["segments"] if name == "lccp" else objects)
        yield name, view()


def _refused(frame: Frame, settings: SegmentSettings) -> bool:
    try:
        seg_mod.segment(frame, settings)
    except ClearError:
        return True
    return False


def first_difference(frame: Frame, other: Frame, settings: SegmentSettings) -> list[tuple[str, int, int]]:
    """Per step: (name, groups without a partner, points that changed group)."""
    from clearcli.perception.resolution import WorkingGrid

    # segment works on the working grid (every k-th row and column of a frame far denser
    # than the voxels, a 1280x720 one): trace that grid, as segment sees it
    frame, other = WorkingGrid.of(frame, settings, None).frame, WorkingGrid.of(other, settings, None).frame
    out = []
    for (name, a), (_, b) in zip(trace(frame, settings), trace(other, settings)):
        unmatched, moved = _partition_diff(a, b)
        out.append((name, unmatched, moved))
    return out


def _run_until(frame: Frame, settings: SegmentSettings, through_supervoxels: bool) -> Any:
    """`segment`'s work on ``frame`` up to the supervoxels (``through_supervoxels``: with
    them), or None when no voxel stands above the table."""
    from clearcli.perception.resolution import WorkingGrid

    f = WorkingGrid.of(frame, settings, None).frame
    organized = f.is_organized and f.shape is not None and f.shape[0] * f.shape[1] == f.n_points
    w = seg_mod._Work(f, settings, organized, Clock())
    for step in seg_mod.STEPS:
        if step.run is seg_mod._supervoxels and not through_supervoxels:
            break
        if step.above_table and w.vox is None:
            return None
        step.run(w)
        if step.run is seg_mod._supervoxels:
            break
    return w


def voxel_difference(frame: Frame, other: Frame, settings: SegmentSettings) -> str:
    """Where a supervoxel flip starts (issue 37): the voxels one run has and the other
    not (with their point counts), the voxels whose point count changed, how far the
    voxel normals of the voxels both have turned, and how many of those voxels changed
    supervoxel (the most voxels of each supervoxel of the first run kept together)."""
    from clearcli.perception.supervoxels import grid_cells, stage_voxel_normals, supervoxel_labels

    runs = []
    for f in (frame, other):
        w = _run_until(f, settings, through_supervoxels=False)
        if w is None:
            return "no voxels"
        assert w.vox is not None and w.size is not None and w.fit is not None
        viewpoint = np.zeros(3) if w.fit.camera_is_origin else w.fit.polygon.mean(axis=0) + w.fit.plane.normal
        normals = stage_voxel_normals(w.vox, viewpoint, settings, w.size)
        labels = supervoxel_labels(w.vox, normals, settings, w.size)
        # a voxel's cell from its centroid: the grid's cell of every point in it
        cells = grid_cells(w.vox.centroids, w.size.voxel_m)
        runs.append(({tuple(c): i for i, c in enumerate(cells.tolist())}, w.vox.counts, normals, labels))
    (ka, ca, na, la), (kb, cb, nb, lb) = runs
    only_a = [ca[i] for k, i in ka.items() if k not in kb]
    only_b = [cb[i] for k, i in kb.items() if k not in ka]
    both = [(i, kb[k]) for k, i in ka.items() if k in kb]
    ia = np.array([i for i, _ in both], dtype=np.int64)
    ib = np.array([j for _, j in both], dtype=np.int64)
    turn = np.degrees(np.arccos(np.clip(np.abs(np.sum(na[ia] * nb[ib], axis=1)), 0.0, 1.0)))
    n_b = int(lb.max()) + 1
    uniq, count = np.unique(la[ia] * n_b + lb[ib], return_counts=True)
    kept = np.zeros(int(la.max()) + 1)
    np.maximum.at(kept, uniq // n_b, count)
    moved_sv = int(ia.size - kept.sum())
    return (
        f"voxels only before {len(only_a)} (points {sorted(int(c) for c in only_a)}), only after {len(only_b)} "
        f"(points {sorted(int(c) for c in only_b)}), point count changed {int((ca[ia] != cb[ib]).sum())}; "
        f"normals turned > 1 deg {int((turn > 1).sum())}, most {turn.max(initial=0.0):.2f} deg; "
        f"voxels that changed supervoxel {moved_sv}"
    )


def supervoxel_decisions(frame: Frame, other: Frame, settings: SegmentSettings, most: int = 8) -> list[str]:
    """The supervoxel stage's first decisions that differ between two runs (issue 37),
    each with its margin: the voxels both runs have are matched by their cells and the
    seeds by their seed voxel's cell; then (1) the seed voxels that lost or gained points
    (their centroid moved) or whose normal turned more than 0.5 degree (a seed's first
    normal is its voxel's), and the seeds one run has and the other not; (2) per
    assignment (`supervoxel_labels`' trace), the voxels whose seed changed, the ``most``
    of them nearest a tie first: their points, the turn of their own normal and the cost
    margin to the runner-up in each run (a margin of 1e-4 is 3 um of distance at the 3 cm
    seed, or a fraction of a degree of normal)."""
    from clearcli.perception.supervoxels import grid_cells, stage_voxel_normals, supervoxel_labels

    runs = []
    for f in (frame, other):
        w = _run_until(f, settings, through_supervoxels=False)
        if w is None:
            return ["no voxels"]
        assert w.vox is not None and w.size is not None and w.fit is not None
        viewpoint = np.zeros(3) if w.fit.camera_is_origin else w.fit.polygon.mean(axis=0) + w.fit.plane.normal
        normals = stage_voxel_normals(w.vox, viewpoint, settings, w.size)
        trace: list[np.ndarray] = []
        supervoxel_labels(w.vox, normals, settings, w.size, trace=trace)
        cells = [tuple(c) for c in grid_cells(w.vox.centroids, w.size.voxel_m).tolist()]
        runs.append((w.vox, normals, trace, cells))
    (va, na, ta, ca), (vb, nb, tb, cb) = runs
    row_b = {c: i for i, c in enumerate(cb)}
    both = np.array([(i, row_b[c]) for i, c in enumerate(ca) if c in row_b], dtype=np.int64).reshape(-1, 2)
    ia, ib = both[:, 0], both[:, 1]
    turn = np.zeros(va.n_voxels)
    turn[ia] = np.degrees(np.arccos(np.clip(np.abs(np.sum(na[ia] * nb[ib], axis=1)), 0.0, 1.0)))
    seeds_a = {ca[v]: s for s, v in enumerate(ta[0].tolist())}
    seeds_b = {cb[v]: s for s, v in enumerate(tb[0].tolist())}
    lines = []
    for cell, s in seeds_a.items():
        if cell not in seeds_b:
            lines.append(f"seed {s} (voxel {cell}) only before")
            continue
        v, u = int(ta[0][s]), int(tb[0][seeds_b[cell]])
        moved = float(np.linalg.norm(va.centroids[v] - vb.centroids[u])) * 1e3
        if va.counts[v] != vb.counts[u] or turn[v] > 0.5:
            lines.append(
                f"seed {s} (voxel {cell}): {va.counts[v]} -> {vb.counts[u]} points, moved {moved:.3f} mm, "
                f"its normal turned {turn[v]:.2f} deg"
            )
    lines += [f"seed {s} (voxel {cell}) only after" for cell, s in seeds_b.items() if cell not in seeds_a]
    # a seed's name in both runs: its seed voxel's cell (seeds without a partner: none)
    name_a = np.array([hash(ca[v]) for v in ta[0].tolist()] + [0], dtype=np.int64)
    name_b = np.array([hash(cb[v]) for v in tb[0].tolist()] + [0], dtype=np.int64)
    for it in range(1, len(ta), 2):
        la, ma, lb, mb = ta[it], ta[it + 1], tb[it], tb[it + 1]
        changed = np.flatnonzero(name_a[la[ia]] != name_b[lb[ib]])
        changed = changed[np.argsort(ma[ia[changed]], kind="stable")]
        lines.append(f"assignment {it // 2 + 1}: {changed.size} voxels changed seed")
        for j in changed[:most].tolist():
            v, u = int(ia[j]), int(ib[j])
            lines.append(
                f"    voxel {ca[v]}: seed {la[v]} -> {lb[u]}, {va.counts[v]} -> {vb.counts[u]} points, normal "
                f"turned {turn[v]:.2f} deg, cost margin {ma[v]:.3g} -> {mb[u]:.3g}"
            )
    return lines


def _lccp_tests(sv: Supervoxels, settings: SegmentSettings, size: SegmentSize) -> dict[str, np.ndarray]:
    """Per supervoxel adjacency, each of lccp.convex_edges' tests as a margin (>= 0 passes, in
    its own unit: metres for smoothness, degrees for the rest): "smoothness" (the offset along
    the normals under its allowance), "convexity" (angle(d, n2) - angle(d, n1)), "tolerance"
    (the concavity tolerance minus the normals' angle), "sanity" (the angle of d to n1 x n2 over
    its threshold); and "facing" (n1 . n2: the sign flips when one normal's orientation does)."""
    from clearcli.perception.lccp import _angle_deg

    e = sv.edges
    n1, n2 = sv.normals[e[:, 0]], sv.normals[e[:, 1]]
    d = sv.centroids[e[:, 0]] - sv.centroids[e[:, 1]]
    normal_angle = _angle_deg(n1, n2)
    ncross = np.cross(n1, n2)
    offset = np.minimum(np.abs(np.einsum("ij,ij->i", d, n1)), np.abs(np.einsum("ij,ij->i", d, n2)))
    inter = _angle_deg(ncross, d)
    return {
        "smoothness": np.linalg.norm(ncross, axis=1) * size.seed_m
        + settings.smoothness_threshold * size.voxel_m
        - offset,
        "convexity": _angle_deg(d, n2) - _angle_deg(d, n1),
        "tolerance": settings.concavity_tolerance_deg - normal_angle,
        "sanity": np.minimum(inter, 180.0 - inter) - 60.0 / (1.0 + np.exp(-0.25 * (normal_angle - 25.0))),
        "facing": np.einsum("ij,ij->i", n1, n2),
    }


def lccp_difference(frame: Frame, other: Frame, settings: SegmentSettings) -> str:
    """Which of LCCP's tests changed its answer (issue 37): the supervoxels of both runs
    matched by their voxels' cells (IoU >= 0.7), and on the adjacencies both runs have, the
    tests whose margin changed sign, with the least margin each had before."""
    from clearcli.perception.supervoxels import grid_cells

    runs = []
    for f in (frame, other):
        w = _run_until(f, settings, through_supervoxels=True)
        if w is None:
            return "no voxels"
        assert w.vox is not None and w.sv is not None and w.size is not None
        voxel_cells = grid_cells(w.vox.centroids, w.size.voxel_m)
        groups: dict[int, set[tuple[int, ...]]] = {}
        for cell, label in zip(map(tuple, voxel_cells.tolist()), w.sv.voxel_label.tolist()):
            groups.setdefault(label, set()).add(cell)
        runs.append((groups, w.sv, _lccp_tests(w.sv, settings, w.size)))
    (ga, sva, ta), (gb, svb, tb) = runs
    owner_b = {cell: label for label, cells in gb.items() for cell in cells}
    partner: dict[int, int] = {}
    for label, cells in ga.items():
        hits: dict[int, int] = {}
        for cell in cells:
            if cell in owner_b:
                hits[owner_b[cell]] = hits.get(owner_b[cell], 0) + 1
        if hits:
            best = max(hits, key=lambda k: hits[k])
            if hits[best] / (len(cells) + len(gb[best]) - hits[best]) >= 0.7:
                partner[label] = best
    row_b = {(int(a), int(b)): i for i, (a, b) in enumerate(svb.edges.tolist())}
    flips: dict[str, list[float]] = {name: [] for name in ta}
    for i, (a, b) in enumerate(sva.edges.tolist()):
        if a not in partner or b not in partner:
            continue
        j = row_b.get((min(partner[a], partner[b]), max(partner[a], partner[b])))
        if j is None:
            continue
        for name in ta:
            if (ta[name][i] >= 0) != (tb[name][j] >= 0):
                flips[name].append(abs(float(ta[name][i])))
    changed = len(ga) - len(partner)
    said = ", ".join(f"{name} {len(m)} (least {min(m):.3g})" for name, m in flips.items() if m) or "none"
    return f"supervoxels without a partner {changed}; LCCP tests that changed answer on shared adjacencies: {said}"


def _lccp_state(frame: Frame, settings: SegmentSettings) -> Any:
    """`segment`'s work on ``frame`` through LCCP (its segments in ``seg_of_voxel``), with
    each voxel's cell and, when the frame's colour is used, each supervoxel's CIELAB
    colour as `segment._lccp` works it out; None when no voxel stands above the table."""
    from clearcli.perception.flat import group_lab
    from clearcli.perception.supervoxels import grid_cells

    w = _run_until(frame, settings, through_supervoxels=True)
    if w is None:
        return None
    assert w.vox is not None and w.sv is not None and w.size is not None
    seg_mod._lccp(w)
    sv_lab = None
    if w.color_used and settings.lccp_color_delta > 0:
        assert w.frame.colors is not None
        colors = np.take(w.frame.colors, w.obj_idx, axis=0)
        sv_lab = group_lab(w.sv.voxel_label[w.vox.point_voxel], colors, w.sv.centroids.shape[0])
    cells = [tuple(c) for c in grid_cells(w.vox.centroids, w.size.voxel_m).tolist()]
    return w, cells, sv_lab


def _spread_ratio(centroids: np.ndarray) -> float:
    """The second over the least eigenvalue of the scatter of a supervoxel's voxel
    centroids (supervoxel_stats uses PCA's normal above 4)."""
    d = centroids - centroids.mean(axis=0)
    evals = np.linalg.eigvalsh(d.T @ d)
    return float(evals[1] / max(evals[0], 1e-12))


def decisive_edges(frame: Frame, other: Frame, settings: SegmentSettings) -> list[str]:
    """Where LCCP's answer changed (issue 37), with how near its threshold each test was.

    The supervoxels of both runs are matched by their voxels' cells (each of ``frame``'s to
    the one of ``other``'s holding most of its cells); on every adjacency both runs have, the
    edge is "decisive" when its two supervoxels end in one LCCP segment in one run and in two
    in the other, and its own convexity answer (`lccp.convex_edges`, colour included)
    changed. Per decisive edge: the supervoxels' sizes (voxels) and IoU with their partners
    (a supervoxel that lost or gained a voxel moves its centroid and normal: the margins
    then move by far more than the micrometre the points did), and each test of
    `_lccp_tests` whose sign changed, its margin before -> after; per supervoxel of those
    edges that changed, its voxels, the eigenvalue ratio that picks its normal's source,
    and how far its normal turned. The last line: the
    supervoxels without a partner at IoU >= 0.95, and the least |margin before| of the
    tests that changed on decisive edges (a margin rule must reach that far to catch it)."""
    from clearcli.perception.lccp import convex_edges

    runs = [_lccp_state(f, settings) for f in (frame, other)]
    if runs[0] is None or runs[1] is None:
        return ["no voxels"]
    (wa, cells_a, lab_a), (wb, cells_b, lab_b) = runs
    la, lb = wa.sv.voxel_label, wb.sv.voxel_label
    owner_b = dict(zip(cells_b, lb.tolist(), strict=True))
    size_a = np.bincount(la)
    size_b = np.bincount(lb)
    hits: dict[tuple[int, int], int] = {}
    for cell, label in zip(cells_a, la.tolist(), strict=True):
        if cell in owner_b:
            hits[label, owner_b[cell]] = hits.get((label, owner_b[cell]), 0) + 1
    partner: dict[int, tuple[int, float]] = {}
    for (a, b), h in hits.items():
        if a not in partner or h > hits[a, partner[a][0]]:
            partner[a] = (b, h / (size_a[a] + size_b[b] - h))
    tests_a = _lccp_tests(wa.sv, settings, wa.size)
    tests_b = _lccp_tests(wb.sv, settings, wb.size)
    convex_a = convex_edges(wa.sv, settings, wa.size, lab_a, wa.vox)
    convex_b = convex_edges(wb.sv, settings, wb.size, lab_b, wb.vox)
    seg_a = np.zeros(size_a.size, dtype=np.int64)
    seg_a[la] = wa.seg_of_voxel
    seg_b = np.zeros(size_b.size, dtype=np.int64)
    seg_b[lb] = wb.seg_of_voxel
    row_b = {(int(a), int(b)): i for i, (a, b) in enumerate(wb.sv.edges.tolist())}
    unit = {"smoothness": 1e3}  # metres shown as mm; the angles in degrees
    lines = []
    least = np.inf
    for i, (a, b) in enumerate(wa.sv.edges.tolist()):
        if a not in partner or b not in partner:
            continue
        (pa, iou_a), (pb, iou_b) = partner[a], partner[b]
        j = row_b.get((min(pa, pb), max(pa, pb)))
        if j is None or (seg_a[a] == seg_a[b]) == (seg_b[pa] == seg_b[pb]) or convex_a[i] == convex_b[j]:
            continue
        changed = []
        for name, before in tests_a.items():
            if name != "facing" and (before[i] >= 0) != (tests_b[name][j] >= 0):
                k = unit.get(name, 1.0)
                changed.append(f"{name} {before[i] * k:+.3g} -> {tests_b[name][j] * k:+.3g}")
                least = min(least, abs(float(before[i]) * k))
        lines.append(
            f"edge {a}-{b} (voxels {size_a[a]},{size_a[b]}; IoU {iou_a:.2f},{iou_b:.2f}): convex "
            f"{bool(convex_a[i])} -> {bool(convex_b[j])}; " + ("; ".join(changed) or "colour only")
        )
    # the supervoxels of the decisive edges that changed: their normal's source (supervoxel_stats
    # takes the PCA normal when the second eigenvalue exceeds 4 x the first, else the mean voxel normal)
    touched = sorted({int(x) for line in lines for x in line.split()[1].split("-")})
    for s in touched:
        pb, iou = partner[s]
        if iou >= 1.0:
            continue
        ra, rb = _spread_ratio(wa.vox.centroids[la == s]), _spread_ratio(wb.vox.centroids[lb == pb])
        turn = np.degrees(np.arccos(np.clip(abs(float(wa.sv.normals[s] @ wb.sv.normals[pb])), 0.0, 1.0)))
        lines.append(
            f"supervoxel {s}: {size_a[s]} -> {size_b[pb]} voxels, eigenvalue ratio {ra:.2f} -> {rb:.2f} (PCA normal "
            f"over 4, mean voxel normal under), its normal turned {turn:.1f} deg"
        )
    moved = sorted((int(s), int(size_a[s])) for s in range(size_a.size) if partner.get(s, (0, 0.0))[1] < 0.95)
    n_edges = sum(line.startswith("edge") for line in lines)
    lines.append(
        f"supervoxels (label, voxels) without a partner at IoU >= 0.95: {moved}; decisive edges {n_edges}; "
        f"least |margin| before of a changed test: {least:.3g} (mm or deg)"
    )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sets", default="mosd,uois,fixtures")
    parser.add_argument("--amplitude-um", type=float, default=1.0)
    parser.add_argument("--seeds", type=int, default=1, help="perturbations per frame")
    parser.add_argument("--noise-seeds", type=int, default=3, help="sensor-noise draws per frame")
    parser.add_argument("--no-noise", action="store_true")
    parser.add_argument("--frames", default="", help="only frames whose file name is in this list")
    parser.add_argument("--quiet", action="store_true", help="print only the frames that differ")
    parser.add_argument(
        "--float32",
        action="store_true",
        help="store every frame's points as float32 first (a float64 frame rounded as a float32 file would hold it)",
    )
    args = parser.parse_args()
    settings = SegmentSettings()
    sets = frame_sets()
    wanted = {s for s in args.frames.split(",") if s}
    amp = args.amplitude_um * 1e-6
    totals: dict[str, tuple[int, int]] = {}
    kept_share: dict[str, list[float]] = {}
    first_steps: dict[str, int] = {}
    times: list[float] = []
    for set_name in args.sets.split(","):
        paths = [p for p in sets[set_name] if not wanted or p.name in wanted or p.stem in wanted]
        if not paths:
            print(f"{set_name}: no frames here")
            continue
        flipped = 0
        print(f"{set_name} ({len(paths)} frames), +-{args.amplitude_um:g} um:")
        for path in paths:
            frame = read_frame(path)
            if args.float32:
                frame = dataclasses.replace(frame, points=frame.points.astype(np.float32))
            t0 = time.perf_counter()
            try:
                base = seg_mod.segment(frame, settings)
            except ClearError as err:
                # a frame the segmenter refuses (no table in view) must be refused as well
                # when moved by a micrometre: that is "the same" answer
                refused = sum(_refused(perturbed(frame, amp, seed=s), settings) for s in range(args.seeds))
                if refused < args.seeds:
                    flipped += 1
                verdict = "refused  " if refused == args.seeds else "DIFFERENT"
                print(f"  {path.name:24s} {verdict} ({refused} of {args.seeds} moved copies refused too: {err})")
                continue
            times.append(time.perf_counter() - t0)
            bad_seeds = []
            for s in range(args.seeds):
                try:
                    moved = seg_mod.segment(perturbed(frame, amp, seed=s), settings)
                except ClearError:  # refused when moved, segmented as read: different
                    bad_seeds.append(s)
                    continue
                if not same_objects(base, moved):
                    bad_seeds.append(s)
            if not bad_seeds:
                if not args.quiet:
                    print(f"  {path.name:24s} same      ({len(base.objects)} objects)")
            else:
                flipped += 1
                other = perturbed(frame, amp, seed=bad_seeds[0])
                try:
                    changed = seg_mod.segment(other, settings)
                except ClearError as err:
                    print(f"  {path.name:24s} DIFFERENT (moved copy seed {bad_seeds[0]} refused: {err})")
                    continue
                steps = first_difference(frame, other, settings)
                first = next((name for name, unmatched, _ in steps if unmatched > 0), "objects")
                first_steps[first] = first_steps.get(first, 0) + 1
                chain = ", ".join(f"{name} {unmatched}/{moved}" for name, unmatched, moved in steps if moved)
                print(
                    f"  {path.name:24s} DIFFERENT ({len(base.objects)} vs {len(changed.objects)} objects, "
                    f"seeds {bad_seeds}); first differing step: {first}"
                )
                print(f"      groups unmatched/points moved: {chain}")
                print(f"      {voxel_difference(frame, other, settings)}")
                print(f"      {lccp_difference(frame, other, settings)}")
            if not args.no_noise:
                for s in range(args.noise_seeds):
                    try:
                        noisy = seg_mod.segment(sensor_noise(frame, 1e-3, seed=100 + s), settings)
                    except ClearError as err:  # the noisy copy refused: none of its objects kept
                        print(f"  {path.name:24s} noise draw {s} refused ({err})")
                        kept_share.setdefault(set_name, []).extend([0.0] * len(base.objects))
                        continue
                    m = object_matches(base, noisy)
                    kept_share.setdefault(set_name, []).extend((m >= KEPT_IOU).astype(float).tolist())
        totals[set_name] = (flipped, len(paths))
    print()
    for set_name, (flipped, n) in totals.items():
        print(f"{set_name:9s} frames with other objects under +-{args.amplitude_um:g} um: {flipped} of {n}")
    if first_steps:
        print("first differing step:", ", ".join(f"{k} {v}" for k, v in sorted(first_steps.items())))
    if kept_share:
        print(
            f"sensor noise (Gaussian along the ray, sigma 1 mm at 1 m growing with depth^2), "
            f"{args.noise_seeds} draws a frame: objects kept at IoU >= {KEPT_IOU}:"
        )
        for set_name, kept in kept_share.items():
            print(f"  {set_name:9s} {100 * np.mean(kept):5.1f} % of {len(kept)}")
    if times:
        print(f"segment time (unperturbed, first frame cold): median {np.median(times) * 1000:.0f} ms")


if __name__ == "__main__":
    main()
