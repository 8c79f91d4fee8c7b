"""Every micrometre flip, seed by seed, with the stage it starts at (issue 37).

    .venv/bin/python benchmarks/flips.py [--sets mosd,uois,fixtures,scenes,rgbd]
        [--amplitude-um 1] [--seeds 0:10] [--with-report] [--margins] [--set KEY=VALUE]
        [--fixed-draws] [--dither-mm 0.5]
    .venv/bin/python benchmarks/flips.py --table --sets mosd,fixtures,foreign --first 12 --seeds 0:6

stability.py traces only the first perturbation seed that changes a frame's objects;
this traces every one, so a flip that starts in a later stage is not hidden behind a
supervoxel flip of the same frame under another seed. Per flip: frame, seed, object
counts, the first step whose groups differ (stability.first_difference: a group of at
least 30 points without a partner at IoU >= 0.95), the points that changed group there
and at the end, and the whole chain
(groups unmatched/points moved per step; a merge of two groups moves no point).
With --margins, per flip also the supervoxel stage's first decisions that differ
(stability.supervoxel_decisions: seed voxels that lost or gained points or whose normal
turned, and per assignment the voxels that changed seed, nearest a tie first, with their
cost margins), and LCCP's decisive edges (stability.decisive_edges): the
adjacencies both runs have whose supervoxels end in one segment in one run and two in
the other, each changed test's margin before -> after, and the supervoxels that lost or
gained voxels (a margin rule at LCCP can only catch a flip whose margins moved less
than the rule's band; one voxel more or less in a supervoxel moves them by far more).

Sets: stability.py's (points moved by uniform noise in [-a, +a] per coordinate), and
"rgbd": the RealSense depth PNGs of ../shared/data/rgbd/uois read by clear's RGB-D
reader, against the same depth image with every depth value moved by [-a, +a] (the
float depth, back-projected by clear: what a sensor's float depth or a different
rounding gives); for each it also checks that float32 -> float64 -> float32 of the
points is bit-identical and segments the same.

With --table, the table step alone (issue 37): per frame and seed, the points whose
table-step class differs from the unperturbed run's (on the chosen plane: the table step's
table; on a rejected plane: within plane_distance_m of another plane find_table found;
neither; filtered out), and the frames whose chosen plane moved. Its sets may include
"foreign", the foreign frames of the "choose" part; --first N takes the first N frames of
each set (mosd's first 12 are learn frames).

The "report" part of the foreign frames (benchmarks/foreign/*.toml, part = "report") is
left out unless --with-report: flips are hunted on the frames settings may be chosen on.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tomllib
from collections.abc import Iterator
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "benchmarks"))

import stability as sb  # noqa: E402

from clearcli.errors import ClearError  # noqa: E402
from clearcli.io.frames import Frame  # noqa: E402
from clearcli.io.read import read_frame  # noqa: E402
from clearcli.perception import segment as seg_mod  # noqa: E402
from clearcli.perception.stability import perturbed, same_objects  # noqa: E402
from clearcli.settings.segment import SegmentSettings  # noqa: E402

RGBD = sb.SHARED / "rgbd" / "uois"


def report_frames() -> set[str]:
    """Stems of the foreign frames of the "report" part (their toml's source)."""
    out = set()
    for p in sorted((REPO / "benchmarks" / "foreign").glob("*.toml")):
        spec = tomllib.loads(p.read_text(encoding="utf-8"))
        if spec.get("part") == "report":
            out.add(Path(str(spec.get("source", p.stem))).stem)
    return out


def foreign_choose() -> list[Path]:
    """The frames of the foreign "choose" part (their toml's source), by name."""
    out = []
    for p in sorted((REPO / "benchmarks" / "foreign").glob("*.toml")):
        spec = tomllib.loads(p.read_text(encoding="utf-8"))
        if spec.get("part") == "choose":
            out.append(sb.SHARED / str(spec["source"]))
    return out


def table_classes(frame: Frame, settings: SegmentSettings) -> tuple[np.ndarray, np.ndarray]:
    """The table step's class of each of ``frame``'s points on segment's working grid: 0 on
    the chosen plane (the step's table), 1 on a rejected plane (within plane_distance_m of
    another plane find_table found), 2 neither, -1 filtered out; and the chosen plane
    (normal, offset) as 4 numbers (NaN when the frame is refused)."""
    from clearcli.perception.clock import Clock
    from clearcli.perception.resolution import WorkingGrid

    f = WorkingGrid.of(frame, settings, None).frame
    organized = f.is_organized and f.shape is not None and f.shape[0] * f.shape[1] == f.n_points
    w = seg_mod._Work(f, settings, organized, Clock())
    out = np.full(f.n_points, -1, dtype=np.int64)
    try:
        seg_mod._filter(w)
        seg_mod._table(w)
    except ClearError:
        return out, np.full(4, np.nan)
    assert w.fit is not None
    rejected = np.zeros(w.pts.shape[0], dtype=bool)
    for v in w.fit.planes[1:]:
        rejected |= np.abs(w.pts @ np.asarray(v.normal) + v.offset_m) <= settings.plane_distance_m
    out[w.idx] = np.where(w.table_mask, 0, np.where(rejected, 1, 2))
    return out, np.append(w.fit.plane.normal, w.fit.plane.offset)


def table_step(
    sets: list[str], skip: set[str], first: int | None, seeds: range, amp_m: float, settings: SegmentSettings
) -> None:
    """--table: per frame, the points whose table-step class changed under each seed."""
    total = runs = changed_runs = moved_planes = filtered = over_100 = 0
    for set_name, path in cases(sets, skip, first):
        if set_name == "rgbd":
            continue
        frame = read_frame(path)
        base, base_plane = table_classes(frame, settings)
        per_seed = []
        for seed in seeds:
            classes, plane = table_classes(perturbed(frame, amp_m, seed=seed), settings)
            per_seed.append(int((classes != base).sum()))
            # the filter kept other points: the RANSAC sample (every k-th kept point) shifts
            filtered += bool(((classes == -1) != (base == -1)).any())
            # the chosen plane moved by more than rounding: another plane chosen, or refit
            if not np.allclose(plane, base_plane, atol=1e-4, equal_nan=True):
                moved_planes += 1
        runs += len(per_seed)
        changed_runs += sum(1 for k in per_seed if k)
        over_100 += sum(1 for k in per_seed if k > 100)
        total += sum(per_seed)
        print(f"{set_name:8s} {path.name:36s} points changed class per seed: {per_seed}", flush=True)
    print(
        f"+-{amp_m * 1e6:g} um, table step: {total} point-class changes in {runs} runs "
        f"({changed_runs} runs with any, {over_100} with over 100); chosen plane moved in {moved_planes} runs; "
        f"the filter kept other points in {filtered} runs"
    )


def _depth_moved(path: Path, amp_m: float, seed: int) -> Frame:
    """The depth image at ``path`` read as clear reads it, every depth value moved by
    uniform noise in [-amp_m, +amp_m] (0, no reading, stays 0), back-projected."""
    from clearcli.io.images import find_intrinsics, or_defaults, read_depth_m
    from clearcli.io.intrinsics import back_project

    images = or_defaults(None)
    depth = read_depth_m(path, images.depth_scale_m)
    rng = np.random.default_rng(seed)
    moved = depth.astype(np.float64) + rng.uniform(-amp_m, amp_m, size=depth.shape)
    moved[~(depth > 0)] = 0.0
    base = read_frame(path)
    return dataclasses.replace(base, points=back_project(moved.astype(np.float32), find_intrinsics(path, images)))


def cases(sets: list[str], skip: set[str], first: int | None = None) -> Iterator[tuple[str, Path]]:
    """(set name, frame path) of the sets (the first ``first`` of each), without the frames
    in ``skip``."""
    all_sets = sb.frame_sets()
    all_sets["foreign"] = foreign_choose()
    for name in sets:
        paths = sorted(RGBD.glob("*_depth.png")) if name == "rgbd" else all_sets[name]
        for p in paths[:first]:
            stem = "uois_image_" + p.stem.split("_")[1] if name == "rgbd" else p.stem
            if stem not in skip:
                yield name, p


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sets", default="mosd,uois,fixtures,scenes,rgbd")
    parser.add_argument("--amplitude-um", type=float, default=1.0)
    parser.add_argument("--seeds", default="0:10", help="perturbation seeds, first:last (last excluded)")
    parser.add_argument("--with-report", action="store_true", help="also the foreign report part's frames")
    parser.add_argument(
        "--margins",
        action="store_true",
        help="per flip, LCCP's decisive edges: each changed test's margin before -> after (stability.decisive_edges)",
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a SegmentSettings field to try, e.g. --set supervoxel_share_cost=0.01",
    )
    parser.add_argument("--table", action="store_true", help="the table step's point classes alone (issue 37)")
    parser.add_argument("--first", type=int, default=None, help="only the first N frames of each set")
    parser.add_argument(
        "--dither-mm",
        type=float,
        default=0.0,
        help="first move every point by a fixed uniform draw in [-D, +D] mm (seed 9999): a whole-millimetre "
        "frame made a float-metre one, whose micrometre flips can then be hunted on labelled frames",
    )
    parser.add_argument(
        "--fixed-draws", action="store_true", help="with settings.ransac_fixed_draws (as --set ransac_fixed_draws=1)"
    )
    args = parser.parse_args()
    settings = SegmentSettings(ransac_fixed_draws=args.fixed_draws)
    for item in args.set:
        key, _, text = item.partition("=")
        kind = type(getattr(settings, key))
        value = text.lower() in ("1", "true", "yes") if kind is bool else kind(text)
        settings = dataclasses.replace(settings, **{key: value})
    amp = args.amplitude_um * 1e-6
    first_seed, last_seed = (int(x) for x in args.seeds.split(":"))
    skip = set() if args.with_report else report_frames()
    if args.table:
        # never the foreign report part: its frames are not looked at one by one
        table_step(args.sets.split(","), report_frames(), args.first, range(first_seed, last_seed), amp, settings)
        return
    runs = flips = 0
    starts: dict[str, int] = {}
    for set_name, path in cases(args.sets.split(","), skip, args.first):
        frame = read_frame(path)
        if args.dither_mm > 0:
            frame = perturbed(frame, args.dither_mm * 1e-3, seed=9999)
        try:
            base = seg_mod.segment(frame, settings)
        except ClearError:
            continue  # refused as read: stability.py checks the moved copies are refused too
        if set_name == "rgbd":
            twice = dataclasses.replace(frame, points=frame.points.astype(np.float64).astype(np.float32))
            same = np.array_equal(twice.points, frame.points, equal_nan=True)
            same = same and same_objects(base, seg_mod.segment(twice, settings))
            print(f"{path.name}: float32 -> float64 -> float32 {'identical' if same else 'DIFFERENT'}", flush=True)
        for seed in range(first_seed, last_seed):
            runs += 1
            other = _depth_moved(path, amp, seed) if set_name == "rgbd" else perturbed(frame, amp, seed=seed)
            try:
                moved = seg_mod.segment(other, settings)
            except ClearError as err:
                flips += 1
                print(f"{path.name} seed {seed}: refused when moved ({err})", flush=True)
                continue
            if same_objects(base, moved):
                continue
            flips += 1
            steps = sb.first_difference(frame, other, settings)
            name, groups, points = next(((n, u, m) for n, u, m in steps if u > 0), ("objects", 0, 0))
            starts[name] = starts.get(name, 0) + 1
            print(
                f"{path.name} seed {seed}: {len(base.objects)} vs {len(moved.objects)} objects; first differing "
                f"{name} ({groups} groups, {points} points); at the end {steps[-1][1]} groups, {steps[-1][2]} points",
                flush=True,
            )
            # a merge moves no point out of its group's best partner (the merged group holds it
            # all): a step with groups unmatched is shown with 0 points moved too
            print("    " + ", ".join(f"{n} {u}/{m}" for n, u, m in steps if m or u), flush=True)
            if args.margins:
                for line in sb.supervoxel_decisions(frame, other, settings):
                    print("      " + line, flush=True)
                for line in sb.decisive_edges(frame, other, settings):
                    print("      " + line, flush=True)
    print(f"+-{args.amplitude_um:g} um: {flips} flips in {runs} runs (seeds {args.seeds})")
    if starts:
        print("first differing step:", ", ".join(f"{k} {v}" for k, v in sorted(starts.items())))


if __name__ == "__main__":
    main()
