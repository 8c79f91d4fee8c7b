"""Paired A/B timing of `segment` per step: two checkouts of clearcli in one process.

    .venv/bin/python benchmarks/ab.py OLD_TREE [NEW_TREE] [--runs 5] [--frames cluttered|all|uois|NAME,...]

OLD_TREE and NEW_TREE are checkouts (NEW_TREE defaults to this one). Both are imported
into this process, each with its own `clearcli` modules (swapped in `sys.modules` round
each call, so the imports made inside functions find their own tree's). On each frame the
two sides run in turn, ``--runs`` times each, interleaved (old, new, old, new, ...), and
each step keeps the minimum over the runs. NumPy's BLAS runs one thread, as in `clear`. The steps' clocks (perception/clock.py, and
resolution.py's) read the thread's CPU time instead of the wall clock: the machine is
shared, and another process's work does not count in the thread's time.

Prints per frame the total of each side, then per step: the sum over the frames (ms),
the least-squares slope over mOSD's ground-truth object count (ms per object) and the
fitted time at 3 and 15 objects, old and new. Each frame's objects and table are
compared between the sides: any difference is reported (the change was to keep them).

Frames: mOSD's 50 ("all"), or the cluttered 6 ("cluttered": those with 5 or more
objects, benchmarks/pcl.py's "mosd_cluttered": learn33 and the 5 test frames), or the
nine RealSense 640x480 frames ("uois", benchmarks/pcl.py's "realsense_640x480"; no ground
truth: their object count is clear's, and the per-object fit reads it).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import types
from pathlib import Path

# one BLAS thread, as `clear` itself runs (clearcli/startup.py), before NumPy loads: with
# OpenBLAS's threads a large product waits for its worker on a busy machine, and the
# sides' times measured that wait instead of the work `clear` does (stop 57)
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent.parent
DATA = HERE.parent / "shared" / "data" / "mosd"
UOIS = HERE.parent / "shared" / "data" / "scenes" / "uois_realsense"


class Side:
    """One checkout's clearcli, imported into this process."""

    def __init__(self, tree: Path) -> None:
        self.tree = str(tree)
        self.modules: dict[str, types.ModuleType] = {}
        self.activate()
        import clearcli.io.read as read
        import clearcli.perception.clock as clock
        import clearcli.perception.resolution as resolution
        import clearcli.perception.segment as seg
        import clearcli.settings.segment as settings

        thread_clock = types.SimpleNamespace(perf_counter=time.thread_time)
        clock.time = thread_clock  # type: ignore[attr-defined]
        resolution.time = thread_clock  # type: ignore[attr-defined]
        self.read_frame = read.read_frame
        self.segment = seg.segment
        self.settings = settings.SegmentSettings()
        self.stash()

    def activate(self) -> None:
        for name in [k for k in sys.modules if k == "clearcli" or k.startswith("clearcli.")]:
            del sys.modules[name]
        sys.modules.update(self.modules)
        sys.path[:] = [self.tree] + [p for p in sys.path if p != self.tree]

    def stash(self) -> None:
        self.modules = {k: v for k, v in sys.modules.items() if k == "clearcli" or k.startswith("clearcli.")}

    def run(self, frame: object) -> object:
        self.activate()
        try:
            return self.segment(frame, self.settings)
        finally:
            self.stash()  # modules first imported inside the call stay with this side


def truth_objects(frame: object) -> int:
    """mOSD's ground-truth object count; -1 for a frame without labels."""
    if "label" not in frame.fields:  # type: ignore[attr-defined]
        return -1
    labels = frame.fields["label"]  # type: ignore[attr-defined]
    ids = np.unique(np.asarray(labels).astype(np.int64).ravel() // 10)
    return int((ids >= 1).sum())


def same(a: object, b: object) -> str:
    """'' when the two segmentations agree, else what differs."""
    if len(a.objects) != len(b.objects):  # type: ignore[attr-defined]
        return f"{len(a.objects)} vs {len(b.objects)} objects"  # type: ignore[attr-defined]
    for k, (oa, ob) in enumerate(zip(a.objects, b.objects, strict=True)):  # type: ignore[attr-defined]
        if not np.array_equal(oa.indices, ob.indices):
            return f"object {k}: indices differ"
        for f in ("centroid", "obb_center", "obb_axes", "obb_extents", "principal_axes"):
            if not np.array_equal(getattr(oa, f), getattr(ob, f)):
                return f"object {k}: {f} differs"
    if not np.array_equal(a.table_indices, b.table_indices):  # type: ignore[attr-defined]
        return "table indices differ"
    if len(a.excluded) != len(b.excluded):  # type: ignore[attr-defined]
        return "excluded differ"
    return ""


def frame_paths(which: str) -> list[Path]:
    learn = [DATA / "learn" / f"learn{i}.pcd" for i in range(45)]
    test = [DATA / "test" / f"test{i}.pcd" for i in (44, 46, 47, 55, 57)]
    if which == "all":
        return learn + test
    if which == "cluttered":
        return [DATA / "learn" / "learn33.pcd"] + test
    if which == "uois":
        return sorted(UOIS.glob("uois_image_*.pcd"))
    return [p for p in learn + test if p.stem in which.split(",")]


def fit(counts: np.ndarray, ms: np.ndarray) -> tuple[float, float]:
    """(slope ms per object, intercept) of the least-squares line."""
    if np.ptp(counts) == 0:
        return 0.0, float(ms.mean())
    slope, icpt = np.polyfit(counts, ms, 1)
    return float(slope), float(icpt)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("old", type=Path)
    ap.add_argument("new", type=Path, nargs="?", default=HERE)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--frames", default="cluttered")
    opts = ap.parse_args()

    sides = [Side(opts.old), Side(opts.new)]
    paths = frame_paths(opts.frames)
    warm = sides[0].read_frame(paths[0])
    for s in sides:
        s.run(warm)  # imports made inside functions, first calls
    names: list[str] = []
    rows = []  # (name, truth, [per side: {step: min s}])
    for path in paths:
        frame = sides[0].read_frame(path)
        n_truth = truth_objects(frame)
        best: list[dict[str, float]] = [{}, {}]
        results = [None, None]
        for _ in range(opts.runs):
            for k, s in enumerate(sides):
                seg = s.run(frame)
                results[k] = seg
                for step, t in seg.timings_s.items():  # type: ignore[attr-defined]
                    best[k][step] = min(best[k].get(step, np.inf), t)
        diff = same(results[0], results[1])
        if n_truth < 0:  # no labels: the object count clear finds (the same on both sides)
            n_truth = len(results[0].objects)  # type: ignore[attr-defined]
        for step in best[0]:
            if step not in names:
                names.append(step)
        rows.append((path.stem, n_truth, best))
        print(
            f"{path.stem:<8} truth {n_truth:>2}  total old {best[0]['total'] * 1e3:7.1f} ms  new "
            f"{best[1]['total'] * 1e3:7.1f} ms  new/old {best[1]['total'] / best[0]['total']:.3f}"
            + (f"  DIFFERS: {diff}" if diff else ""),
            flush=True,
        )
    counts = np.array([r[1] for r in rows], dtype=float)
    print(f"\n{len(rows)} frames, thread CPU time, min of {opts.runs} interleaved runs per side")
    print(
        f"{'step':<12} {'old ms':>9} {'new ms':>9} {'new/old':>7} {'old /obj':>9} {'new /obj':>9}"
        f" {'old @3':>7} {'old @15':>7} {'new @3':>7} {'new @15':>7}"
    )
    for step in names:
        per = [np.array([r[2][k].get(step, 0.0) for r in rows]) * 1e3 for k in (0, 1)]
        (so, io), (sn, inn) = fit(counts, per[0]), fit(counts, per[1])
        tot_o, tot_n = per[0].sum(), per[1].sum()
        ratio = tot_n / tot_o if tot_o > 0 else float("nan")
        print(
            f"{step:<12} {tot_o:9.1f} {tot_n:9.1f} {ratio:7.3f} {so:9.3f} {sn:9.3f}"
            f" {io + 3 * so:7.1f} {io + 15 * so:7.1f} {inn + 3 * sn:7.1f} {inn + 15 * sn:7.1f}"
        )


if __name__ == "__main__":
    main()
