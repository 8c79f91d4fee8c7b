"""Predicate-stage figures: time per predicate family and for the whole stage.

    .venv/bin/python benchmarks/predicates.py [--repeat 31]

Scenes: mOSD test57 (16 objects) segmented by the segmentation stage, the same frame
with its ground-truth objects, and a self-made 30-object scene (boxes on a 6 x 5 grid,
random yaw and size, every fifth one stacked on its neighbour). Prints the median wall
and CPU (process) time of `compute_state` and of each family (as timed inside it), the
number of objects and facts, and the broad-phase counts: object pairs whose boxes
overlap, and push sweeps / gripper poses that reach another object's box (the narrow
phase runs only for those). Target: whole stage under 50 ms median for 16 objects.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from clearcli.predicates.state_builder import compute_state  # noqa: E402
from clearcli.predicates.synthetic import Box, make_scene, segmentation_from_labels  # noqa: E402
from clearcli.settings import Settings  # noqa: E402

SHARED = REPO.parent / "shared" / "data"
FAMILIES = ("models", "poses", "on", "block_grasp", "block_dir", "static", "export", "total")


def thirty_boxes(seed: int = 0) -> list[Box]:
    rng = np.random.default_rng(seed)
    boxes = []
    for i in range(6):
        for j in range(5):
            size = (rng.uniform(0.06, 0.14), rng.uniform(0.03, 0.08), rng.uniform(0.03, 0.12))
            x, y = -0.30 + 0.12 * i, -0.28 + 0.14 * j
            boxes.append(Box((x, y), size, yaw_deg=float(rng.uniform(0, 180))))
    # every fifth box stands on the one before it (a stack)
    for k in range(4, 30, 5):
        below = boxes[k - 1]
        boxes[k] = Box(below.center_xy, (0.06, 0.04, 0.04), yaw_deg=below.yaw_deg + 15.0, base_z=below.size[2])
    return boxes


def broad_phase_counts(frame, seg, settings) -> dict[str, int]:  # type: ignore[no-untyped-def]
    from clearcli.geometry.gripper import gripper_model
    from clearcli.geometry.models import TableFrame, build_object
    from clearcli.geometry.poses import push_geometry
    from clearcli.predicates import relations as rel

    tf = TableFrame.from_plane(seg.table)
    g = gripper_model(settings.gripper)
    objs = [build_object(frame.points[o.indices], tf, k, settings.predicates) for k, o in enumerate(seg.objects)]
    boxes = rel.aabbs(objs)
    pairs = int(np.triu(rel.overlap_matrix(boxes, boxes), 1).sum())
    pushes = [push_geometry(o, g, settings.push) for o in objs]
    swept = 0
    for b, by_dir in enumerate(pushes):
        for p in by_dir.values():
            hit = rel.overlap_matrix(rel.swept_box(objs[b], p.object_translations[-1])[None], boxes)[0]
            hit[b] = False
            swept += int(hit.sum())
    return {
        "objects": len(objs),
        "all_pairs": len(objs) * (len(objs) - 1) // 2,
        "overlapping_pairs": pairs,
        "sweep_candidates": swept,
    }


def bench(name: str, frame, seg, settings: Settings, repeat: int) -> None:  # type: ignore[no-untyped-def]
    compute_state(frame, seg, settings)  # warm-up: imports, caches
    wall, cpu, fam = [], [], {k: [] for k in FAMILIES}
    state = None
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        state = compute_state(frame, seg, settings)
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
        for k in FAMILIES:
            fam[k].append(state.timings_s.get(k, 0.0))
    assert state is not None
    counts = broad_phase_counts(frame, seg, settings)
    kinds = {}
    for f in state.facts:
        kinds[f[0]] = kinds.get(f[0], 0) + 1
    print(f"\n== {name}: {len(state.objects)} objects, {len(state.facts)} facts {dict(sorted(kinds.items()))}")
    print(f"   broad phase: {counts}")
    print(
        f"   whole stage: median wall {1e3 * statistics.median(wall):.1f} ms, CPU {1e3 * statistics.median(cpu):.1f} ms "
        f"(min wall {1e3 * min(wall):.1f} ms, {repeat} runs)"
    )
    print(
        "   per family (median wall ms): " + ", ".join(f"{k} {1e3 * statistics.median(v):.1f}" for k, v in fam.items())
    )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=31)
    args = ap.parse_args()
    if args.repeat < 21:
        ap.error("--repeat: at least 21 runs (the figures are medians)")
    settings = Settings()
    # wall figures depend on what else runs: print the load next to them
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    print(f"{os.cpu_count()} CPUs, load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    pcd = SHARED / "mosd" / "test" / "test57.pcd"
    if pcd.exists():
        from clearcli.io.read import read_frame

        frame = read_frame(pcd)
        try:
            from clearcli.perception.segment import segment

            t0 = time.perf_counter()
            seg = segment(frame, settings.segment)
            print(
                f"segmentation of test57: {len(seg.objects)} objects in {time.perf_counter() - t0:.2f} s (not counted below)"
            )
            bench("test57, segmented", frame, seg, settings, args.repeat)
        except ImportError:
            print("segmentation stage not available: test57 measured on ground-truth objects only")
        bench("test57, ground-truth objects", frame, segmentation_from_labels(frame), settings, args.repeat)
    else:
        print(f"{pcd} not found: real frame skipped")
    frame, seg = make_scene(thirty_boxes(), table_half_size_m=(0.5, 0.5))
    bench("self-made 30 boxes", frame, seg, settings, args.repeat)


if __name__ == "__main__":
    main()
