"""Every micrometre flip, seed by seed, with the stage it starts at (issue 37).

    .venv/bin/python benchmarks/flips.py [--sets mosd,uois,fixtures,scenes,rgbd]
        [--amplitude-um 1] [--seeds 0:10] [--with-report] [--margins] [--set KEY=VALUE]

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


def cases(sets: list[str], skip: set[str]) -> Iterator[tuple[str, Path]]:
    """(set name, frame path) of the sets, without the frames in ``skip``."""
    all_sets = sb.frame_sets()
    for name in sets:
        paths = sorted(RGBD.glob("*_depth.png")) if name == "rgbd" else all_sets[name]
        for p in paths:
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
    args = parser.parse_args()
    settings = SegmentSettings()
    for item in args.set:
        key, _, text = item.partition("=")
        kind = type(getattr(settings, key))
        value = text.lower() in ("1", "true", "yes") if kind is bool else kind(text)
        settings = dataclasses.replace(settings, **{key: value})
    amp = args.amplitude_um * 1e-6
    first_seed, last_seed = (int(x) for x in args.seeds.split(":"))
    skip = set() if args.with_report else report_frames()
    runs = flips = 0
    starts: dict[str, int] = {}
    for set_name, path in cases(args.sets.split(","), skip):
        frame = read_frame(path)
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
