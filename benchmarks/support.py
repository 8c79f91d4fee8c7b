"""The support families of issue 37 (`clearcli.sim.families.SUPPORT_FAMILIES`) per sensor
variant: objects exactly right, missed, and spurious segments (clearcli/evaluate/exact.py).

    .venv/bin/python benchmarks/support.py [--seeds choose|report] [--n 8] [--families a,b] [--variants kinect,hd,stereo,hd_stereo] [--off]

Variants: the scene's own Kinect view; ``hd``: a RealSense at 1280x720 seen obliquely
(0.6 m above the table, 35 degrees down); ``stereo``: the Kinect with stereo-like noise;
``hd_stereo``: both. Choose settings on seeds 0.. (`--seeds choose`), report 1000.. once.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from clearcli.evaluate.exact import exact_report  # noqa: E402
from clearcli.perception.segment import segment  # noqa: E402
from clearcli.settings.segment import SegmentSettings  # noqa: E402
from clearcli.sim.families import REALSENSE_HD, STEREO_NOISE, SUPPORT_FAMILIES, support_frame  # noqa: E402

OBLIQUE = (0.6, 35.0)
VARIANTS = {
    "kinect": {},
    "hd": {"camera": REALSENSE_HD, "view": OBLIQUE},
    "stereo": {"noise": STEREO_NOISE},
    "hd_stereo": {"camera": REALSENSE_HD, "view": OBLIQUE, "noise": STEREO_NOISE},
}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", choices=("choose", "report"), default="choose")
    ap.add_argument("--n", type=int, default=8)
    ap.add_argument("--families", default=",".join(SUPPORT_FAMILIES))
    ap.add_argument("--variants", default=",".join(VARIANTS))
    ap.add_argument("--verbose", action="store_true", help="per frame lines")
    ap.add_argument(
        "--off",
        action="store_true",
        help="beyond_edge_own_load, mat_below_seen_max_share and raised_below_seen_max_share off (as before them)",
    )
    args = ap.parse_args()
    first = 0 if args.seeds == "choose" else 1000
    settings = SegmentSettings()
    if args.off:
        settings = dataclasses.replace(
            settings, beyond_edge_own_load=False, mat_below_seen_max_share=1.0, raised_below_seen_max_share=1.0
        )
    tot = [0, 0, 0, 0, 0]
    for name in args.families.split(","):
        for variant in args.variants.split(","):
            acc = [0, 0, 0, 0, 0]  # frames, objects, right, missed, spurious
            bad = []
            for seed in range(first, first + args.n):
                try:
                    frame = support_frame(name, seed, **VARIANTS[variant])  # type: ignore[arg-type]
                    labels = segment(frame, settings).labels()
                except Exception as exc:  # noqa: BLE001 - a frame with no table counts all missed
                    print(f"  {name} {variant} {seed}: {type(exc).__name__} {exc}")
                    continue
                r = exact_report(labels, frame.fields["label"])
                acc = [a + b for a, b in zip(acc, [1, r.n_objects, r.right, r.missed, r.spurious], strict=True)]
                if r.right != r.n_objects or r.spurious:
                    bad.append(f"{seed}:{r.right}/{r.n_objects} m{r.missed} g{r.merged} s{r.split} sp{r.spurious}")
            tot = [a + b for a, b in zip(tot, acc, strict=True)]
            print(
                f"{name:15s} {variant:9s} right {acc[2]:3d}/{acc[1]:3d} missed {acc[3]:2d} spurious {acc[4]:2d}", end=""
            )
            print(("   " + " ".join(bad)) if args.verbose else "", flush=True)
    print(f"TOTAL frames {tot[0]} right {tot[2]}/{tot[1]} missed {tot[3]} spurious {tot[4]}")


if __name__ == "__main__":
    main()
