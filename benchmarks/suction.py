"""Suction on real frames (issue 36): what the profiles with a cup remove, against the fingers.

    .venv/bin/python benchmarks/suction.py                      # mOSD (50) and uois (9)
    .venv/bin/python benchmarks/suction.py --set mosd --limit 10
    .venv/bin/python benchmarks/suction.py --profiles panda,panda-hybrid
    .venv/bin/python benchmarks/suction.py --ratio               # the predicates stage's cost

Each frame is segmented once (the default settings), then planned by `clear plan`'s own
stages for each profile with its default grasp kinds (panda: pinch, rim, slide;
panda-hybrid: those and suction; panda-suction and ur5e-epick: suction alone). Printed
per set and profile: objects removed (the plan's goal) out of the segments found (a frame
with nothing to do where a cup's load was judged on the estimated mass planned once more
as light as a cracker box, as `clear plan` does: clearcli/settings/weigh.py), plans
that remove nothing, which kinds the plans used, the predicates stage's median time,
and why the objects left were left (the plan's reason, and for the ungraspable the
suction kind's reason class: "curved", "rough", "hole or edge", "tilted", "another
object", "too heavy", ...).

Sets: ``mosd``: the 50 shared mOSD Kinect frames (learn and test); ``uois``: the nine
RealSense frames of ../shared/data/scenes/uois_realsense. The defaults of [suction] were
set from the makers' and YCB's figures (clearcli/settings/suction.py), not from these
frames; the seal tests' thresholds were looked at on mOSD learn only.

``--ratio``: the predicates stage (`compute_state`, models reused: each profile run once
first) on mOSD test57 and the 50 mOSD frames, panda-hybrid against panda, the two
interleaved frame by frame in one run so that the machine's other work weighs on both
alike; per frame the minimum of ``--repeat`` runs (wall and CPU time); printed: test57's
ratio, and over the mOSD frames the ratio of the summed minima and the median of the
per-frame ratios (issue 36's target: test57 at most 1.3).
"""

from __future__ import annotations

import argparse
import math
import os
import re
import statistics
import sys
import time
from collections import Counter
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
DATA = REPO.parent / "shared" / "data"
PROFILES = ("panda", "panda-hybrid", "panda-suction", "ur5e-epick")


def _sets(which: str, limit: int | None) -> dict[str, list[Path]]:
    sets = {
        "mosd": sorted((DATA / "mosd").glob("*/*.pcd")),
        "uois": sorted((DATA / "scenes" / "uois_realsense").glob("*.pcd")),
    }
    chosen = sets if which == "all" else {which: sets[which]}
    return {k: v[:limit] if limit else v for k, v in chosen.items()}


def _why(detail: str) -> str:
    """The suction kind's reason class in a left object's detail."""
    m = re.search(r"suction grasp: (.*?)(;|$)", detail)
    if not m:
        return "-"
    text = m.group(1)
    for key in ("curved", "rough", "hole or an edge", "tilted", "another object", "too heavy", "no face", "no cup"):
        if key in text:
            return key
    return text[:40]


def ratio(paths: list[Path], repeat: int) -> None:
    """The predicates stage, panda-hybrid against panda, per frame (see the module)."""
    from clearcli import pipeline
    from clearcli.io.read import read_frame
    from clearcli.predicates.state_builder import compute_state
    from clearcli.settings import Settings
    from clearcli.settings.tree import load_settings

    fingers = load_settings(None, ["robot.name=panda"])
    hybrid = load_settings(None, ["robot.name=panda-hybrid"])
    rows = []
    for p in paths:
        frame = read_frame(p)
        seg = pipeline.segmented(frame, Settings())
        best: dict[str, list[float]] = {"panda": [math.inf, math.inf], "panda-hybrid": [math.inf, math.inf]}
        for settings in (fingers, hybrid):  # the first run of each: imports, caches
            compute_state(frame, seg, settings)
        for _ in range(repeat):
            for name, settings in (("panda", fingers), ("panda-hybrid", hybrid)):
                t0, c0 = time.perf_counter(), time.process_time()
                compute_state(frame, seg, settings)
                wall, cpu = time.perf_counter() - t0, time.process_time() - c0
                best[name] = [min(best[name][0], wall), min(best[name][1], cpu)]
        rows.append((p.stem, best["panda"], best["panda-hybrid"]))
    load = os.getloadavg()
    print(f"load average {load[0]:.2f}; minimum of {repeat} runs per frame and profile, panda / panda-hybrid")
    for stem, f, h in rows:
        if stem == "test57":
            print(
                f"  test57: wall {f[0]:.3f} -> {h[0]:.3f} s ({h[0] / f[0]:.2f}x), "
                f"CPU {f[1]:.3f} -> {h[1]:.3f} s ({h[1] / f[1]:.2f}x)"
            )
    for k, what in ((0, "wall"), (1, "CPU")):
        fs = [f[k] for _, f, _ in rows]
        hs = [h[k] for _, _, h in rows]
        print(
            f"  {len(rows)} frames, {what}: median {statistics.median(fs):.3f} -> {statistics.median(hs):.3f} s, "
            f"summed {sum(hs) / sum(fs):.2f}x, median of the frames' ratios "
            f"{statistics.median(h / f for f, h in zip(fs, hs)):.2f}x, largest {max(h / f for f, h in zip(fs, hs)):.2f}x"
        )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--set", choices=("mosd", "uois", "all"), default="all")
    ap.add_argument("--limit", type=int, default=None, help="the first N frames of each set")
    ap.add_argument("--profiles", default=",".join(PROFILES))
    ap.add_argument("--ratio", action="store_true", help="the predicates stage's time, panda-hybrid / panda")
    ap.add_argument("--repeat", type=int, default=5, help="--ratio: runs per frame and profile (the minimum)")
    args = ap.parse_args()
    if args.ratio:
        if args.repeat < 1:
            ap.error("--repeat: at least 1")
        ratio(_sets("mosd", args.limit)["mosd"], args.repeat)
        return

    from clearcli import pipeline
    from clearcli.errors import NoPlanError
    from clearcli.io.read import read_frame
    from clearcli.planning.backtrack import make_plan
    from clearcli.predicates.state_builder import compute_state
    from clearcli.robot.arm import resolve_arm
    from clearcli.settings import Settings
    from clearcli.settings.tree import load_settings
    from clearcli.settings.weigh import lightest_plausible

    profiles = [p.strip() for p in args.profiles.split(",") if p.strip()]
    for name, paths in _sets(args.set, args.limit).items():
        segs = []
        for p in paths:
            frame = read_frame(p)
            segs.append((p.stem, frame, pipeline.segmented(frame, Settings())))
        n_segments = sum(len(s.objects) for _, _, s in segs)
        print(f"{name}: {len(segs)} frames, {n_segments} segments")
        print(f"  {'profile':14s} {'removed':>16s} {'nothing':>8s} {'predicates':>11s}  kinds used; left (why)")
        for robot in profiles:
            settings = load_settings(None, [f"robot.name={robot}"])
            arm = resolve_arm(settings)
            removed, nothing, weighed, kinds, left, t_pred = 0, 0, 0, Counter(), Counter(), []
            for _stem, frame, seg in segs:
                t0 = time.perf_counter()
                state = compute_state(frame, seg, settings)
                t_pred.append(time.perf_counter() - t0)
                try:
                    plan = make_plan(state, settings, robot=arm)
                except NoPlanError as err:
                    plan = err.plan  # type: ignore[attr-defined]
                relaxed = lightest_plausible(settings) if not plan.actions else None
                if relaxed is not None:  # as `clear plan` does (clearcli/tasks/plan.py): weigh on the lift
                    try:
                        light = make_plan(compute_state(frame, seg, relaxed), relaxed, robot=arm)
                    except NoPlanError as err:
                        light = err.plan  # type: ignore[attr-defined]
                    if light.actions:
                        plan = light
                        weighed += 1
                removed += len(plan.goal)
                nothing += not plan.goal
                kinds.update(a.grasp_kind for a in plan.actions if a.kind == "grasp")
                for x in plan.left:
                    left[x.reason + ("/" + _why(x.detail) if x.reason == "ungraspable" else "")] += 1
            share = 100.0 * removed / max(n_segments, 1)
            print(
                f"  {robot:14s} {removed:5d} ({share:5.1f} %) {nothing:8d} {statistics.median(t_pred):9.3f} s"
                f"  {dict(kinds)}; {dict(left.most_common(6))}"
                + (f"; {weighed} frame(s) planned as light as a cracker box (weigh on lift)" if weighed else "")
            )


if __name__ == "__main__":
    main()
