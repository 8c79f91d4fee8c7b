"""Tests of clearcli/tasks/evaluate.py: a labelled frame segmented (or its labels read
from a folder of predictions) and scored against its own labels.

The frames are real mOSD frames (../shared/data/mosd; label 0 invalid, 1..9 table,
object = label // 10). Predictions are made here from the ground truth itself with
pypcd4 (the truth, two objects merged, one object split), so that every score can be
worked out by hand from the point counts."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from helpers import FIXTURES, shared_path

from clearcli.errors import ClearError, InputError
from clearcli.evaluate.dataset import load_groups
from clearcli.settings import Settings
from clearcli.tasks import evaluate as task
from clearcli.tasks.base import Outputs, Source

SCORES = ("precision", "recall", "f1", "mean_best_iou")


def _cloud(path: Path):  # type: ignore[no-untyped-def]
    from pypcd4 import PointCloud

    return PointCloud.from_path(path)


def _objects(labels: np.ndarray) -> dict[int, int]:
    """True object id -> its point count (mOSD: id = label // 10, labels >= 10)."""
    ids, counts = np.unique(labels[labels >= 10] // 10, return_counts=True)
    return {int(i): int(c) for i, c in zip(ids, counts)}


def _write_pred(folder: Path, name: str, truth: Path, labels: np.ndarray) -> None:
    """A labels PCD named as `segment --out-dir` names it: the truth's points, ``labels``."""
    from pypcd4 import PointCloud

    cloud = _cloud(truth)
    data = cloud.pc_data.copy()
    data["label"] = labels.astype(data["label"].dtype)
    folder.mkdir(exist_ok=True)
    PointCloud(cloud.metadata, data).save(folder / f"{name}.labels.pcd")


def _scored(frame: Path, pred: Path | None = None, groups: dict | None = None) -> dict:
    outcome = task.run(task.Request(Settings(), pred=pred, groups=groups or {}), Source(frame))
    assert (outcome.schema, outcome.version, outcome.exit_code) == ("evaluate.frame", 1, 0)
    return dict(outcome.payload)


def test_a_segmented_mosd_frame_is_scored_and_its_labels_score_the_same_read_back(tmp_path: Path) -> None:
    frame = shared_path("mosd/learn/learn0.pcd")
    truth = _objects(_cloud(frame).numpy(("label",)).ravel().astype(np.int64))
    labels = tmp_path / "preds" / "learn0.labels.pcd"
    labels.parent.mkdir()
    outcome = task.run(
        task.Request(Settings(), groups=load_groups("mosd"), outputs=Outputs.of(labels=labels)), Source(frame)
    )
    got = dict(outcome.payload)
    assert outcome.written == (labels,) and labels.is_file()
    assert got["name"] == "learn0" and got["group"] == "boxes"  # clearcli/data/mosd_groups.toml
    assert got["n_true"] == len(truth) == 2
    tp, n_pred = got["true_positives"], got["n_pred"]
    assert got["precision"] == pytest.approx(tp / n_pred)
    assert got["recall"] == pytest.approx(tp / got["n_true"])
    p, r = got["precision"], got["recall"]
    assert got["f1"] == pytest.approx(0.0 if tp == 0 else 2 * p * r / (p + r))
    assert all(0.0 <= got[k] <= 1.0 for k in (*SCORES, "overlap_f", "boundary_f", "objects_f75"))
    assert got["f1"] >= 0.5  # two boxes apart on a table: the segmenter finds them
    assert got["exact"]["objects"] == got["n_true"] and len(got["exact"]["verdicts"]) == got["n_true"]
    assert got["time_s"] > 0
    # the labels it wrote, read back as predictions, score the same (and take no time)
    again = _scored(frame, pred=labels.parent)
    for key in (*SCORES, "n_pred", "true_positives", "overlap_f", "boundary_f", "exact"):
        assert again[key] == got[key], key
    assert again["time_s"] == 0.0


def test_the_truth_as_prediction_scores_perfectly(tmp_path: Path) -> None:
    frame = shared_path("mosd/learn/learn33.pcd")  # 5 objects, two of them labelled in parts
    labels = _cloud(frame).numpy(("label",)).ravel().astype(np.int64)
    assert len(_objects(labels)) == 5 and len(set(labels[labels >= 10].tolist())) > 5
    _write_pred(tmp_path / "preds", "learn33", frame, labels)
    got = _scored(frame, pred=tmp_path / "preds")
    assert (got["n_true"], got["n_pred"], got["true_positives"]) == (5, 5, 5)
    assert [got[k] for k in SCORES] == [1.0, 1.0, 1.0, 1.0]
    assert (got["over_segmented"], got["under_segmented"]) == (0, 0)
    assert got["overlap_f"] == pytest.approx(1.0) and got["boundary_f"] == pytest.approx(1.0)
    assert got["exact"]["right"] == 5 and got["exact"]["verdicts"] == ["right"] * 5


def test_two_objects_merged_score_as_worked_out_by_hand(tmp_path: Path) -> None:
    frame = shared_path("mosd/learn/learn33.pcd")
    labels = _cloud(frame).numpy(("label",)).ravel().astype(np.int64)
    sizes = _objects(labels)
    a, b = 5, 6
    merged = labels.copy()
    merged[(labels // 10 == b) & (labels >= 10)] = 10 * a
    _write_pred(tmp_path / "preds", "learn33", frame, merged)
    got = _scored(frame, pred=tmp_path / "preds")
    n = len(sizes)
    # the merged object matches the larger of the two (IoU = larger / both >= 0.5), the
    # other true object is missed; every other object is predicted exactly
    assert (got["n_true"], got["n_pred"], got["true_positives"]) == (n, n - 1, n - 1)
    assert got["precision"] == 1.0
    assert got["recall"] == pytest.approx((n - 1) / n)
    assert got["f1"] == pytest.approx(2 * (n - 1) / (2 * n - 1))
    both = sizes[a] + sizes[b]
    assert got["mean_best_iou"] == pytest.approx((n - 2 + sizes[a] / both + sizes[b] / both) / n)
    assert (got["over_segmented"], got["under_segmented"]) == (0, 1)


def test_one_object_split_scores_as_worked_out_by_hand(tmp_path: Path) -> None:
    frame = shared_path("mosd/learn/learn33.pcd")
    labels = _cloud(frame).numpy(("label",)).ravel().astype(np.int64)
    sizes = _objects(labels)
    split = labels.copy()
    points = np.flatnonzero((labels >= 10) & (labels // 10 == 2))
    cut = int(0.7 * points.size)
    split[points[cut:]] = 90  # the last 30 % of object 2's points: a new object 9
    _write_pred(tmp_path / "preds", "learn33", frame, split)
    got = _scored(frame, pred=tmp_path / "preds")
    n = len(sizes)
    assert (got["n_true"], got["n_pred"], got["true_positives"]) == (n, n + 1, n)
    assert got["precision"] == pytest.approx(n / (n + 1)) and got["recall"] == 1.0
    assert got["mean_best_iou"] == pytest.approx((n - 1 + cut / sizes[2]) / n)
    assert (got["over_segmented"], got["under_segmented"]) == (1, 0)
    assert math.isclose(got["f1"], 2 * n / (2 * n + 1))


def test_bad_frames_and_predictions_are_input_errors(tmp_path: Path) -> None:
    from pypcd4 import PointCloud

    frame = shared_path("mosd/learn/learn0.pcd")
    # no predictions where --pred says
    with pytest.raises(InputError, match="no predicted labels"):
        task.run(task.Request(Settings(), pred=tmp_path), Source(frame))
    # a prediction of another size: 100 points labelled as one object
    folder = tmp_path / "other"
    folder.mkdir()
    points = np.column_stack([np.linspace(0, 0.1, 100), np.zeros(100), np.ones(100), np.full(100, 20)])
    PointCloud.from_points(points, ("x", "y", "z", "label"), (np.float32, np.float32, np.float32, np.uint32)).save(
        folder / "learn0.labels.pcd"
    )
    with pytest.raises(InputError, match="not the same frame"):
        task.run(task.Request(Settings(), pred=folder), Source(frame))
    # a frame without ground truth
    bare = tmp_path / "bare.pcd"
    PointCloud.from_xyz_points(_cloud(FIXTURES / "isolated_box.pcd").numpy(("x", "y", "z"))).save(bare)
    with pytest.raises(ClearError) as info:
        task.run(task.Request(Settings()), Source(bare))
    assert isinstance(info.value, InputError) and "no `label` field" in str(info.value)
