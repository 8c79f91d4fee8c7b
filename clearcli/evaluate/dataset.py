"""Scores of a labelled dataset: each frame segmented (or its predicted labels read) and
scored against its own ground-truth `label` field (mOSD convention), then summarised,
overall and per group of frames.

Per frame (`evaluate_frame`, run by a batch worker): the fields of
`segmentation.SegmentationScore` plus ``time_s`` (segmentation wall time; 0 with
``--pred``) and ``group``. Groups come from a TOML file mapping group names to
file-name patterns (``[groups] name = ["learn1[0-6].pcd", ...]``); the one for mOSD's
categories ships as `clearcli/data/mosd_groups.toml` (``--groups mosd``).
"""

from __future__ import annotations

import csv
import fnmatch
import io
import tomllib
from collections.abc import Mapping, Sequence
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from clearcli.errors import InputError
from clearcli.evaluate.osd import OSD_KEYS  # the OSD/OCID metrics; Boundary over organized frames only
from clearcli.files import atomic_output, atomic_path

MOSD_GROUPS = "mosd"


def load_groups(spec: str | None) -> dict[str, list[str]]:
    """Group name -> file-name patterns, from a TOML file or "mosd" (the shipped one)."""
    if not spec:
        return {}
    if spec == MOSD_GROUPS:
        text = (resources.files("clearcli") / "data" / "mosd_groups.toml").read_text(encoding="utf-8")
        where = "clearcli/data/mosd_groups.toml"
    else:
        try:
            text = Path(spec).read_text(encoding="utf-8")
        except OSError as exc:
            raise InputError(f"{spec}: cannot read the groups file ({exc.strerror})") from None
        where = spec
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{where}: not valid TOML ({exc})") from None
    groups = data.get("groups")
    if not isinstance(groups, dict) or not all(
        isinstance(v, list) and all(isinstance(p, str) for p in v) for v in groups.values()
    ):
        raise InputError(f'{where}: expected a [groups] table of name = ["pattern", ...]')
    return {str(k): list(v) for k, v in groups.items()}


def group_of(source: str, groups: Mapping[str, Sequence[str]]) -> str | None:
    name = Path(source).name
    for group, patterns in groups.items():
        if any(fnmatch.fnmatchcase(name, p) for p in patterns):
            return group
    return None


def _labels(frame: Any, path: str, what: str) -> np.ndarray:
    if "label" not in frame.fields:
        raise InputError(f"{path}: the {what} has no `label` field (fields: {', '.join(frame.fields) or 'none'})")
    return np.asarray(frame.fields["label"]).ravel()


SUMMARY_KEYS = ("precision", "recall", "f1", "mean_best_iou")


def summarise(docs: Sequence[Mapping[str, Any]], groups: Mapping[str, Sequence[str]]) -> dict[str, Any]:
    """Means over the scored frames, overall and per group (in the groups file's order)."""

    def means(rows: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
        if not rows:
            return {"frames": 0}
        out: dict[str, Any] = {"frames": len(rows)}
        for k in SUMMARY_KEYS:
            out[f"mean_{k}" if not k.startswith("mean") else k] = round(float(np.mean([r[k] for r in rows])), 4)
        for k in OSD_KEYS:
            values = [r[k] for r in rows if r.get(k) is not None]
            out[f"mean_{k}"] = round(float(np.mean(values)), 4) if values else None
        exact = [r["exact"] for r in rows if "exact" in r]
        if exact:  # objects exactly right, and what went wrong with the others (clearcli/evaluate/exact.py)
            out["exact"] = {
                k: int(sum(e[k] for e in exact)) for k in ("objects", "right", "merged", "split", "missed", "spurious")
            }
        out["over_segmented"] = int(sum(r["over_segmented"] for r in rows))
        out["under_segmented"] = int(sum(r["under_segmented"] for r in rows))
        times = [r["time_s"] for r in rows]
        out["median_time_s"] = round(float(np.median(times)), 4)
        return out

    summary = {"all": means(docs)}
    if groups:
        summary["groups"] = {g: means([d for d in docs if d.get("group") == g]) for g in groups}
        ungrouped = [d for d in docs if d.get("group") is None]
        if ungrouped:
            summary["groups"]["(no group)"] = means(ungrouped)
    return summary


def write_csv(path: Path, docs: Sequence[Mapping[str, Any]]) -> None:
    cols = [
        "source",
        "group",
        "n_true",
        "n_pred",
        "true_positives",
        "precision",
        "recall",
        "f1",
        "mean_best_iou",
        "over_segmented",
        "under_segmented",
        *OSD_KEYS,
        "time_s",
    ]
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(cols)
    for d in docs:
        w.writerow([d.get(c, "") for c in cols])
    with atomic_output(path, "w") as handle:
        handle.write(buf.getvalue())


def write_png(path: Path, docs: Sequence[Mapping[str, Any]]) -> None:
    """Per-frame F1 as bars, coloured by group."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [Path(d["source"]).stem for d in docs]
    groups = [d.get("group") or "" for d in docs]
    palette = plt.get_cmap("tab10")
    order = list(dict.fromkeys(groups))
    colours = [palette(order.index(g) % 10) for g in groups]
    fig, ax = plt.subplots(figsize=(max(6.0, 0.18 * len(docs) + 2), 4), dpi=110)
    ax.bar(range(len(docs)), [d["f1"] for d in docs], color=colours)
    ax.set_xticks(range(len(docs)), names, rotation=90, fontsize=6)
    ax.set_ylim(0, 1.05)
    ax.set_ylabel("object F1 at IoU >= 0.5")
    mean = float(np.mean([d["f1"] for d in docs])) if docs else 0.0
    ax.set_title(f"{len(docs)} frames, mean F1 {mean:.3f}", fontsize=10)
    from matplotlib.patches import Patch

    handles = [Patch(color=palette(k % 10), label=g) for k, g in enumerate(order) if g]
    if handles:
        ax.legend(handles=handles, fontsize=7, loc="lower right")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp)
    plt.close(fig)
