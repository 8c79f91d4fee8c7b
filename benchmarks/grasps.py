"""The grasp kinds beyond the pinch (issue 25): what they remove, on real frames.

    .venv/bin/python benchmarks/grasps.py                 # both parts
    .venv/bin/python benchmarks/grasps.py --part uois     # nine uois frames, panda and ur5e
    .venv/bin/python benchmarks/grasps.py --part mosd     # 50 mOSD frames, plans removing nothing

``uois``: the nine RealSense frames of ../shared/data/scenes/uois_realsense, with the
hand-made object labels of benchmarks/foreign (the foreign-segmentation work). Per
profile and grasp setting: segments removed by `clear plan` out of those segmented, and
labelled objects removed out of those the segmentation gets exactly right (an object is
removed when the plan's goal holds the segment that is exactly it).

``mosd``: the 50 mOSD frames (learn and test): plans whose goal is empty (they remove
nothing), per profile, with the thesis's pinch alone and with every kind; and which
kinds the plans used.
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "benchmarks"))
DATA = REPO.parent / "shared" / "data"
GRASPS = ("pinch", "pinch,rim,slide")


def _settings(robot: str, grasps: str):  # type: ignore[no-untyped-def]
    from clearcli.settings.tree import load_settings

    return load_settings(None, [f"robot.name={robot}", f'plan.grasps="{grasps}"'])


def _plan(frame, seg, settings):  # type: ignore[no-untyped-def]
    from clearcli.errors import NoPlanError
    from clearcli.planning.backtrack import make_plan
    from clearcli.predicates.state_builder import compute_state

    state = compute_state(frame, seg, settings)
    try:
        plan = make_plan(state, settings)
    except NoPlanError as err:
        plan = err.plan  # type: ignore[attr-defined]
    return state, plan


def uois() -> None:
    import foreign

    from clearcli import pipeline
    from clearcli.evaluate.exact import exact_report
    from clearcli.settings import Settings

    frames = [n for n in foreign.names("all") if n.startswith("uois_image")]
    loaded = []
    for name in frames:
        frame, truth, spec = foreign.load(name)
        seg = pipeline.segmented(frame, Settings())
        pred = seg.labels()
        verdicts = exact_report(pred, truth).verdicts
        # the segment that is exactly each object right
        ids = [int(v) for v in np.unique(truth) if v >= 10]
        seg_of: dict[int, int] = {}
        for k, (lab, verdict) in enumerate(zip(ids, verdicts)):
            if verdict != "right":
                continue
            mask = truth == lab
            inside = pred[mask]
            best = int(np.bincount(inside[inside >= 10] // 10 - 1).argmax()) if np.any(inside >= 10) else -1
            seg_of[k] = best
        loaded.append((name, frame, seg, seg_of, len(ids)))
    n_labelled = sum(x[4] for x in loaded)
    n_right = sum(len(x[3]) for x in loaded)
    n_segments = sum(len(x[2].objects) for x in loaded)
    print(f"nine uois frames: {n_segments} segments, {n_labelled} labelled objects, {n_right} exactly right")
    print(f"{'robot':6s} {'grasps':16s} {'segments removed':>17s} {'right objects removed':>22s}  kinds used")
    for robot in ("panda", "ur5e", "wam"):
        for grasps in GRASPS:
            settings = _settings(robot, grasps)
            removed_segments = removed_right = 0
            kinds: Counter = Counter()
            for _name, frame, seg, seg_of, _ in loaded:
                state, plan = _plan(frame, seg, settings)
                gone = {state.by_name(n).segment_index for n in plan.goal}
                removed_segments += len(gone)
                removed_right += sum(1 for s in seg_of.values() if s in gone)
                kinds.update(a.grasp_kind for a in plan.actions if a.kind == "grasp")
            print(
                f"{robot:6s} {grasps:16s} {removed_segments:>8d} of {n_segments:<5d}"
                f" {removed_right:>10d} of {n_right:<3d} ({100 * removed_right / max(n_right, 1):5.1f} %)  {dict(kinds)}"
            )


def mosd() -> None:
    from clearcli import pipeline
    from clearcli.io.read import read_frame
    from clearcli.settings import Settings

    paths = sorted((DATA / "mosd").glob("*/*.pcd"))
    segs = []
    for p in paths:
        frame = read_frame(p)
        segs.append((p.stem, frame, pipeline.segmented(frame, Settings())))
    print(f"{len(paths)} mOSD frames: plans that remove nothing")
    for robot in ("wam", "panda", "ur5e"):
        for grasps in GRASPS:
            settings = _settings(robot, grasps)
            empty, kinds, removed = [], Counter(), 0
            for name, frame, seg in segs:
                _, plan = _plan(frame, seg, settings)
                if not plan.goal:
                    empty.append(name)
                removed += len(plan.goal)
                kinds.update(a.grasp_kind for a in plan.actions if a.kind == "grasp")
            print(
                f"  {robot:6s} {grasps:16s} {len(empty):3d} remove nothing; {removed} objects removed in all; kinds {dict(kinds)}"
            )
            print(f"         ({', '.join(empty)})")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--part", choices=("uois", "mosd", "all"), default="all")
    args = ap.parse_args()
    if args.part in ("uois", "all"):
        uois()
    if args.part in ("mosd", "all"):
        mosd()


if __name__ == "__main__":
    main()
