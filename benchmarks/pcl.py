"""`clear`'s segmentation side by side with PCL's supervoxels + LCCP pipeline.

    .venv/bin/python benchmarks/pcl.py [--runs N] [--per-set K] [--sets mosd_simple,...]

The PCL side is benchmarks/pcl/pcl_segment.cpp (NaN removal, statistical outlier
removal, RANSAC plane, convex hull + polygonal prism, supervoxels, LCCP), built here
with g++ into benchmarks/pcl/build/ when the binary is missing or older than its source;
it needs PCL's development files (Debian: `apt-get install libpcl-dev`) and pkg-config.
Without them the benchmark says why and stops (exit 0: a skip, not a failure).

The sets (shared data, $CLEAR_SHARED else ../shared/data):
- mosd_simple: mOSD frames whose ground truth holds 2-3 objects;
- mosd_cluttered: mOSD frames with 5 or more (the test split's five frames: 5, 6, 6, 14
  and 16 objects by their labels; learn33: 5);
- realsense_640x480: scenes/uois_realsense (9 frames);
- realsense_1280x720: scenes/cleargrasp_d435 (4 frames).

Per frame, interleaved: the PCL program runs the frame N times in one process (its own
timings: read + every stage), then `clear` reads and segments it N times in this
process (`clearcli.pipeline.read` + `segmented`, default settings; warm: one untimed
frame first, so imports and first calls are excluded). Printed per frame: the medians,
their ratio clear/PCL, and the object counts (ground truth, clear, PCL's LCCP segments of
at least 300 points); per set: the median of the frames' medians and ratios, also
against PCL without its outlier stage (most of its time); over all mOSD frames run, each
side's time against the ground-truth object count (a least-squares line: its slope and
its values at 3 and 15 objects), so growth with clutter shows.

Both sides run on one thread (clear's BLAS too, as a single `clear` call does). Other
work on the machine slows both; the load average is printed before and after.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

# one BLAS thread, as `clear` itself runs (clearcli/cli.py), before NumPy loads
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
SOURCE = REPO / "benchmarks" / "pcl" / "pcl_segment.cpp"
BINARY = REPO / "benchmarks" / "pcl" / "build" / "pcl_segment"
PCL_PACKAGES = (
    "pcl_common pcl_io pcl_filters pcl_sample_consensus pcl_search pcl_segmentation pcl_surface pcl_octree "
    "pcl_kdtree pcl_features"
).split()


def _shared() -> Path:
    env = os.environ.get("CLEAR_SHARED")
    return Path(env) if env else REPO.parent / "shared" / "data"


def build() -> str | None:
    """Builds the PCL program when missing or stale; None, or why it cannot."""
    if BINARY.is_file() and BINARY.stat().st_mtime >= SOURCE.stat().st_mtime:
        return None
    cxx = shutil.which(os.environ.get("CXX", "g++"))
    if cxx is None:
        return "no C++ compiler (g++, or $CXX)"
    if shutil.which("pkg-config") is None:
        return "no pkg-config (apt-get install pkg-config)"
    flags = subprocess.run(["pkg-config", "--cflags", "--libs", *PCL_PACKAGES], capture_output=True, text=True)
    if flags.returncode != 0:
        return f"PCL's development files are not installed (apt-get install libpcl-dev): {flags.stderr.strip()[:200]}"
    BINARY.parent.mkdir(parents=True, exist_ok=True)
    print(f"building {BINARY.relative_to(REPO)} (about a minute)...", flush=True)
    cmd = [cxx, "-std=c++17", "-O2", "-DNDEBUG", "-o", str(BINARY), str(SOURCE), *flags.stdout.split()]
    res = subprocess.run(cmd, capture_output=True, text=True)
    if res.returncode != 0:
        return f"the PCL program did not build: {res.stderr.strip()[-600:]}"
    return None


def truth_objects(frame: object) -> int | None:
    """mOSD's ground-truth object count: labels >= 10, object id = label // 10."""
    labels = getattr(frame, "fields", {}).get("label")
    if labels is None:
        return None
    ids = np.unique(np.asarray(labels).astype(np.int64).ravel() // 10)
    return int((ids >= 1).sum())


def frame_sets(data: Path, per_set: int | None) -> dict[str, list[Path]]:
    from clearcli.io.read import read_frame
    from clearcli.tasks.sources import natural_key

    mosd = sorted((data / "mosd").glob("*/*.pcd"), key=lambda p: (p.parent.name, natural_key(p)))
    simple, cluttered = [], []
    for path in mosd:
        n = truth_objects(read_frame(path))
        if n is not None and 2 <= n <= 3:
            simple.append(path)
        elif n is not None and n >= 5:
            cluttered.append(path)
    sets = {
        "mosd_simple": simple,
        "mosd_cluttered": cluttered,
        "realsense_640x480": sorted((data / "scenes" / "uois_realsense").glob("*.pcd")),
        "realsense_1280x720": sorted((data / "scenes" / "cleargrasp_d435").glob("*.pcd")),
    }
    if per_set:
        # spread over the set, not its first frames (the mOSD frames grow in clutter)
        sets = {
            k: [v[round(i * (len(v) - 1) / max(per_set - 1, 1))] for i in range(min(per_set, len(v)))] if v else v
            for k, v in sets.items()
        }
    return sets


def run_pcl(path: Path, runs: int) -> list[dict]:
    res = subprocess.run([str(BINARY), "--repeat", str(runs), str(path)], capture_output=True, text=True)
    if res.returncode != 0:
        raise SystemExit(f"pcl_segment failed on {path}: {res.stderr.strip()[-400:]}")
    return [json.loads(line) for line in res.stdout.splitlines() if line.strip()]


def run_clear(path: Path, runs: int, settings: object) -> tuple[list[float], int, int | None]:
    from clearcli import pipeline

    walls = []
    n_objects = 0
    truth = None
    for _ in range(runs):
        t0 = time.perf_counter()
        frame = pipeline.read(path, settings=settings)
        seg = pipeline.segmented(frame, settings)
        walls.append(time.perf_counter() - t0)
        n_objects = len(seg.objects)
        truth = truth_objects(frame)
    return walls, n_objects, truth


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=3, help="runs per frame and side (default 3)")
    ap.add_argument("--per-set", type=int, default=0, help="at most K frames per set, spread over it (default all)")
    ap.add_argument("--sets", default="", help="comma-separated set names (default all)")
    opts = ap.parse_args()

    why = build()
    if why:
        print(f"pcl.py: skipped: {why}")
        return
    data = _shared()
    if not (data / "mosd").is_dir():
        raise SystemExit(f"pcl.py: shared data not found at {data} (set CLEAR_SHARED)")

    from clearcli import pipeline
    from clearcli.settings import Settings

    settings = Settings()
    sets = frame_sets(data, opts.per_set or None)
    if opts.sets:
        wanted = opts.sets.split(",")
        sets = {k: v for k, v in sets.items() if k in wanted}
    first = next(p for v in sets.values() for p in v)
    pipeline.segmented(pipeline.read(first, settings=settings), settings)  # warm-up: imports, first calls

    load0 = os.getloadavg()[0]
    print(f"runs per frame and side: {opts.runs}   cpus: {os.cpu_count()}   load (1 min) before: {load0:.2f}")
    summary = []
    mosd_rows: list[tuple] = []
    for name, paths in sets.items():
        if not paths:
            print(f"\n{name}: no frames")
            continue
        print(f"\n{name} ({len(paths)} frames)")
        print(
            f"  {'frame':<28} {'truth':>5} {'clear':>5} {'pcl':>4} {'clear s':>8} {'pcl s':>7} {'ratio':>6}  pcl stages (median s)"
        )
        rows = []
        for path in paths:
            pcl_runs = run_pcl(path, opts.runs)
            walls, n_clear, truth = run_clear(path, opts.runs, settings)
            pcl_total = statistics.median(r["total_s"] for r in pcl_runs)
            pcl_no_sor = statistics.median(r["total_s"] - r["stages_s"]["outliers"] for r in pcl_runs)
            stages = {k: statistics.median(r["stages_s"][k] for r in pcl_runs) for k in pcl_runs[0]["stages_s"]}
            clear_s = statistics.median(walls)
            rows.append((path, truth, n_clear, pcl_runs[0]["objects"], clear_s, pcl_total, pcl_no_sor))
            print(
                f"  {path.name:<28} {'-' if truth is None else truth:>5} {n_clear:>5} {pcl_runs[0]['objects']:>4} "
                f"{clear_s:8.3f} {pcl_total:7.3f} {clear_s / pcl_total:6.2f}  "
                + " ".join(f"{k} {v:.3f}" for k, v in stages.items())
            )
        clear_med = statistics.median(r[4] for r in rows)
        pcl_med = statistics.median(r[5] for r in rows)
        ratio = statistics.median(r[4] / r[5] for r in rows)
        ratio_no_sor = statistics.median(r[4] / r[6] for r in rows)
        summary.append((name, len(rows), clear_med, pcl_med, ratio, ratio_no_sor))
        print(
            f"  median: clear {clear_med:.3f} s, PCL {pcl_med:.3f} s; clear/PCL {ratio:.2f} "
            f"(against PCL without its outlier stage: {ratio_no_sor:.2f})"
        )
        mosd_rows.extend(r for r in rows if r[1] is not None)
    if len({r[1] for r in mosd_rows}) >= 2:
        x = np.array([r[1] for r in mosd_rows], float)
        print(
            f"\ntime against ground-truth objects, {len(mosd_rows)} mOSD frames ({int(x.min())}-{int(x.max())} objects):"
        )
        for side, k in (("clear", 4), ("PCL", 5)):
            slope, icept = np.polyfit(x, np.array([r[k] for r in mosd_rows]), 1)
            at3, at15 = icept + 3 * slope, icept + 15 * slope
            print(
                f"  {side:<5} {1000 * slope:+6.1f} ms per object; line at 3 objects {at3:.3f} s, "
                f"at 15 {at15:.3f} s ({at15 / at3:.2f}x)"
            )
    load1 = os.getloadavg()[0]
    print(f"\nload (1 min) after: {load1:.2f}")
    print(f"\n{'set':<20} {'frames':>6} {'clear s':>8} {'PCL s':>7} {'clear/PCL':>9} {'vs PCL w/o outliers':>20}")
    for name, n, c, p, r, r2 in summary:
        print(f"{name:<20} {n:>6} {c:8.3f} {p:7.3f} {r:9.2f} {r2:20.2f}")
    print("(medians over the frames of each frame's median; ratios are the median of the frames' ratios)")


if __name__ == "__main__":
    main()
