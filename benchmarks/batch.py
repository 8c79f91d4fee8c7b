"""Batch figures on the 50 given mOSD frames (../shared/data/mosd).

    .venv/bin/python benchmarks/batch.py            # everything (several minutes)
    .venv/bin/python benchmarks/batch.py --quick    # 10 frames, 100 for memory, no loops

Prints:
1. `clear plan FRAMES --jobs 2`: frames/s end to end (one process, worker start-up and
   imports included), against a shell-style loop of single `clear plan FRAME` calls on
   the same code;
2. the same batch on a local Ray cluster (`--ray`): wall time with `ray.init` reported
   apart, workers' imports counted in the batch;
3. memory: each worker's resident memory after the first pass of the frames and after
   ten passes (500 frames), and their ratio;
4. `clear evaluate dataset` on the frames: its mean F1 and wall time, against a loop of
   single `clear segment -o` + `clear evaluate segmentation` calls.

    .venv/bin/python benchmarks/batch.py --stages   # only this (about a minute)

`--stages`: what a warm worker spends per frame, stage by stage (one process, one BLAS
thread, the lighter imports, a first pass over the frames untimed, as a worker that has
done a few frames): read, segment, predicates, plan (placement, search, IK), median and
mean ms per frame and each stage's share; then `plan`'s whole task on each frame right
after its stages, timed apart (its payload and the rest are the difference), and the frames/s two such
workers would reach with nothing else to do.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
MOSD = REPO.parent / "shared" / "data" / "mosd"


def frames(n: int | None) -> list[Path]:
    from clearcli.tasks.sources import natural_key

    files = sorted(MOSD.glob("learn/*.pcd"), key=natural_key) + sorted(MOSD.glob("test/*.pcd"), key=natural_key)
    return files[:n] if n else files


def clear(*args: object) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "clearcli.cli", *map(str, args)], capture_output=True, text=True)


def timed(*args: object) -> tuple[float, subprocess.CompletedProcess[str]]:
    t0 = time.perf_counter()
    res = clear(*args)
    return time.perf_counter() - t0, res


def summary_of(res: subprocess.CompletedProcess[str]) -> dict:
    rows = [json.loads(x) for x in res.stdout.splitlines() if x.strip()]
    if not rows or rows[-1].get("type") != "summary":
        raise SystemExit(f"no summary line: {res.stderr[-500:]}")
    return rows[-1]


def plan_throughput(files: list[Path], loop: bool) -> float:
    wall, res = timed("plan", *files, "--json", "--jobs", "2")
    s = summary_of(res)
    pool_fps = len(files) / wall
    print(
        f"plan --jobs 2: {len(files)} frames in {wall:.1f} s = {pool_fps:.2f} frames/s "
        f"(exit codes {s['exit_codes']}, failed {s['failed']})"
    )
    if loop:
        t0 = time.perf_counter()
        for f in files:
            clear("plan", f, "--json")
        loop_wall = time.perf_counter() - t0
        print(
            f"loop of single `clear plan` calls: {len(files)} frames in {loop_wall:.1f} s = "
            f"{len(files) / loop_wall:.2f} frames/s; the batch is {loop_wall / wall:.1f}x faster"
        )
    return wall


def ray_throughput(files: list[Path], pool_wall: float) -> None:
    try:
        import ray  # noqa: F401
    except ImportError:
        print("ray: not installed (pip install 'clear-table[ray]'): skipped")
        return
    wall, res = timed("plan", *files, "--json", "--ray")
    s = summary_of(res)
    init = s.get("ray_init_s") or 0.0
    print(
        f"plan --ray (local): {len(files)} frames in {wall:.1f} s wall, of which ray.init {init:.1f} s; "
        f"without ray.init {wall - init:.1f} s = {(wall - init) / pool_wall:.2f} x the pool's wall time "
        f"(target <= 1.5); failed {s['failed']}"
    )


def memory(files: list[Path], passes: int) -> None:
    from clearcli.batch.run import BatchRequest, run_batch
    from clearcli.settings import Settings
    from clearcli.tasks import plan as task

    rss: dict[int, list[tuple[int, float]]] = {}
    seen = [0]

    def on_line(line: dict) -> None:
        seen[0] += 1
        if "_pid" in line:
            rss.setdefault(line["_pid"], []).append((seen[0], line["_rss_mb"]))

    import contextlib
    import io

    req = BatchRequest("plan", list(files) * passes, task.Request(Settings()), jobs=2, json_out=True)
    with contextlib.redirect_stdout(io.StringIO()):
        t0 = time.perf_counter()
        run_batch(req, on_line=on_line)
        wall = time.perf_counter() - t0
    n1 = len(files)
    for pid, points in sorted(rss.items()):
        first = [mb for k, mb in points if k <= n1]
        if not first:
            continue
        at_first, at_end = first[-1], points[-1][1]
        print(
            f"worker {pid}: resident {at_first:.0f} MB after the first {n1} frames, {at_end:.0f} MB after "
            f"{n1 * passes} ({points[-1][0]} lines seen); ratio {at_end / at_first:.2f} (target <= 1.20)"
        )
    print(f"({n1 * passes} frames in {wall:.1f} s = {n1 * passes / wall:.2f} frames/s)")


def evaluate(files: list[Path], loop: bool) -> None:
    wall, res = timed("evaluate", "dataset", *files, "--json", "--jobs", "2")
    s = summary_of(res)
    print(f"evaluate dataset: {len(files)} frames in {wall:.1f} s, mean F1 {s['evaluation']['all']['mean_f1']:.3f}")
    if loop:
        f1 = []
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            for f in files:
                lab = Path(tmp) / f"{f.stem}.pcd"
                clear("segment", f, "-o", lab)
                f1.append(json.loads(clear("evaluate", "segmentation", lab, f, "--json").stdout)["f1"])
            loop_wall = time.perf_counter() - t0
        print(
            f"loop of `segment -o` + `evaluate segmentation`: {loop_wall:.1f} s, mean F1 {statistics.mean(f1):.3f}; "
            f"evaluate dataset takes {wall / loop_wall:.2f} of it (target <= 0.5)"
        )


def stages(files: list[Path]) -> None:
    """A warm worker's time per frame, stage by stage (see the module's docstring)."""
    from clearcli import startup

    startup.single_threaded_numerics()  # as a worker does, before NumPy loads
    startup.lighten_imports()
    from clearcli import pipeline
    from clearcli.robot.arm import resolve_arm
    from clearcli.settings import Settings
    from clearcli.tasks import plan as task
    from clearcli.tasks.base import Source

    settings = Settings()
    request = task.Request(settings)
    for f in files:  # warm: imports and first calls, as a worker's first frames
        task.run(request, Source(str(f), 0, None, f.stem))
    names = ("read", "segment", "predicates", "plan")
    per: dict[str, list[float]] = {n: [] for n in names}
    whole: list[float] = []
    for f in files:
        t = [time.perf_counter()]
        robot = resolve_arm(settings)
        frame = pipeline.read(f, None, 0, settings)
        t.append(time.perf_counter())
        seg = pipeline.segmented(frame, settings)
        t.append(time.perf_counter())
        if seg.objects:
            state = pipeline.stated(frame, seg, settings)
            t.append(time.perf_counter())
            pipeline.planned(state, settings, robot, None, None)
            t.append(time.perf_counter())
        else:
            t += [t[-1], t[-1]]
        for k, name in enumerate(names):
            per[name].append(t[k + 1] - t[k])
        t0 = time.perf_counter()  # the whole task on the same frame, right after: the same load
        task.run(request, Source(str(f), 0, None, f.stem))
        whole.append(time.perf_counter() - t0)
    total = sum(statistics.mean(v) for v in per.values())
    print(f"a warm worker, per frame ({len(files)} frames; ms median / mean / share of the stages' mean total):")
    for name in names:
        v = per[name]
        print(
            f"  {name:<11} {1e3 * statistics.median(v):7.1f} {1e3 * statistics.mean(v):7.1f} {statistics.mean(v) / total:6.0%}"
        )
    print(f"  {'stages':<11} {'':7} {1e3 * total:7.1f}")
    task_s = statistics.mean(whole)
    print(
        f"  {'plan task':<11} {1e3 * statistics.median(whole):7.1f} {1e3 * task_s:7.1f}   (timed apart; "
        f"-> two such workers: {2 / task_s:.2f} frames/s at most)"
    )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--stages", action="store_true", help="only a warm worker's time per frame, stage by stage")
    args = ap.parse_args()
    if not MOSD.is_dir():
        raise SystemExit(f"{MOSD} is not here: the benchmark needs ../shared/data/mosd")
    files = frames(10 if args.quick else None)
    if args.stages:
        stages(files)
        return
    pool_wall = plan_throughput(files, loop=not args.quick)
    ray_throughput(files, pool_wall)
    memory(files, 10)
    evaluate(files, loop=not args.quick)


if __name__ == "__main__":
    main()
