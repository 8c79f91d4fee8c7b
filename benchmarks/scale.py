"""`segment` as the points grow: time and peak memory, organized and unorganized.

    .venv/bin/python benchmarks/scale.py [--sizes 0.3,1,2,5]
    .venv/bin/python benchmarks/scale.py --quality   # F1 on mOSD, organized and unorganized

Frames are made from mOSD test57 (shared data): organized, its 640 x 480 grid upsampled
by repeating pixels (1 x 1, 2 x 2, 3 x 3, 4 x 4: 0.3, 1.2, 2.8, 4.9 million points);
unorganized, its finite points (171k) in several copies, each moved by 1 mm Gaussian
noise (merged views, a dense scanner), the number of copies chosen for 0.3, 1, 2 and 5
million points. Each size runs in a fresh process (so peak memory is that run's):
`segment()` on the frame with the default settings, timed from the frame in memory to the
segmentation. Printed: points, seconds (and per stage), peak resident MB, objects found,
and the ratio of each time to the organized 640 x 480 frame's.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
SHARED = Path(os.environ.get("CLEAR_SHARED", REPO.parent / "shared")).resolve()

CHILD = r"""
import json, resource, sys, time
import numpy as np
from clearcli.io.read import read_frame
from clearcli.io.frames import Frame
from clearcli.perception.segment import segment
from clearcli.settings import Settings

kind, target = sys.argv[1], float(sys.argv[2])
base = read_frame(sys.argv[3])
if kind == "organized":
    f = int(round((target / 0.3072) ** 0.5))
    h, w = base.shape
    grid = base.points.reshape(h, w, 3)
    pts = np.repeat(np.repeat(grid, f, axis=0), f, axis=1).reshape(-1, 3)
    cols = None
    if base.colors is not None:
        c = base.colors.reshape(h, w, 3)
        cols = np.repeat(np.repeat(c, f, axis=0), f, axis=1).reshape(-1, 3)
    frame = Frame(points=pts, colors=cols, shape=(h * f, w * f), fields={}, source="up")
else:
    fin = np.isfinite(base.points).all(axis=1)
    p = base.points[fin]
    copies = max(1, int(round(target * 1e6 / p.shape[0])))
    rng = np.random.default_rng(0)
    pts = np.concatenate([p + (rng.normal(0, 0.001, p.shape).astype(np.float32) if k else 0) for k in range(copies)])
    cols = np.concatenate([base.colors[fin]] * copies) if base.colors is not None else None
    frame = Frame(points=pts.astype(np.float32), colors=cols, shape=None, fields={}, source="merged")
t0 = time.perf_counter()
seg = segment(frame, Settings().segment)
dt = time.perf_counter() - t0
peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
print(json.dumps({"kind": kind, "points": int(frame.n_points), "s": dt, "peak_mb": peak_mb,
                  "objects": len(seg.objects), "stages": {k: round(v, 3) for k, v in seg.timings_s.items()}}))
"""


def run(kind: str, size: float, frame: Path) -> dict:
    out = subprocess.run(
        [sys.executable, "-c", CHILD, kind, str(size), str(frame)],
        capture_output=True,
        text=True,
        timeout=3600,
        cwd=REPO,
    )
    if out.returncode != 0:
        raise SystemExit(f"{kind} {size}: {out.stderr[-2000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def quality() -> None:
    """Object F1 of `segment` on the 50 mOSD frames as recorded (organized) and as the
    unorganized cloud of their finite points (labels kept), scored the same way."""
    import numpy as np

    sys.path.insert(0, str(REPO))
    from clearcli.evaluate.segmentation import score
    from clearcli.io.frames import Frame
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment
    from clearcli.settings import Settings

    settings = Settings().segment
    frames = sorted((SHARED / "data/mosd/learn").glob("*.pcd")) + sorted((SHARED / "data/mosd/test").glob("*.pcd"))
    f1 = {"organized": [], "unorganized": []}
    for path in frames:
        frame = read_frame(path)
        truth = np.asarray(frame.fields["label"]).ravel()
        f1["organized"].append(score(segment(frame, settings).labels(), truth).f1)
        fin = np.isfinite(frame.points).all(axis=1)
        flat = Frame(
            points=frame.points[fin],
            colors=None if frame.colors is None else frame.colors[fin],
            shape=None,
            fields={},
            source=path.name,
        )
        f1["unorganized"].append(score(segment(flat, settings).labels(), truth[fin]).f1)
    for kind, values in f1.items():
        print(f"mOSD all {len(values)}, {kind:11s}: mean object F1 {np.mean(values):.3f}")
    worse = [(frames[k].stem, a, b) for k, (a, b) in enumerate(zip(f1["organized"], f1["unorganized"])) if b < a - 1e-9]
    print(f"unorganized worse on {len(worse)} frames: " + ", ".join(f"{n} {a:.2f}->{b:.2f}" for n, a, b in worse))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="0.3,1,2,5", help="millions of points")
    ap.add_argument("--quality", action="store_true", help="only: F1 on the 50 mOSD frames, organized and not")
    args = ap.parse_args()
    if args.quality:
        quality()
        return
    frame = SHARED / "data/mosd/test/test57.pcd"
    sizes = [float(s) for s in args.sizes.split(",")]
    base = None
    for kind in ("organized", "unorganized"):
        for size in sizes:
            r = run(kind, size, frame)
            if base is None:
                base = r["s"]
            stages = ", ".join(f"{k} {v:.2f}" for k, v in r["stages"].items() if k != "total")
            print(
                f"{kind:11s} {r['points'] / 1e6:5.2f} M points  {r['s']:7.2f} s  ({r['s'] / base:5.1f} x the "
                f"640 x 480 frame)  peak {r['peak_mb']:6.0f} MB  {r['objects']:2d} objects   [{stages}]",
                flush=True,
            )


if __name__ == "__main__":
    main()
