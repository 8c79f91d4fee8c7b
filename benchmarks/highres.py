"""High resolution: the working grid (clearcli/perception/resolution.py) on 1280x720 frames.

    .venv/bin/python benchmarks/highres.py [--rounds 5] [--skip-full]

1. The rule: each frame set's pixel pitch and the stride k it gets (the 640x480 sets
   must keep k = 1).
2. Full against working resolution on the 1280x720 RealSense frames
   (scenes/cleargrasp_d435) and any other frame the rule thins: the objects of
   ``segment(frame, stride=1)`` (every pixel) against ``segment(frame)`` (the working
   grid, labels carried back to every pixel), matched one to one by IoU on the full
   grid (greedy, best pair first, pairs at IoU >= 0.5): counts, matched, and how many
   match at IoU >= 0.9.
3. Time: warm ``segment`` of every frame, interleaved round by round (the machine may
   be loaded: only ratios measured in one run mean anything), medians per set: the
   1280x720 frames at the working grid and at full resolution, the nine 640x480
   RealSense frames (uois) and five mOSD frames; ratios to the 640x480 sets.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from clearcli.io.read import read_frame  # noqa: E402
from clearcli.perception.resolution import choose_stride, pixel_pitch  # noqa: E402
from clearcli.perception.segment import segment  # noqa: E402
from clearcli.perception.types import Segmentation  # noqa: E402
from clearcli.settings.segment import SegmentSettings  # noqa: E402

DATA = REPO.parent / "shared" / "data"
SETS = {
    "cleargrasp 1280x720": sorted((DATA / "scenes/cleargrasp_d435").glob("*.pcd")),
    "uois 640x480": sorted((DATA / "scenes/uois_realsense").glob("*.pcd")),
    "mOSD 640x480": [
        DATA / f"mosd/{n}.pcd" for n in ("test/test44", "test/test57", "learn/learn5", "learn/learn30", "learn/learn40")
    ],
}
OTHERS = sorted((DATA / "scenes/gqcnn").glob("*.pcd")) + sorted((DATA / "scenes/pcl").glob("*.pcd"))


def match(a: Segmentation, b: Segmentation) -> list[tuple[int, int, float]]:
    """One-to-one pairs (object of a, object of b, IoU) at IoU >= 0.5, best first."""
    n = a.n_points
    la = np.full(n, -1, np.int64)
    lb = np.full(n, -1, np.int64)
    for i, o in enumerate(a.objects):
        la[o.indices] = i
    for j, o in enumerate(b.objects):
        lb[o.indices] = j
    both = (la >= 0) & (lb >= 0)
    inter = np.zeros((len(a.objects), len(b.objects)))
    np.add.at(inter, (la[both], lb[both]), 1)
    na = np.array([o.n_points for o in a.objects], dtype=float)
    nb = np.array([o.n_points for o in b.objects], dtype=float)
    iou = inter / np.maximum(na[:, None] + nb[None, :] - inter, 1)
    pairs = []
    used_a: set[int] = set()
    used_b: set[int] = set()
    for flat in np.argsort(-iou, axis=None, kind="stable"):
        i, j = np.unravel_index(flat, iou.shape)
        if iou[i, j] < 0.5:
            break
        if i in used_a or j in used_b:
            continue
        used_a.add(int(i))
        used_b.add(int(j))
        pairs.append((int(i), int(j), float(iou[i, j])))
    return pairs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--skip-full", action="store_true", help="no full-resolution timing of the 1280x720 frames")
    args = ap.parse_args()
    settings = SegmentSettings()
    frames = {name: [read_frame(p) for p in paths] for name, paths in SETS.items()}

    print("1. the rule: pixel pitch (mrad, rows x columns) and stride k")
    for name, fs in [*frames.items(), ("others (gqcnn, pcl)", [read_frame(p) for p in OTHERS])]:
        for f in fs:
            pitch = pixel_pitch(f.points, f.shape) if f.shape is not None else None
            text = "no pinhole grid" if pitch is None else f"{pitch[0] * 1e3:.3f} x {pitch[1] * 1e3:.3f}"
            print(
                f"   {name:22s} {Path(f.source).name:34s} {f.shape!s:12s} {text:16s} k = {choose_stride(f, settings)}"
            )

    print("\n2. full resolution (every pixel) against the working grid, labels on the full grid")
    thinned = [f for fs in frames.values() for f in fs] + [read_frame(p) for p in OTHERS]
    thinned = [f for f in thinned if choose_stride(f, settings) > 1]
    for f in thinned:
        full = segment(f, settings, stride=1)
        work = segment(f, settings)
        pairs = match(full, work)
        ious = [p[2] for p in pairs]
        at90 = sum(i >= 0.9 for i in ious)
        worst = f"{min(ious):.3f}" if ious else "-"
        print(
            f"   {Path(f.source).name:34s} objects full {len(full.objects):2d}, working {len(work.objects):2d}; "
            f"matched {len(pairs):2d}, at IoU >= 0.9: {at90:2d}, mean IoU {np.mean(ious) if ious else 0:.3f}, worst {worst}"
        )

    print(f"\n3. warm segment time, {args.rounds} rounds interleaved (medians per frame, then per set)")
    timed: dict[str, list[tuple[object, int | None]]] = {name: [(f, None) for f in fs] for name, fs in frames.items()}
    if not args.skip_full:
        timed["cleargrasp full res"] = [(f, 1) for f in frames["cleargrasp 1280x720"]]
    times: dict[str, list[list[float]]] = {name: [[] for _ in items] for name, items in timed.items()}
    segment(frames["mOSD 640x480"][0], settings)  # warm
    for _ in range(args.rounds):
        for name, items in timed.items():
            for i, (f, stride) in enumerate(items):
                start = time.perf_counter()
                segment(f, settings, stride=stride)  # type: ignore[arg-type]
                times[name][i].append(time.perf_counter() - start)
    med = {name: statistics.median(statistics.median(t) for t in per) for name, per in times.items()}
    for name, m in med.items():
        print(f"   {name:22s} median {m * 1e3:7.1f} ms")
    for hi in [n for n in ("cleargrasp 1280x720", "cleargrasp full res") if n in med]:
        for lo in ("uois 640x480", "mOSD 640x480"):
            print(f"   {hi} / {lo}: {med[hi] / med[lo]:.2f}x")


if __name__ == "__main__":
    main()
