"""Suction in the simulated world (issue 36): clearing sessions of `families.suction_mix`
with a profile that has a cup, judged by the world's own rules.

    .venv/bin/python benchmarks/suction_sim.py                        # report seeds 1000-1019, both modes
    .venv/bin/python benchmarks/suction_sim.py --n 50 --mode segmenter
    .venv/bin/python benchmarks/suction_sim.py --seeds 1003,1017 -v   # a few sessions, each step
    .venv/bin/python benchmarks/suction_sim.py --robot panda-suction

Each session is `clear simulate --scene suction_mix --robot panda-hybrid`'s closed loop
(`clearcli.sim.episode`: plan on the rendered frame, carry out the first action in the
world, render again, with push memory, until the table is clear, no plan exists, or 40
actions), once with the camera's true labels as the segmentation (``truth``) and once
with the segmenter (``segmenter``). The scenes (`clearcli.sim.families.suction_mix`):
2-4 flat boxes and lidded containers wider than every gripper's opening, some tops
porous or ribbed, some 3-5 kg, and 1-2 small graspable objects; the true masses and
surfaces are the world's alone (the planner estimates a mass from the volume it sees
and sees no surface).

A suction step is judged by `clearcli.sim.physics.world_suction` (what the cup meets,
whether its lip seals on that true face, whether the seal holds the true weight with no
safety factor). Printed per mode: the share of objects cleared (removed out of those at
the start) and of sessions cleared by the world's verdict (`cleared_truly`); the
objects removed per grasp kind; the suction steps and their failures per cause (the
outcome's prefix: "no seal: the top is porous", "dropped: too heavy", "missed: ...");
why the objects left were left.

Seeds: ``report`` (1000-1099, `families.REPORT_SEEDS`), the first ``--n`` of them; the
world's rules and the family were written without looking at them.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

MODES = ("truth", "segmenter")
MAX_ACTIONS = 40
KINDS = {"(grasp ": "pinch", "(grasp_rim ": "rim", "(slide_grasp ": "slide", "(grasp_suction ": "suction"}


def cause(outcome: str) -> str:
    """A failed suction step's cause class, from the world's stable prefixes."""
    why = outcome.removeprefix("suction failed: ")
    if why.startswith("no seal: the top is "):
        return why  # porous | ribbed
    for key, name in (
        ("no seal: an open container", "no seal: an open container's top"),
        ("no seal: the side curves", "no seal: a side too curved"),
        ("no seal: the lip overhangs", "no seal: the lip over an edge"),
        ("no seal: the cup meets", "no seal: a face askew"),
        ("under the cup", "no seal: another object under the cup"),
        ("no seal: on the mug", "no seal: a handle"),
        ("dropped: too heavy", "dropped: too heavy"),
        ("missed: the cup struck", "missed: the cup struck an object short of its contact"),
        ("missed:", "missed: the cup met nothing"),
    ):
        if why.startswith(key) or key in why:
            return name
    return why[:60]


def left_reason(r: Any, o: int) -> str:
    if o in r.truly_ungraspable:
        return "excused: no kind takes it (the world's rules)"
    if o in r.world_unreachable and o not in r.moved:
        return "excused: the world's arm cannot reach it"
    if o in r.world_unreachable:
        return "pushed out of reach by the robot"
    if r.end == "budget":
        return "action budget ran out"
    if o in r.unseen:
        return "merged with another or missed by the segmenter"
    if o in r.claimed_ungraspable:
        return "planner: no kind offered (the world would take it)"
    if o in r.unreachable:
        return "planner: no arm motion (the world's arm reaches it)"
    if o in r.stuck:
        return "planner: blocked by objects it cannot move"
    return f"other ({r.end})"


def planner_cause(why: str) -> str:
    """The plan's reason for an object left, short: its class and, for an object no kind
    was offered, what suction said (the kind the scenes are made for)."""
    if not why:
        return "no plan reason (the session ended first)"
    head = why.split(":", 1)[0]
    if "suction grasp: " in why:
        said = why.split("suction grasp: ", 1)[1].split(";")[0]
        return f"{head}; suction: {said.split(':')[0].split(' ~')[0]}"
    if "suction" not in why and head == "ungraspable":
        return f"{head}; suction not tried"
    return f"{head}: {why.split(':', 1)[1].strip()[:50]}" if ":" in why else head


def run_session(seed: int, mode: str, robot: str) -> dict[str, Any]:
    from clearcli.pipeline import Pipeline
    from clearcli.replay.session import ReplayOptions, Session
    from clearcli.settings import load_settings
    from clearcli.sim.episode import Episode
    from clearcli.sim.families import suction_mix
    from clearcli.sim.truth import truth_segment

    world = suction_mix(seed)
    settings = load_settings(None, [f"robot.name={robot}"])
    pipeline = Pipeline(settings, segment_fn=truth_segment if mode == "truth" else None)
    episode = Episode(world, Session(pipeline, ReplayOptions(push_memory=True)), seed=seed, max_actions=MAX_ACTIONS)
    t0 = time.perf_counter()
    for _ in episode:
        pass
    r = episode.result
    assert r is not None
    acted = [s for s in r.steps if s.action]
    removed_by: Counter[str] = Counter()
    for s in acted:
        if s.outcome == "removed":
            removed_by[next((v for k, v in KINDS.items() if s.action.startswith(k)), "other")] += 1
    suction = [s for s in acted if s.action.startswith("(grasp_suction ")]
    truth = {o.object_id: o for o in world.objects}
    return {
        "seed": seed,
        "mode": mode,
        "objects": r.n_objects,
        "removed": r.n_objects - len(r.remaining),
        "cleared": r.cleared_truly,
        "end": r.end,
        "actions": len(acted),
        "removed_by": dict(removed_by),
        "suction_steps": len(suction),
        "suction_failed": [cause(s.outcome) for s in suction if s.outcome != "removed"],
        "heavy_or_rough": sum(1 for o in world.objects if o.mass_kg >= 3.0 or o.surface != "smooth"),
        "left": [
            f"{left_reason(r, o)} [{truth[o].surface}, {truth[o].true_mass_kg:.1f} kg]"
            if o in truth
            else left_reason(r, o)
            for o in r.remaining
        ],
        # per object left: the plan's reason and the world's verdict ("" = it could)
        "left_why": [
            (o, planner_cause(r.planner_why.get(o, "")), r.planner_why.get(o, ""), r.world_why.get(o, ""))
            for o in r.remaining
        ],
        "wall_s": time.perf_counter() - t0,
        "steps": [f"{s.action} -> {s.outcome}" if s.action else s.status for s in r.steps],
    }


def _run(args: tuple[int, str, str]) -> dict[str, Any]:
    return run_session(*args)


def report(label: str, rows: list[dict[str, Any]], verbose: bool) -> None:
    objects = sum(r["objects"] for r in rows)
    removed = sum(r["removed"] for r in rows)
    cleared = sum(r["cleared"] for r in rows)
    by_kind: Counter[str] = Counter()
    for r in rows:
        by_kind.update(r["removed_by"])
    steps = sum(r["suction_steps"] for r in rows)
    failed = Counter(c for r in rows for c in r["suction_failed"])
    left = Counter(x.split(" [")[0] for r in rows for x in r["left"])
    causes = Counter(
        (cause, "the world's robot could take it" if not world else f"the world: {world}")
        for r in rows
        for _o, cause, _why, world in r["left_why"]
    )
    print(
        f"{label}: objects cleared {removed}/{objects} = {100 * removed / max(objects, 1):.1f} %; "
        f"sessions cleared (the world's verdict) {cleared}/{len(rows)}; "
        f"{sum(r['actions'] for r in rows)} actions, {sum(r['wall_s'] for r in rows):.0f} s"
    )
    print("    removed by kind: " + (", ".join(f"{k} {v}" for k, v in sorted(by_kind.items())) or "none"))
    print(
        f"    suction steps {steps}: removed {steps - sum(failed.values())}, failed {sum(failed.values())}"
        + "".join(f"\n        {c}: {n}" for c, n in failed.most_common())
    )
    print("    objects left: " + ("; ".join(f"{k}: {v}" for k, v in sorted(left.items())) or "none"))
    print(
        "    objects left by the plan's reason, and the world's verdict:"
        + "".join(f"\n        {n} x {c} -- {w}" for (c, w), n in causes.most_common())
    )
    for r in rows:
        if verbose or r["left"]:
            print(f"    seed {r['seed']}: end {r['end']}, removed {r['removed']}/{r['objects']}, left {r['left']}")
            for o, _cause, why, world in r["left_why"]:
                print(f"        object {o}: plan: {why or '-'} | world: {world or 'its robot could take it'}")
            if verbose:
                for s in r["steps"]:
                    print(f"        {s}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=20, help="sessions per mode: the first N report seeds")
    ap.add_argument("--seeds", default="", help="comma-separated seeds instead")
    ap.add_argument("--mode", choices=(*MODES, "both"), default="both")
    ap.add_argument("--robot", default="panda-hybrid", help="a robot profile with a cup (`clear robots`)")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("-v", "--verbose", action="store_true", help="every session's steps")
    args = ap.parse_args()

    from clearcli.sim.families import REPORT_SEEDS

    seeds = [int(s) for s in args.seeds.split(",")] if args.seeds else list(REPORT_SEEDS)[: args.n]
    modes = MODES if args.mode == "both" else (args.mode,)
    work = [(seed, mode, args.robot) for mode in modes for seed in seeds]
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        rows = list(pool.map(_run, work, chunksize=1))
    print(
        f"{len(rows)} sessions of suction_mix, seeds {seeds[0]}-{seeds[-1]}, --robot {args.robot}, "
        f"in {time.perf_counter() - t0:.0f} s on {args.jobs} processes"
    )
    for mode in modes:
        report(f"{mode} segmentation", [r for r in rows if r["mode"] == mode], args.verbose)


if __name__ == "__main__":
    main()
