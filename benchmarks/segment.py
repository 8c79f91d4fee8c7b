"""Segmentation over every mOSD frame: object F1 and IoU per category, time, memory.

    .venv/bin/python benchmarks/segment.py [--data ../shared/data/mosd] [--key=value ...]
    .venv/bin/python benchmarks/segment.py --sim-clutter 90 [--key=value ...]

After the mOSD frames it scores the self-made scene families of `clearcli.sim.families`
(small objects on and against larger ones, rows with 3/5/10 mm gaps running away from
the camera and across the line of sight, dense mixes, open containers), each rendered
like a Kinect frame, on the report seeds 1000-1099 (`--seeds choose` for 0-99, the
seeds settings are chosen on; `--families-only` skips mOSD; `--n-seeds N` takes the
first N; 0 skips them). Per family: mean F1, mean best IoU, over- and under-segmented objects per
render, the share of renders segmented exactly right ("right": every object matched at
IoU >= 0.5 and nothing more predicted) and the median time.

`--key=value` overrides a SegmentSettings field (e.g. --concavity_tolerance_deg=15) to
compare choices. `--sim-clutter N` instead scores N simulated clutter scenes
(`clearcli.sim.scene.clutter(4 + s % 7, s)`, s = 100..., many touching pairs) with the
planar cuts off and on, a validation set apart from the mOSD frames. The defaults
were chosen on the 45 learn frames only; the 5 test frames are held out and reported
apart.

Times are per frame in a warm process (one untimed frame first, so imports and first
calls are excluded; reading the file is excluded too); memory is the peak resident
set of the process (ru_maxrss) after all frames.
"""

from __future__ import annotations

import argparse
import dataclasses
import re
import resource
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from clearcli.evaluate.segmentation import score  # noqa: E402
from clearcli.io.read import read_frame  # noqa: E402
from clearcli.perception.segment import segment  # noqa: E402
from clearcli.settings.segment import SegmentSettings  # noqa: E402


def _categories() -> list[tuple[str, list[str]]]:
    """mOSD's categories from the groups file `clear evaluate dataset --groups mosd` uses."""
    import fnmatch

    from clearcli.evaluate.dataset import load_groups
    from clearcli.tasks.sources import natural_key

    names = [f"learn/learn{i}.pcd" for i in range(45)] + [f"test/test{i}.pcd" for i in (44, 46, 47, 55, 57)]
    out = []
    for group, patterns in load_groups("mosd").items():
        hits = [n for n in names if any(fnmatch.fnmatchcase(Path(n).name, p) for p in patterns)]
        out.append((group, sorted(hits, key=lambda n: natural_key(Path(n)))))
    return out


CATEGORIES: list[tuple[str, list[str]]] = _categories()
STAGES = ("filter", "table", "edges", "supervoxels", "lccp", "cuts", "merge", "flat", "objects", "total")


def _settings(overrides: list[str]) -> SegmentSettings:
    base = SegmentSettings()
    kinds = {f.name: type(getattr(base, f.name)) for f in dataclasses.fields(base)}
    changes = {}
    for item in overrides:
        m = re.fullmatch(r"--(\w+)=(.*)", item)
        if not m or m.group(1) not in kinds:
            raise SystemExit(f"unknown override {item!r}; fields: {', '.join(kinds)}")
        key, text = m.groups()
        kind = kinds[key]
        changes[key] = text.lower() in ("1", "true", "yes") if kind is bool else kind(text)
    return dataclasses.replace(base, **changes)


def sim_clutter(n_scenes: int, settings: SegmentSettings) -> None:
    from clearcli.sim.camera import render
    from clearcli.sim.scene import clutter

    off = dataclasses.replace(settings, planar_cuts=False)
    on = dataclasses.replace(settings, planar_cuts=True)
    f_off, f_on = [], []
    for s in range(100, 100 + n_scenes):
        frame = render(clutter(4 + s % 7, s), seed=s)
        a = score(segment(frame, off).labels(), frame.fields["label"])
        b = score(segment(frame, on).labels(), frame.fields["label"])
        f_off.append(a.f1)
        f_on.append(b.f1)
        if a.f1 != b.f1:
            print(
                f"  clutter({4 + s % 7}, {s})  F1 {a.f1:.3f} -> {b.f1:.3f}  "
                f"(true {a.n_true}, predicted {a.n_pred} -> {b.n_pred})"
            )
    better = sum(b > a for a, b in zip(f_off, f_on))
    worse = sum(b < a for a, b in zip(f_off, f_on))
    print(
        f"sim clutter n={n_scenes}: mean F1 cuts off {np.mean(f_off):.3f}, on {np.mean(f_on):.3f} "
        f"({better} better, {worse} worse)"
    )


def families(settings: SegmentSettings, seeds: range) -> None:
    from clearcli.sim.camera import render
    from clearcli.sim.families import FAMILIES

    segment(render(FAMILIES["small_on_large"](0), seed=0), settings)  # warm-up
    print(f"self-made families, seeds {seeds.start}-{seeds.stop - 1} ({len(seeds)} renders each):")
    print(f"  {'family':22s} {'F1':>6s} {'IoU':>6s} {'over':>5s} {'under':>5s} {'right':>6s} {'time ms':>8s}")
    for name, build in FAMILIES.items():
        f1, iou, over, under, right, wall = [], [], [], [], [], []
        for seed in seeds:
            frame = render(build(seed), seed=seed)
            t0 = time.perf_counter()
            seg = segment(frame, settings)
            wall.append(time.perf_counter() - t0)
            sc = score(seg.labels(), frame.fields["label"])
            f1.append(sc.f1)
            iou.append(sc.mean_best_iou)
            over.append(sc.over_segmented)
            under.append(sc.under_segmented)
            right.append(sc.true_positives == sc.n_true == sc.n_pred)
        print(
            f"  {name:22s} {np.mean(f1):6.3f} {np.mean(iou):6.3f} {np.mean(over):5.2f} {np.mean(under):5.2f} "
            f"{100 * np.mean(right):5.0f}% {np.median(wall) * 1000:8.0f}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=REPO.parent / "shared" / "data" / "mosd")
    parser.add_argument("--sim-clutter", type=int, default=0, metavar="N")
    parser.add_argument("--seeds", choices=("report", "choose"), default="report")
    parser.add_argument("--n-seeds", type=int, default=100)
    parser.add_argument("--families-only", action="store_true")
    args, rest = parser.parse_known_args()
    settings = _settings(rest)
    if args.sim_clutter:
        sim_clutter(args.sim_clutter, settings)
        return
    from clearcli.sim.families import CHOOSE_SEEDS, REPORT_SEEDS

    seeds = REPORT_SEEDS if args.seeds == "report" else CHOOSE_SEEDS
    seeds = seeds[: args.n_seeds]
    if args.families_only:
        families(settings, seeds)
        return
    changed = {
        f.name: getattr(settings, f.name)
        for f in dataclasses.fields(settings)
        if getattr(settings, f.name) != getattr(SegmentSettings(), f.name)
    }
    print(f"settings: defaults{' with ' + str(changed) if changed else ''}")

    first = args.data / CATEGORIES[0][1][0]
    segment(read_frame(first), settings)  # warm-up: imports, first calls

    rows: dict[str, list[tuple[str, float, float, dict[str, float]]]] = {}
    for cat, names in CATEGORIES:
        for name in names:
            frame = read_frame(args.data / name)
            t0 = time.perf_counter()
            seg = segment(frame, settings)
            wall = time.perf_counter() - t0
            sc = score(seg.labels(), frame.fields["label"])
            timings = dict(seg.timings_s)
            timings["total"] = wall
            rows.setdefault(cat, []).append((name, sc.f1, sc.mean_best_iou, timings))
            flag = "" if sc.f1 == 1.0 else f"  (true {sc.n_true}, predicted {sc.n_pred}, matched {sc.true_positives})"
            print(f"  {name:18s} F1 {sc.f1:.3f}  IoU {sc.mean_best_iou:.3f}  {wall * 1000:5.0f} ms{flag}")

    def summary(label: str, items: list[tuple[str, float, float, dict[str, float]]]) -> None:
        f1 = np.mean([r[1] for r in items])
        iou = np.mean([r[2] for r in items])
        tot = np.array([r[3]["total"] for r in items])
        print(
            f"{label:16s} n={len(items):2d}  mean F1 {f1:.3f}  mean IoU {iou:.3f}  "
            f"time median {np.median(tot) * 1000:4.0f} ms  max {tot.max() * 1000:4.0f} ms"
        )

    print()
    for cat, _ in CATEGORIES:
        summary(cat, rows[cat])
    learn = [r for cat, _ in CATEGORIES[:4] for r in rows[cat]]
    test = [r for cat, _ in CATEGORIES[4:] for r in rows[cat]]
    every = learn + test
    print()
    summary("learn (45)", learn)
    summary("test (5, held out)", test)
    summary("all (50)", every)
    print()
    print("per stage (all 50 frames):   median    max   (ms)")
    for stage in STAGES:
        vals = np.array([r[3].get(stage, 0.0) for r in every]) * 1000
        print(f"  {stage:12s}              {np.median(vals):6.1f} {vals.max():6.1f}")
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak memory (resident, whole process): {peak_mb:.0f} MB")
    print(f"overall mean F1 over all {len(every)} frames: {np.mean([r[1] for r in every]):.3f}")
    print()
    if len(seeds):  # --n-seeds 0: mOSD alone
        families(settings, seeds)


if __name__ == "__main__":
    main()
