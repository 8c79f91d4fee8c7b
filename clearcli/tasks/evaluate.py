"""`evaluate dataset`, per frame: a labelled frame segmented (or its labels read from a
folder of predictions) and scored against its own labels (``run``). Also `evaluate
segmentation`'s one comparison of two files (``score_files``), and the dataset-level
helpers the command uses (re-exported from clearcli/evaluate/dataset.py)."""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from clearcli import pipeline
from clearcli.errors import InputError
from clearcli.evaluate.dataset import group_of
from clearcli.evaluate.dataset import load_groups as load_groups  # the command's
from clearcli.evaluate.dataset import summarise as summarise
from clearcli.evaluate.dataset import write_csv as write_csv
from clearcli.evaluate.dataset import write_png as write_png
from clearcli.evaluate.exact import exact_report
from clearcli.evaluate.osd import osd_metrics
from clearcli.evaluate.segmentation import score
from clearcli.io.frames import Frame
from clearcli.io.pcd import write_pcd
from clearcli.settings import Settings
from clearcli.tasks.base import NO_OUTPUTS, OUTPUT_FILES, Outcome, Outputs, Source

SCHEMA, VERSION = "evaluate.frame", 1
OUTPUTS = ("labels",)


@dataclass(frozen=True)
class Request:
    settings: Settings
    pred: Path | None = None  # --pred DIR: labels written by an earlier `segment --out-dir`
    groups: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    outputs: Outputs = NO_OUTPUTS


def _labels(frame: Frame, path: str | Path, what: str) -> np.ndarray[Any, Any]:
    if "label" not in frame.fields:
        raise InputError(f"{path}: the {what} has no `label` field (fields: {', '.join(frame.fields) or 'none'})")
    return np.asarray(frame.fields["label"]).ravel()


def run(request: Request, source: Source) -> Outcome:
    name = source.name or Path(source.path).stem
    frame = pipeline.read(source.path, source.topic, source.index, request.settings, source.color)
    truth = _labels(frame, source.path, "ground truth")
    elapsed = 0.0
    if request.pred is not None:
        pred_path = Path(request.pred) / OUTPUT_FILES["labels"].format(name=name)
        if not pred_path.is_file():
            raise InputError(f"{pred_path}: no predicted labels for {source.path} (named as --out-dir names them)")
        pred = _labels(pipeline.read(pred_path), pred_path, "prediction")
    else:
        t0 = time.perf_counter()
        seg = pipeline.segmented(frame, request.settings)
        elapsed = time.perf_counter() - t0
        pred = seg.labels()
        out = request.outputs.get("labels")
        if out is not None:
            write_pcd(out, frame, pred)
    if pred.shape != truth.shape:
        raise InputError(f"{source.path}: {pred.size} predicted labels for {truth.size} points; not the same frame")
    result = score(pred, truth)
    payload = {
        "source": str(source.path),
        "name": name,
        "group": group_of(str(source.path), request.groups),
        **{k: v for k, v in result.as_dict().items() if k not in ("matched_iou", "true_ids", "pred_ids")},
        **osd_metrics(pred, truth, frame.shape).as_dict(),
        "exact": exact_report(pred, truth).as_dict(),
        "time_s": round(elapsed, 4),
    }
    return Outcome(SCHEMA, VERSION, payload, 0, request.outputs.all())


def score_files(pred: Path, truth: Path) -> dict[str, Any]:
    """`evaluate segmentation`: a labels PCD scored against a labelled frame (payload of
    schema ``clear.evaluate.segmentation``)."""
    p = _labels(pipeline.read(pred), pred, "prediction")
    truth_frame = pipeline.read(truth)
    t = _labels(truth_frame, truth, "ground truth")
    if p.shape != t.shape:
        raise InputError(f"{pred}: {p.size} points but {truth} has {t.size}; both must be the same frame")
    return {
        "pred": str(pred),
        "truth": str(truth),
        **score(p, t).as_dict(),
        **osd_metrics(p, t, truth_frame.shape).as_dict(),
    }
