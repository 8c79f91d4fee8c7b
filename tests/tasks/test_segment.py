"""Tests of clearcli/tasks/segment.py: `segment` through the task layer.

The expected objects come from the fixtures' own per-point ground truth (`label`: 1
table, 10 (k + 1) object k; fixtures/README.md), read here with pypcd4, and from the
table pose and box sizes fixtures/README.md states."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from helpers import FIXTURES

from clearcli.errors import ClearError, InputError, SceneError
from clearcli.settings import Settings
from clearcli.tasks import segment as task
from clearcli.tasks.base import Outputs, Source

# fixtures/README.md, "Files": objects per frame
OBJECTS = {"isolated_box": 1, "two_touching_boxes": 2, "box_on_box": 2, "clutter10": 10}
# fixtures/README.md: the table frame's z axis in the camera frame (third column of
# T_camera_table) and the table centre's distance along the optical axis
TABLE_UP = np.array([0.0, -0.743145, -0.669131])
TABLE_CENTRE = np.array([0.0, 0.0, 0.926575])


def _labels(path: Path) -> np.ndarray:
    from pypcd4 import PointCloud

    return PointCloud.from_path(path).numpy(("label",)).ravel().astype(np.int64)


def _run_with_labels(name: str, tmp_path: Path) -> tuple[list[dict], np.ndarray, np.ndarray]:
    """The payload's objects, the labels written by the task and the fixture's own."""
    frame = FIXTURES / f"{name}.pcd"
    truth = _labels(frame)
    assert len([k for k in np.unique(truth) if k >= 10]) == OBJECTS[name]  # the README and the file agree
    out = tmp_path / "labels.pcd"
    outcome = task.run(task.Request(Settings(), Outputs.of(labels=out)), Source(frame))
    assert outcome.exit_code == 0 and outcome.written == (out,)
    objects = list(outcome.payload["objects"])
    pred = _labels(out)
    assert pred.shape == truth.shape  # the same organized frame, point for point
    assert sorted(int(k) for k in np.unique(pred) if k >= 10) == sorted(o["label"] for o in objects)
    for o in objects:
        assert o["n_points"] == int((pred == o["label"]).sum())
    return objects, pred, truth


def _best_iou(truth: np.ndarray, pred: np.ndarray) -> dict[int, tuple[int, float]]:
    """Per true object: the segment holding most of its points and their IoU."""
    found = {}
    for k in (int(k) for k in np.unique(truth) if k >= 10):
        t = truth == k
        candidates = [int(p) for p in np.unique(pred[t]) if p >= 10]
        if not candidates:
            found[k] = (0, 0.0)
            continue
        best = max(candidates, key=lambda p: int((pred[t] == p).sum()))
        found[k] = (best, float((t & (pred == best)).sum() / (t | (pred == best)).sum()))
    return found


@pytest.mark.parametrize("name", ["isolated_box", "two_touching_boxes", "box_on_box"])
def test_each_fixture_gives_its_objects_each_matching_one_true_object(name: str, tmp_path: Path) -> None:
    objects, pred, truth = _run_with_labels(name, tmp_path)
    assert len(objects) == OBJECTS[name]
    best = _best_iou(truth, pred)
    assert all(iou > 0.7 for _, iou in best.values()), best
    assert len({segment for segment, _ in best.values()}) == OBJECTS[name]  # one segment each


def test_clutter10_gives_ten_objects(tmp_path: Path) -> None:
    objects, pred, truth = _run_with_labels("clutter10", tmp_path)
    assert len(objects) == 10
    best = _best_iou(truth, pred)
    # every box matches a segment of its own, the touching pairs 20/80 and 50/70 included
    assert all(iou > 0.7 for _, iou in best.values()), best
    assert len({segment for segment, _ in best.values()}) == 10, best


def test_clutter10_touching_pair_1_7_is_told_apart(tmp_path: Path) -> None:
    _, pred, truth = _run_with_labels("clutter10", tmp_path)
    best = _best_iou(truth, pred)
    assert best[20][1] > 0.7 and best[80][1] > 0.7 and best[20][0] != best[80][0], best


def test_the_table_found_is_the_one_the_fixture_was_rendered_with() -> None:
    payload = task.run(task.Request(Settings()), Source(FIXTURES / "isolated_box.pcd")).payload
    normal = np.asarray(payload["table"]["normal"])
    assert np.degrees(np.arccos(min(1.0, float(normal @ TABLE_UP)))) < 1.0
    # the table centre lies on the plane n.p + offset = 0
    assert abs(float(normal @ TABLE_CENTRE) + payload["table"]["offset"]) < 0.005
    assert payload["n_points"] == 640 * 480
    assert payload["table"]["n_points"] > 0.8 * int((_labels(FIXTURES / "isolated_box.pcd") == 1).sum())


def test_the_isolated_box_measures_as_built() -> None:
    (box,) = task.run(task.Request(Settings()), Source(FIXTURES / "isolated_box.pcd")).payload["objects"]
    # fixtures/README.md: box 5.00 x 4.00 x 8.00 cm, standing on the table
    assert sorted(box["obb"]["extents"]) == pytest.approx([0.04, 0.05, 0.08], abs=0.006)
    axes = np.asarray(box["obb"]["axes"])
    assert max(abs(float(a @ TABLE_UP)) for a in axes) > 0.99  # one box axis is the table's normal
    # the box's centre is 4 cm above the table, within the visible surface's bias
    centre = np.asarray(box["obb"]["center"])
    height = float(centre @ TABLE_UP) + float(-(TABLE_UP @ TABLE_CENTRE))
    assert 0.025 < height < 0.055


def test_outcome_schema_and_a_json_payload(tmp_path: Path) -> None:
    png = tmp_path / "seg.png"
    outcome = task.run(task.Request(Settings(), Outputs.of(png=png)), Source(FIXTURES / "two_touching_boxes.pcd"))
    assert (outcome.schema, outcome.version) == (task.SCHEMA, task.VERSION) == ("segmentation", 3)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and outcome.written == (png,)
    assert json.loads(json.dumps(outcome.payload, allow_nan=False))["source"].endswith("two_touching_boxes.pcd")
    assert task.OUTPUTS == ("labels", "png")


def test_a_log_frame_is_read_by_its_index() -> None:
    # session.mcap frame 3: object 6 and the cylinder 2 picked, 8 left (fixtures/README.md)
    outcome = task.run(task.Request(Settings()), Source(FIXTURES / "session.mcap", index=3))
    assert len(outcome.payload["objects"]) == 8
    assert outcome.payload["stamp_s"] == pytest.approx(1_763_683_200.0 + 3 * 0.5)
    assert outcome.payload["frame_id"] == "camera_rgb_optical_frame"


def test_bad_inputs_are_clear_errors(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="file not found"):
        task.run(task.Request(Settings()), Source(tmp_path / "missing.pcd"))
    text = tmp_path / "notes.pcd"
    text.write_text("this is no point cloud\n")
    with pytest.raises(InputError):
        task.run(task.Request(Settings()), Source(text))
    with pytest.raises(InputError, match="--frame 9"):
        task.run(task.Request(Settings()), Source(FIXTURES / "session.mcap", index=9))
    with pytest.raises(InputError, match="no topic"):
        task.run(task.Request(Settings()), Source(FIXTURES / "session.mcap", topic="/nope"))


def test_a_frame_with_no_table_is_a_scene_error(tmp_path: Path) -> None:
    # a few points on a line in mid air: no plane, let alone a table
    pts = "\n".join(f"{0.01 * i:.3f} 0.0 1.0" for i in range(50))
    pcd = tmp_path / "line.pcd"
    pcd.write_text(
        "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 50\nHEIGHT 1\n"
        "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 50\nDATA ascii\n" + pts + "\n"
    )
    with pytest.raises(ClearError) as info:
        task.run(task.Request(Settings()), Source(pcd))
    assert isinstance(info.value, SceneError) and info.value.exit_code == 4
