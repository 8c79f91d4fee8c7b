"""Which stage cuts an object, on the labelled frames of other labs (issue 37).

    .venv/bin/python benchmarks/foreign_stages.py                       # every choose frame
    .venv/bin/python benchmarks/foreign_stages.py gqcnn_primesense_2    # some frames (choose part only)
    .venv/bin/python benchmarks/foreign_stages.py --set segment.color_split=false

For every labelled object that is not exactly right (clearcli/evaluate/exact.py), its
pieces (the segments holding at least `exact.PIECE` of its points) after LCCP and after
each refinement of refine.STAGES that changed them: ``7:0.60`` is segment 7 with 60 % of
the object, ``16:0.39(of 8)`` a segment with 39 % of it that holds more of object 8
than of it (a piece left in a neighbour's segment). A split that is there after LCCP and
no stage undoes is the supervoxels' or LCCP's; one that appears after a stage is that
stage's. The refinements are run here one by one exactly as refine.refine runs them.

Only frames of the choose part are looked at: per-frame results on the report part are
never printed (benchmarks/foreign.py prints only its totals for settings being chosen).
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))


def _foreign():  # benchmarks/foreign.py (a script, not a package), loaded by path
    spec = importlib.util.spec_from_file_location("foreign", REPO / "benchmarks" / "foreign.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def staged(frame, settings):  # -> (Segmentation, [(step, seg_of_voxel)], RefineContext)
    """The frame segmented, with the voxel segments after LCCP and after every stage."""
    from clearcli import pipeline
    from clearcli.perception import refine, segment

    snaps: list[tuple[str, np.ndarray]] = []
    seen = {}
    original = segment.refine

    def run_staged(seg, ctx, clock=None):
        seen["ctx"] = ctx
        snaps.append(("lccp", np.asarray(seg).copy()))
        for stage in refine.STAGES:
            seg = refine.refine(seg, ctx, clock, stages=(stage,))
            snaps.append((stage.name, np.asarray(seg).copy()))
        return seg

    segment.refine = run_staged
    try:
        result = pipeline.segmented(frame, settings)
    finally:
        segment.refine = original
    return result, snaps, seen.get("ctx")


def pieces(seg_of_point: np.ndarray, truth: np.ndarray, obj: int, piece: float) -> tuple[str, list[str]]:
    """The segments holding at least ``piece`` of object ``obj``'s points, with the
    object each holds most of where that is another one; and the same without the
    segment numbers (a stage that renumbers the segments changes nothing)."""
    mine = truth == obj
    n_seg = int(seg_of_point.max()) + 1
    counts = np.bincount(seg_of_point[mine], minlength=n_seg)
    total = max(int(mine.sum()), 1)
    out = []
    for s in np.flatnonzero(counts >= piece * total).tolist():
        major = int(np.bincount(truth[seg_of_point == s]).argmax())
        out.append((s, f"{counts[s] / total:.2f}" + ("" if major == obj else f"(of {major})")))
    return " ".join(f"{s}:{text}" for s, text in out), sorted(text for _, text in out)


def report(name: str, settings) -> None:
    from clearcli.evaluate.exact import PIECE, exact_report
    from clearcli.io.frames import object_ids

    foreign = _foreign()
    frame, labels, spec = foreign.load(name)
    result, snaps, ctx = staged(frame, settings)
    verdicts = exact_report(result.labels(), labels).verdicts
    print(f"== {name}")
    if ctx is None or ctx.point_index is None:
        return
    truth = object_ids(labels)[ctx.point_index]
    for k, verdict in enumerate(verdicts):
        if verdict == "right":
            continue
        print(f"  {k + 1} {spec['object'][k]['name']}: {verdict}")
        before: list[str] | None = None
        for step, seg in snaps:
            text, now = pieces(np.asarray(seg)[ctx.vox.point_voxel], truth, k + 1, PIECE)
            if now != before:
                print(f"      {step:10s} {text}")
            before = now


def main() -> None:
    from clearcli.settings import Settings, apply_sets

    parser = argparse.ArgumentParser()
    parser.add_argument("frames", nargs="*", metavar="FRAME", help="choose-part frames (default: all of them)")
    parser.add_argument("--set", action="append", default=[], metavar="SECTION.KEY=VALUE")
    args = parser.parse_args()
    choose = _foreign().names("choose")
    wrong = [f for f in args.frames if f not in choose]
    if wrong:
        parser.error(f"not frames of the choose part: {', '.join(wrong)}")
    settings = apply_sets(Settings(), args.set)
    for name in args.frames or choose:
        report(name, settings)


if __name__ == "__main__":
    main()
