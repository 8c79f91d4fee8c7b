"""Train the learned join (clearcli/perception/learned.py) from labelled frames.

    .venv/bin/python training/join.py extract   # segment the frames -> training/join_pairs.csv
    .venv/bin/python training/join.py fit       # join_pairs.csv -> clearcli/data/join_model.json
    .venv/bin/python training/join.py           # both
    .venv/bin/python training/join.py heldout   # the choose part's verdicts, each frame
                                                # segmented with a model fitted without it

Data: the 45 mOSD learn frames (../shared/data/mosd/learn, their ``label`` field), the
choose part of the foreign frames (benchmarks/foreign/*.toml with ``part = "choose"``;
the report part is never read) and self-made renders (`SIM_FAMILIES`, choose seeds),
each as it is and with added depth noise (`VARIANTS`). Each frame is segmented with
the default settings and the learned join off; every pair of touching segments is one
row: its `FEATURES`, whether both segments are mostly one labelled object (1), two
different ones or one object and the table (0), and the lesser of the two segments'
purities (the share of a segment's points its own object holds: a pair of segments
half one object and half another is no clear example); pairs of two unlabelled segments
are left out.

The fit is L2-regularised logistic regression on standardised features by Newton's
method, a fixed number of steps from zero: no random draw, inputs in sorted order, the
numbers written rounded to 8 significant digits, so running ``fit`` again writes the
same file byte for byte (tests/perception/test_learned.py checks it).
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import importlib.util
import itertools
import json
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from clearcli.errors import ClearError  # noqa: E402
from clearcli.io.frames import object_ids  # noqa: E402
from clearcli.io.read import read_frame  # noqa: E402
from clearcli.perception import learned, segment  # noqa: E402
from clearcli.perception.learned import FEATURES, MARGIN_LOGIT, MODEL_FORMAT, JoinModel  # noqa: E402
from clearcli.settings.segment import SegmentSettings  # noqa: E402
from clearcli.sim.camera import render  # noqa: E402
from clearcli.sim.families import FAMILIES  # noqa: E402

DATA = REPO.parent / "shared" / "data"
PAIRS = Path(__file__).resolve().parent / "join_pairs.csv"
MODEL = REPO / "clearcli" / "data" / "join_model.json"
VERSION = (
    "join-2 (issue 37: mOSD learn 45, foreign choose 11, 100 renders, each with 3 noisy copies,"
    " segmented by the stages of main 5c7896b; logistic, L2 1.0)"
)
# self-made renders (clearcli/sim/families.py) on the choose seeds (0-99; the report
# seeds 1000-1099 are never used): cluttered families where objects touch
SIM_FAMILIES = ("dense_mix", "wide_objects", "open_container", "small_on_large", "small_against_tall")
SIM_SEEDS = range(20)
L2 = 1.0  # on the standardised weights (not the bias)
NEWTON_STEPS = 30


def _foreign():  # the benchmark's label reader, loaded by path (benchmarks is no package)
    spec = importlib.util.spec_from_file_location("foreign", REPO / "benchmarks" / "foreign.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _frames():  # -> iterator of (source, name, Frame, labels (N,))
    for i in range(45):
        frame = read_frame(DATA / "mosd" / "learn" / f"learn{i}.pcd")
        yield "mosd", f"learn{i}", frame, frame.fields["label"]
    foreign = _foreign()
    for name in foreign.names("choose"):
        frame, labels, _ = foreign.load(name)
        yield "foreign", name, frame, labels
    for family in SIM_FAMILIES:
        for seed in SIM_SEEDS:
            frame = render(FAMILIES[family](seed), seed=seed)
            yield "sim", f"{family}{seed}", frame, frame.fields["label"]


# each frame is segmented as it is, and with noise added to its depth (a sensor noisier
# than its own: most frames here are clean, and splits are what noisy depth makes):
# name suffix, sigma (m at 1 m range, growing with the squared range) of white noise and
# of a smooth field (drawn on a grid 16 pixels apart, interpolated: a structured
# light sensor's blotches), the draw's seed
VARIANTS: tuple[tuple[str, float, float, int], ...] = (
    ("", 0.0, 0.0, 0),
    ("@n2", 0.002, 0.002, 1),
    ("@n4", 0.004, 0.004, 2),
    ("@n6", 0.006, 0.006, 3),
)


def noisy(frame, white_m: float, smooth_m: float, seed: int):  # -> Frame
    """``frame`` with its points moved along their rays by range noise (`VARIANTS`)."""
    if white_m == 0 and smooth_m == 0:
        return frame
    rng = np.random.default_rng(seed)
    pts = frame.points.astype(np.float64)
    r = np.linalg.norm(pts, axis=1)
    n = rng.standard_normal(pts.shape[0]) * white_m
    if frame.shape is not None:
        h, w = frame.shape
        coarse = rng.standard_normal((h // 16 + 2, w // 16 + 2)) * smooth_m
        v, u = np.mgrid[0:h, 0:w] / 16.0
        v0, u0 = v.astype(np.int64), u.astype(np.int64)
        fv, fu = v - v0, u - u0
        field = (
            coarse[v0, u0] * (1 - fv) * (1 - fu)
            + coarse[v0 + 1, u0] * fv * (1 - fu)
            + coarse[v0, u0 + 1] * (1 - fv) * fu
            + coarse[v0 + 1, u0 + 1] * fv * fu
        )
        n = n + field.ravel()
    scale = 1.0 + n * r  # sigma * r^2 along the ray: (r + sigma r^2) / r
    return dataclasses.replace(frame, points=(pts * scale[:, None]).astype(np.float32))


def _pair_rows(frame, labels):  # -> (pairs, features, label per pair (-1: left out))
    captured = []
    original = segment.refine

    def capture(seg_of_voxel, ctx, clock=None):
        out = original(seg_of_voxel, ctx, clock)
        captured.append((out, ctx))
        return out

    segment.refine = capture
    try:
        segment.segment(frame, SegmentSettings(learned_join=False))
    except ClearError as exc:  # a noisy copy may lose its table: no pairs
        print(f"  the segmenter refused it: {str(exc).splitlines()[0][:100]}", flush=True)
        return None
    finally:
        segment.refine = original
    if not captured:
        return None
    seg, ctx = captured[0]
    feats = learned.pair_features(seg, ctx)
    if feats.pairs.shape[0] == 0 or ctx.point_index is None:
        return None
    truth = object_ids(labels)[ctx.point_index]
    seg_of_point = np.asarray(seg)[ctx.vox.point_voxel]
    n_seg = int(seg.max()) + 1
    n_id = int(truth.max()) + 1
    counts = np.bincount(seg_of_point * n_id + truth, minlength=n_seg * n_id).reshape(n_seg, n_id)
    major = counts.argmax(axis=1)  # ties: the lower id (0, no object, first)
    a, b = major[feats.pairs[:, 0]], major[feats.pairs[:, 1]]
    y = np.where((a == 0) & (b == 0), -1, ((a == b) & (a > 0)).astype(np.int64))
    # the share of each segment's points its own object holds (the lesser of the two):
    # a pair whose segments are near half another object's is no clear example
    purity = counts.max(axis=1) / np.maximum(counts.sum(axis=1), 1)
    return feats.pairs, feats.x, y, np.minimum(purity[feats.pairs[:, 0]], purity[feats.pairs[:, 1]])


def extract(out: Path = PAIRS) -> None:
    rows = []
    for source, name, frame, labels in _frames():
        for suffix, white, smooth, seed in VARIANTS:
            got = _pair_rows(noisy(frame, white, smooth, seed), labels)
            if got is None:
                continue
            pairs, x, y, purity = got
            keep = y >= 0
            print(f"{name + suffix:32s} pairs {int(keep.sum()):3d} one object {int((y == 1).sum()):3d}", flush=True)
            for (lo, hi), xi, yi, pi in zip(pairs[keep].tolist(), x[keep], y[keep].tolist(), purity[keep].tolist()):
                rows.append([source, name + suffix, lo, hi, yi, f"{pi:.3f}", *(f"{v:.6g}" for v in xi.tolist())])
    with out.open("w", newline="", encoding="utf-8") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["source", "frame", "seg_a", "seg_b", "one_object", "purity", *FEATURES])
        w.writerows(rows)
    print(f"{len(rows)} pairs -> {out}")


def read_pairs(path: Path = PAIRS, with_purity: bool = False):
    """(frame of each row, features (P, F), labels (P,)) of a pairs file, and with
    ``with_purity`` the lesser purity of each pair's two segments (P,)."""
    with path.open(encoding="utf-8") as f:
        rows = list(csv.reader(f))[1:]
    frames = [r[1] for r in rows]
    x = np.array([[float(v) for v in r[6:]] for r in rows], dtype=np.float64).reshape(len(rows), -1)
    y = np.array([int(r[4]) for r in rows], dtype=np.float64)
    if with_purity:
        return frames, x, y, np.array([float(r[5]) for r in rows], dtype=np.float64)
    return frames, x, y


def fit(x: np.ndarray, y: np.ndarray, l2: float = L2, steps: int = NEWTON_STEPS) -> dict:
    """The model file's content: logistic regression of ``y`` on ``x`` (standardised)."""
    mean = x.mean(axis=0)
    scale = x.std(axis=0)
    scale = np.where(scale > 1e-12, scale, 1.0)
    z = np.column_stack([(x - mean) / scale, np.ones(x.shape[0])])
    w = np.zeros(z.shape[1])
    reg = np.full(z.shape[1], l2)
    reg[-1] = 0.0
    for _ in range(steps):
        p = 1.0 / (1.0 + np.exp(-(z @ w)))
        grad = z.T @ (p - y) + reg * w
        hess = (z * (p * (1 - p))[:, None]).T @ z + np.diag(reg) + 1e-9 * np.eye(z.shape[1])
        w = w - np.linalg.solve(hess, grad)

    def r(v: np.ndarray) -> list[float]:
        return [float(f"{t:.8g}") for t in v.tolist()]

    return {
        "format": MODEL_FORMAT,
        "version": VERSION,
        "features": list(FEATURES),
        "mean": r(mean),
        "scale": r(scale),
        "weights": r(w[:-1]),
        "bias": r(w[-1:])[0],
        "trained_on": {"pairs": int(y.size), "one_object": int(y.sum())},
    }


def dumps(model: dict) -> str:
    return json.dumps(model, indent=1) + "\n"


def _source(frame: str) -> str:
    if frame.startswith("learn"):
        return "mOSD learn"
    return "sim renders" if frame.rstrip("@n0123456789").rstrip("0123456789") in SIM_FAMILIES else "foreign choose"


REPORT_MIN_P = (0.6, 0.7, 0.8, 0.9)


def report(frames: list[str], x: np.ndarray, y: np.ndarray, model: dict) -> None:
    """What the model joins at each of `REPORT_MIN_P` (plus the stage's margin), per
    source; and the same, each frame's pairs scored by a model fitted without that frame
    (and its noisy copies)."""
    logit = JoinModel.from_dict(model).logit(x)
    held = np.zeros_like(logit)
    # a frame and its noisy copies are held out together
    names = np.array([f.split("@")[0] for f in frames])
    for f in sorted(set(names.tolist())):
        mine = names == f
        held[mine] = JoinModel.from_dict(fit(x[~mine], y[~mine])).logit(x[mine])
    for min_p, (label, score) in itertools.product(REPORT_MIN_P, (("fitted on all", logit), ("held out, as-is", held))):
        cut = float(np.log(min_p / (1 - min_p))) + MARGIN_LOGIT
        for src in ("mOSD learn", "foreign choose", "sim renders"):
            sel = np.array([_source(n) == src for n in frames])
            sel &= np.array(["@" not in n for n in frames]) | (label == "fitted on all")
            yes = score[sel] >= cut
            t = y[sel] == 1
            print(
                f"p {min_p} {label:15s} {src:15s} pairs {int(sel.sum()):4d}"
                f" one object {int(t.sum()):3d}: joined right {int((yes & t).sum()):3d},"
                f" joined wrong {int((yes & ~t).sum()):3d}"
            )


def heldout(min_p: float, path: Path = PAIRS) -> dict[str, int]:
    """The foreign choose part's verdicts (benchmarks/foreign.py's) with the learned join
    on at ``min_p``, each frame segmented with a model fitted on the pairs of every other
    frame (its own and its noisy copies left out): what the stage would do on a frame it
    never saw."""
    from clearcli import pipeline  # noqa: PLC0415
    from clearcli.evaluate.exact import exact_report  # noqa: PLC0415
    from clearcli.settings import Settings, apply_sets  # noqa: PLC0415

    frames, x, y = read_pairs(path)
    names = np.array([f.split("@")[0] for f in frames])
    foreign = _foreign()
    settings = apply_sets(Settings(), ["segment.learned_join=true", f"segment.learned_join_min_p={min_p}"])
    totals = dict.fromkeys(("right", "merged", "split", "missed", "spurious"), 0)
    shipped = learned.load_model
    try:
        for name in foreign.names("choose"):
            model = JoinModel.from_dict(fit(x[names != name], y[names != name]))
            learned.load_model = lambda m=model: m  # type: ignore[misc]  # the stage reads this
            frame, truth, spec = foreign.load(name)
            r = exact_report(pipeline.segmented(frame, settings).labels(), truth)
            for k in totals:
                totals[k] += getattr(r, k)
            wrong = ", ".join(f"{o['name']}: {v}" for o, v in zip(spec["object"], r.verdicts) if v != "right")
            print(f"{name:34s} right {r.right:2d} of {r.n_objects:2d}" + (f"   [{wrong}]" if wrong else ""))
    finally:
        learned.load_model = shipped
    print(f"held out, p {min_p}: " + ", ".join(f"{k} {v}" for k, v in totals.items()))
    return totals


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("step", nargs="?", choices=("extract", "fit", "all", "heldout"), default="all")
    parser.add_argument("--min-p", type=float, default=0.7, help="heldout: the stage's threshold")
    args = parser.parse_args()
    if args.step == "heldout":
        heldout(args.min_p)
        return
    if args.step in ("extract", "all"):
        extract()
    if args.step in ("fit", "all"):
        frames, x, y = read_pairs()
        model = fit(x, y)
        MODEL.write_text(dumps(model), encoding="utf-8")
        print(f"{MODEL}: {model['version']}")
        report(frames, x, y, model)


if __name__ == "__main__":
    main()
