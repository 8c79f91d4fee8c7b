"""Frames as other cameras and labs write them: the same objects? (issue 37)

    .venv/bin/python benchmarks/conventions.py [--sets mosd,uois,fixtures,cleargrasp] [--first N]

Every organized frame of the sets is segmented as read (an optical image, upright), then
as each variant of `clearcli.sim.conventions` writes the same view: OpenGL's axes (y up,
looking along -z), ROS camera_link's (x forward, y left, z up), the camera upside down,
on its side, camera_link and upside down. These only reorder and negate coordinates and
move pixels, so the objects should be the frame's, pixel for pixel: per set and variant,
the frames whose labels are identical (carried back to the frame's pixels), and the median
extra time of a variant's segmentation against the frame's.

The same without pixels: the finite points of the frame and of the OpenGL, camera_link and
upside-down variants as unorganized clouds, in the same order: labels identical?

Then the frame moved into a z-up frame whose origin lies 0.75 m beneath the table (a
mobile robot's base on the floor; `beneath_the_table`), organized and as an unorganized
cloud: not the same processing (no camera at the origin: no range noise, no rays), so
per set the frames whose objects are the same (count equal, each matched at IoU >= 0.95)
and those with the same count; and the frames refused (before stop 59 every one was:
"seen from below").
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from clearcli.errors import ClearError  # noqa: E402
from clearcli.io.frames import Frame  # noqa: E402
from clearcli.io.read import read_frame  # noqa: E402
from clearcli.perception.segment import segment  # noqa: E402
from clearcli.perception.stability import same_objects  # noqa: E402
from clearcli.settings.segment import SegmentSettings  # noqa: E402
from clearcli.sim.conventions import beneath_the_table, variants  # noqa: E402

DATA = REPO.parent / "shared" / "data"
SETS = {
    "mosd": sorted((DATA / "mosd").rglob("*.pcd")),
    "uois": sorted((DATA / "scenes" / "uois_realsense").glob("*.pcd")),
    "fixtures": sorted((REPO / "fixtures").glob("*.pcd")),
    "cleargrasp": sorted((DATA / "scenes" / "cleargrasp_d435").glob("*.pcd")),
}


def _unorganized(frame: Frame, rows: np.ndarray) -> Frame:
    """``frame``'s points ``rows`` (in that order) as an unorganized cloud."""
    colors = None if frame.colors is None else np.ascontiguousarray(frame.colors[rows])
    return Frame(points=np.ascontiguousarray(frame.points[rows]), colors=colors, source=frame.source)


def _timed(frame: Frame, settings: SegmentSettings) -> tuple[object, float]:
    start = time.perf_counter()
    try:
        return segment(frame, settings), time.perf_counter() - start
    except ClearError as err:
        return err, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sets", default="mosd,uois,fixtures,cleargrasp")
    parser.add_argument("--first", type=int, default=None, help="only the first N frames of each set")
    args = parser.parse_args()
    settings = SegmentSettings()
    for set_name in args.sets.split(","):
        paths = SETS[set_name][: args.first]
        same: dict[str, int] = {}
        extra: dict[str, list[float]] = {}
        beneath = {"organized": [0, 0, 0], "unorganized": [0, 0, 0]}  # same objects, same count, refused
        n = 0
        for path in paths:
            frame = read_frame(path)
            if not frame.is_organized or frame.shape is None:
                continue
            base, t0 = _timed(frame, settings)
            if isinstance(base, ClearError):
                continue
            n += 1
            labels = base.labels()  # type: ignore[attr-defined]
            made = variants(frame)  # once: the organized rows and the unorganized ones read them
            for name, (variant, pixels) in made.items():
                seg, t = _timed(variant, settings)
                back = np.zeros(frame.n_points, dtype=np.int32)
                if not isinstance(seg, ClearError):
                    back[pixels] = seg.labels()  # type: ignore[attr-defined]
                same[name] = same.get(name, 0) + int(np.array_equal(back, labels))
                extra.setdefault(name, []).append(t - t0)
            # without pixels: the finite points alone, optical against the axes' variants
            finite = np.flatnonzero(np.isfinite(frame.points).all(axis=1))
            loose_optical, _ = _timed(_unorganized(frame, finite), settings)
            if not isinstance(loose_optical, ClearError):
                for name in ("opengl", "camera_link", "upside_down"):
                    variant, pixels = made[name]
                    at = np.argsort(pixels)[finite]  # each finite frame pixel's place in the variant
                    seg, _ = _timed(_unorganized(variant, at), settings)
                    ok = not isinstance(seg, ClearError) and np.array_equal(
                        seg.labels(),  # type: ignore[attr-defined]
                        loose_optical.labels(),  # type: ignore[attr-defined]
                    )
                    key = f"unorganized {name}"
                    same[key] = same.get(key, 0) + int(ok)
            table = base.table  # type: ignore[attr-defined]
            moved = beneath_the_table(frame, table.normal, table.offset)
            keep = np.isfinite(moved.points).all(axis=1)
            loose = Frame(
                points=np.ascontiguousarray(moved.points[keep]),
                colors=None if moved.colors is None else np.ascontiguousarray(moved.colors[keep]),
                source=moved.source,
            )
            for kind, other in (("organized", moved), ("unorganized", loose)):
                seg, _ = _timed(other, settings)
                if isinstance(seg, ClearError):
                    beneath[kind][2] += 1
                    continue
                if kind == "unorganized":  # indices into the kept points: carried back to the frame's
                    at = np.flatnonzero(keep)
                    seg = dataclasses.replace(
                        seg,  # type: ignore[type-var]
                        n_points=frame.n_points,
                        table_indices=at[seg.table_indices],  # type: ignore[attr-defined]
                        objects=tuple(dataclasses.replace(o, indices=at[o.indices]) for o in seg.objects),  # type: ignore[attr-defined]
                    )
                beneath[kind][0] += int(same_objects(base, seg))  # type: ignore[arg-type]
                beneath[kind][1] += int(len(seg.objects) == len(base.objects))  # type: ignore[attr-defined]
        print(f"{set_name}: {n} organized frames")
        for name in same:
            timed = f"   extra time median {1e3 * float(np.median(extra[name])):+6.1f} ms" if name in extra else ""
            print(f"  {name:<24} labels identical {same[name]:>3} of {n}{timed}")
        for kind, (objects, count, refused) in beneath.items():
            print(
                f"  beneath the table, {kind:<11} same objects {objects:>3} of {n}, "
                f"same count {count:>3}, refused {refused}"
            )


if __name__ == "__main__":
    main()
