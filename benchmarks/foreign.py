"""Segmentation on frames of other labs (not mOSD), against labels we wrote ourselves.

    .venv/bin/python benchmarks/foreign.py                 # report part: per frame and totals
    .venv/bin/python benchmarks/foreign.py --part choose   # the part settings may be chosen on
    .venv/bin/python benchmarks/foreign.py --part all
    .venv/bin/python benchmarks/foreign.py --part choose --set segment.color_importance=0.5
    .venv/bin/python benchmarks/foreign.py --show uois_image_0003 [--out picture.png]
    .venv/bin/python benchmarks/foreign.py --grid uois_image_0003   # the colour image with a pixel grid, to label
                                                    # (any frame under ../shared/data/scenes/*/ by name)

Frames: uois_realsense (9), PCL's two tabletop frames, gqcnn (7: a YuMi cell's foam board,
two PhoXi bins whose floor is the support) and cleargrasp_d435 (4, 1280x720, transparent
objects); each source's frames sorted by name alternate choose, report, choose... (the
uois and PCL frames were split before that rule, see their files). Then PCL's
grabber_sequence (3 consecutive Kinect frames of one floor scene, pcl_grabber_0..2: all
report, near-duplicates split across the parts would leak) and the "industrial" table
cloud (unorganized, z up, industrial_table: choose, that lab's only frame).

Labels (benchmarks/foreign/<frame>.toml, written by hand for this project, one file per
frame): the frame's path under ../shared/data, its part ("choose" or "report"), and per
object a name and a polygon in pixel coordinates of the organized frame ([column, row]
vertices, as read off `--grid`). An object's points are the finite pixels inside its
polygon that stand more than 8 mm above the support plane (a RANSAC plane fitted here to
the finite points outside every polygon, within 2 m), so a polygon drawn a little wide
takes no table; where polygons overlap (a can in a bowl) the later object takes the
pixels; `above_m` lowers the 8 mm for an object lying flat (a marker, 3 mm: the
polygon must then be tight, the table's noise is a few millimetres); `fill = true` marks a container (a bowl), whose floor may stand less than 8 mm
above the table: it takes what lies above the plane within its silhouette's convex hull.
`--show` draws the resulting masks over the colour image to check them.

An unorganized cloud already in a table frame, z up, has `frame_kind = "xy"` in its file:
its polygons are in metres in the cloud's x-y plane, the support plane's normal is taken
upwards (+z), the rest as above (`_load_xy`); `--grid`, `--show` and `--result` draw it from
above.

Per frame it prints the objects exactly right, merged, split and missed, the spurious
segments (clearcli/evaluate/exact.py), object F1 at IoU >= 0.5 and the OSD/OCID Overlap
and Boundary F (clearcli/evaluate/osd.py); then the totals of the part. The "choose"
part is where settings may be tuned; "report" is the part the figures are given on, never
tuned on.
"""

from __future__ import annotations

import argparse
import sys
import tomllib
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
DATA = REPO.parent / "shared" / "data"
LABELS = Path(__file__).resolve().parent / "foreign"
ABOVE_PLANE_M = 0.008


def _plane(points: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, float]:
    """(unit normal pointing to the camera side, offset) of the dominant plane: RANSAC,
    then a least-squares refit on its inliers (1 cm)."""
    best, best_n = None, -1
    for _ in range(300):
        a, b, c = points[rng.choice(points.shape[0], 3, replace=False)]
        n = np.cross(b - a, c - a)
        norm = np.linalg.norm(n)
        if norm < 1e-9:
            continue
        n /= norm
        inl = np.abs((points - a) @ n) < 0.01
        if inl.sum() > best_n:
            best, best_n = inl, int(inl.sum())
    assert best is not None
    p = points[best]
    centre = p.mean(axis=0)
    n = np.linalg.svd(p - centre, full_matrices=False)[2][2]
    if n @ -centre < 0:  # towards the camera (the origin)
        n = -n
    return n, float(-n @ centre)


def load(name: str):  # -> (Frame, labels (N,) int64, spec dict)
    from matplotlib.path import Path as Polygon

    from clearcli.io.read import read_frame

    spec = tomllib.loads((LABELS / f"{name}.toml").read_text(encoding="utf-8"))
    frame = read_frame(DATA / spec["source"])
    if spec.get("frame_kind", "pixels") == "xy":
        return _load_xy(frame, spec)
    h, w = frame.shape
    v, u = np.mgrid[0:h, 0:w]
    pixels = np.column_stack([u.ravel(), v.ravel()]).astype(np.float64)
    finite = np.isfinite(frame.points).all(axis=1)
    inside = np.zeros((len(spec["object"]), h * w), dtype=bool)
    for k, obj in enumerate(spec["object"]):
        inside[k] = Polygon(np.asarray(obj["polygon"], dtype=np.float64)).contains_points(pixels)
    outside = finite & ~inside.any(axis=0) & (np.linalg.norm(np.nan_to_num(frame.points), axis=1) < 2.0)
    n, d = _plane(frame.points[outside].astype(np.float64), np.random.default_rng(0))
    height = np.where(finite, np.nan_to_num(frame.points.astype(np.float64)) @ n + d, -np.inf)
    return frame, _labels(spec, inside, finite, height, pixels), spec


def _labels(spec: dict, inside: np.ndarray, finite: np.ndarray, height: np.ndarray, where: np.ndarray) -> np.ndarray:
    """(N,) labels: the table (within 1 cm of the plane) and each object, its points
    ``inside`` its polygon, finite, and above the plane by its ``above_m``; later objects
    take overlapping points. ``where`` (N, 2): the coordinates the polygons are in
    (pixels, or metres in x-y), for a container's convex hull (``fill``)."""
    from clearcli.io.frames import LABEL_TABLE, object_label

    labels = np.zeros(finite.shape[0], dtype=np.int64)
    labels[finite & (np.abs(height) < 0.01)] = LABEL_TABLE
    for k, obj in enumerate(spec["object"]):
        mask = inside[k] & finite & (height > float(obj.get("above_m", ABOVE_PLANE_M)))
        if obj.get("fill") and mask.any():
            # a container: its floor may stand less than 8 mm above the table; take what
            # lies above the plane within the silhouette's convex hull
            from scipy.spatial import Delaunay

            hull = Delaunay(where[mask])
            mask = inside[k] & finite & (height > 0.0) & (hull.find_simplex(where) >= 0)
        labels[mask] = object_label(k)
    return labels


def _load_xy(frame, spec: dict):  # -> (Frame, labels (N,) int64, spec dict)
    """Labels of an unorganized cloud already in a table frame, z up (`frame_kind = "xy"`):
    each polygon is in metres in the cloud's x-y plane, and an object's points are the
    finite points inside it standing more than `above_m` (8 mm) above the support plane (a
    RANSAC plane fitted to the finite points outside every polygon, its normal taken
    upwards, +z); overlaps and `fill` (the convex hull in x-y) as for pixel labels."""
    from matplotlib.path import Path as Polygon

    finite = np.isfinite(frame.points).all(axis=1)
    points = np.nan_to_num(frame.points.astype(np.float64))
    xy = points[:, :2]
    inside = np.zeros((len(spec["object"]), frame.n_points), dtype=bool)
    for k, obj in enumerate(spec["object"]):
        inside[k] = Polygon(np.asarray(obj["polygon"], dtype=np.float64)).contains_points(xy)
    n, d = _plane(points[finite & ~inside.any(axis=0)], np.random.default_rng(0))
    if n[2] < 0:  # _plane turns the normal to the origin; here up is +z
        n, d = -n, -d
    height = np.where(finite, points @ n + d, -np.inf)
    return frame, _labels(spec, inside, finite, height, xy), spec


def names(part: str) -> list[str]:
    out = []
    for p in sorted(LABELS.glob("*.toml")):
        spec = tomllib.loads(p.read_text(encoding="utf-8"))
        if part == "all" or spec.get("part") == part:
            out.append(p.stem)
    return out


def show(name: str, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from clearcli.render.camera import outlined

    frame, labels, spec = load(name)
    palette = matplotlib.colormaps["tab20"]
    objs = spec["object"]
    segments = [np.nonzero(labels == 10 * (k + 1))[0] for k in range(len(objs))]
    if spec.get("frame_kind") == "xy":
        texts = [f"{k} {obj['name']}\n{seg.size} pts" for k, (obj, seg) in enumerate(zip(objs, segments))]
        colours = [palette(k % 20) for k in range(len(objs))]
        title = f"{name}: {len(objs)} labelled objects, top down (dashed: polygons; coloured: the points taken)"
        _top_down(frame, spec, segments, colours, texts, title, out)
        return
    image = outlined(frame.colors, frame.shape, segments, [palette(k % 20) for k in range(len(objs))], width_px=2)
    fig, ax = plt.subplots(figsize=_figsize(*frame.shape), dpi=100)
    ax.imshow(image)
    for k, (obj, seg) in enumerate(zip(objs, segments)):
        poly = np.asarray(obj["polygon"] + obj["polygon"][:1], dtype=float)
        ax.plot(poly[:, 0], poly[:, 1], "--", color=palette(k % 20), lw=0.8)
        if seg.size:
            rows, cols = np.divmod(seg, frame.shape[1])
            ax.text(
                cols.mean(),
                rows.mean(),
                f"{k} {obj['name']}\n{seg.size} px",
                fontsize=8,
                color="white",
                ha="center",
                bbox=dict(fc=palette(k % 20), alpha=0.8, ec="none"),
            )
    _pixel_grid(ax, *frame.shape)
    ax.set_title(f"{name}: {len(objs)} labelled objects (dashed: polygons; solid: the points taken)")
    fig.tight_layout()
    fig.savefig(out)
    print(out)


def result(name: str, out: Path) -> None:
    """The segmenter's objects (solid outlines, numbered) and what it excluded (grey,
    lettered) over the colour image, the labels' polygons dashed: to see what goes wrong."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from clearcli import pipeline
    from clearcli.render.camera import outlined
    from clearcli.settings import Settings

    frame, _, spec = load(name)
    seg = pipeline.segmented(frame, Settings())
    palette = matplotlib.colormaps["tab20"]
    segments = [np.asarray(o.indices) for o in seg.objects] + [np.asarray(e.indices) for e in seg.excluded]
    colours = [palette(k % 20) for k in range(len(seg.objects))] + [(0.5, 0.5, 0.5, 1.0)] * len(seg.excluded)
    for k, e in enumerate(seg.excluded):
        print(chr(ord("A") + k), e.reason)
    if spec.get("frame_kind") == "xy":
        texts = [str(k) for k in range(len(seg.objects))] + [chr(ord("A") + k) for k in range(len(seg.excluded))]
        title = (
            f"{name}: {len(seg.objects)} objects, {len(seg.excluded)} excluded (grey), top down (dashed: the labels)"
        )
        _top_down(frame, spec, segments, colours, texts, title, out)
        return
    image = outlined(frame.colors, frame.shape, segments, colours, width_px=2)
    fig, ax = plt.subplots(figsize=_figsize(*frame.shape), dpi=100)
    ax.imshow(image)
    for obj in spec["object"]:
        poly = np.asarray(obj["polygon"] + obj["polygon"][:1], dtype=float)
        ax.plot(poly[:, 0], poly[:, 1], "--", color="white", lw=0.6)
    for k, idx in enumerate(segments):
        rows, cols = np.divmod(idx, frame.shape[1])
        text = str(k) if k < len(seg.objects) else chr(ord("A") + k - len(seg.objects))
        ax.text(
            cols.mean(), rows.mean(), text, fontsize=9, color="white", bbox=dict(fc=colours[k], alpha=0.8, ec="none")
        )
    _pixel_grid(ax, *frame.shape)
    ax.set_title(f"{name}: {len(seg.objects)} objects, {len(seg.excluded)} excluded (dashed: the labels)")
    fig.tight_layout()
    fig.savefig(out)
    print(out)


def _top_down(frame, spec: dict, segments, colours, texts, title: str, out: Path) -> None:
    """An unorganized z-up cloud (`frame_kind = "xy"`) seen from above: every point in its
    own colour, the given segments' points over it in theirs, the labels' x-y polygons
    dashed, a 5 cm grid to read polygons off."""
    import matplotlib.pyplot as plt

    finite = np.isfinite(frame.points).all(axis=1)
    p = frame.points[finite]
    fig, ax = plt.subplots(figsize=(12.8, 9.6), dpi=100)
    # in the cloud's own colours, grey without any
    shade = frame.colors[finite] / 255.0 if frame.colors is not None else "0.6"
    ax.scatter(p[:, 0], p[:, 1], c=shade, s=3, linewidths=0)
    for idx, colour, text in zip(segments, colours, texts):
        if idx.size:
            q = frame.points[idx]
            ax.scatter(q[:, 0], q[:, 1], color=colour, s=5, linewidths=0)
            ax.text(
                *q[:, :2].mean(axis=0),
                text,
                fontsize=8,
                color="white",
                ha="center",
                bbox=dict(fc=colour, alpha=0.8, ec="none"),
            )
    for obj in spec["object"]:
        poly = np.asarray(obj["polygon"] + obj["polygon"][:1], dtype=float)
        ax.plot(poly[:, 0], poly[:, 1], "--", color="black", lw=0.8)
    ax.set_aspect("equal")
    lo, hi = np.floor(p[:, :2].min(axis=0) / 0.05) * 0.05, np.ceil(p[:, :2].max(axis=0) / 0.05) * 0.05
    ax.set_xticks(np.arange(lo[0], hi[0] + 0.01, 0.05))
    ax.set_yticks(np.arange(lo[1], hi[1] + 0.01, 0.05))
    ax.tick_params(labelsize=7)
    ax.tick_params(axis="x", rotation=90)
    ax.grid(True, lw=0.3)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(out)
    print(out)


def _figsize(h: int, w: int) -> tuple[float, float]:
    """1280 pixels wide, the frame's aspect: 12.8 x 9.6 in for 640x480 as before, and a
    1280x720 frame (cleargrasp_d435) at its own pixel size, its grid lines readable."""
    return 12.8, 12.8 * h / w


def _unlabelled(name: str) -> Path:
    """A frame without a label file yet, found by name under ../shared/data/scenes/ (at any
    depth: scenes/pcl/grabber_sequence/frame_....pcd)."""
    found = sorted((DATA / "scenes").rglob(f"{name}.pcd"))
    if not found:
        raise SystemExit(f"no frame {name}.pcd under {DATA / 'scenes'}")
    return found[0]


def _pixel_grid(ax, h: int, w: int) -> None:
    """Lines every 20 pixels, numbers every 40: polygon vertices are read off these."""
    ax.set_xticks(range(0, w + 1, 20), [str(x) if x % 40 == 0 else "" for x in range(0, w + 1, 20)], fontsize=7)
    ax.set_yticks(range(0, h + 1, 20), [str(y) if y % 40 == 0 else "" for y in range(0, h + 1, 20)], fontsize=7)
    ax.grid(True, color="yellow", lw=0.4, alpha=0.6)
    ax.set_xlim(-0.5, w - 0.5)
    ax.set_ylim(h - 0.5, -0.5)


def grid(name: str, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    spec = (
        tomllib.loads((LABELS / f"{name}.toml").read_text(encoding="utf-8"))
        if (LABELS / f"{name}.toml").exists()
        else None
    )
    from clearcli.io.read import read_frame

    frame = read_frame(DATA / spec["source"] if spec else _unlabelled(name))
    if frame.shape is None:  # unorganized (a z-up cloud in a table frame): from above
        _top_down(frame, {"object": []}, [], [], [], f"{name}: top down", out)
        return
    h, w = frame.shape
    fig, ax = plt.subplots(figsize=_figsize(h, w), dpi=100)
    ax.imshow(frame.colors.reshape(h, w, 3))
    _pixel_grid(ax, h, w)
    fig.tight_layout()
    fig.savefig(out)
    print(out)


def report(part: str, sets: list[str] | None = None) -> None:
    from clearcli import pipeline
    from clearcli.evaluate.exact import exact_report
    from clearcli.evaluate.osd import osd_metrics
    from clearcli.evaluate.segmentation import score
    from clearcli.settings import Settings, apply_sets

    settings = apply_sets(Settings(), sets or ())
    totals = dict(objects=0, right=0, merged=0, split=0, missed=0, spurious=0)
    print(
        f"{'frame':34s} {'obj':>4s} {'right':>5s} {'merged':>6s} {'split':>5s} {'missed':>6s} {'spur':>5s}"
        f" {'F1':>6s} {'Ov F':>6s} {'Bd F':>6s}"
    )
    for name in names(part):
        frame, truth, spec = load(name)
        pred = pipeline.segmented(frame, settings).labels()
        r = exact_report(pred, truth)
        s = score(pred, truth)
        o = osd_metrics(pred, truth, frame.shape)
        for k in totals:
            totals[k] += getattr(r, "n_objects" if k == "objects" else k)
        wrong = ", ".join(f"{obj['name']}: {v}" for obj, v in zip(spec["object"], r.verdicts) if v != "right")
        print(
            f"{name:34s} {r.n_objects:4d} {r.right:5d} {r.merged:6d} {r.split:5d} {r.missed:6d} {r.spurious:5d}"
            f" {s.f1:6.3f} {o.overlap_f:6.3f} "
            + (f"{o.boundary_f:6.3f}" if o.boundary_f is not None else f"{'-':>6s}")  # unorganized: no Boundary
            + (f"   [{wrong}]" if wrong else "")
        )
    n = max(totals["objects"], 1)
    print(
        f"{part}: {totals['right']} of {totals['objects']} objects exactly right ({100 * totals['right'] / n:.1f} %); "
        f"merged {totals['merged']}, split {totals['split']}, missed {totals['missed']}, spurious segments {totals['spurious']}"
    )


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--part", choices=("choose", "report", "all"), default="report")
    parser.add_argument("--show", metavar="FRAME")
    parser.add_argument("--grid", metavar="FRAME")
    parser.add_argument("--result", metavar="FRAME", help="draw the segmenter's objects and exclusions")
    parser.add_argument("--out", type=Path)
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="SECTION.KEY=VALUE",
        help="a setting to try (as clear's --set); choose on --part choose only",
    )
    args = parser.parse_args()
    if args.show:
        show(args.show, args.out or Path(f"/tmp/{args.show}_labels.png"))
    elif args.result:
        result(args.result, args.out or Path(f"/tmp/{args.result}_result.png"))
    elif args.grid:
        grid(args.grid, args.out or Path(f"/tmp/{args.grid}_grid.png"))
    else:
        report(args.part, args.set)


if __name__ == "__main__":
    main()
