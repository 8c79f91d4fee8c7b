"""Tests of clearcli/replay/foxglove.py: the annotated log's messages for Foxglove.

An annotated log is made by replaying fixtures/isolated_box.pcd (a PCD input: its frame
goes in as `foxglove.PointCloud` JSON) and read back with the mcap library's reader; the
point cloud is decoded by hand from its base64 record layout and compared with the PCD
read by pypcd4, and every message is validated against the channel's own JSON schema
with the jsonschema library."""

from __future__ import annotations

import base64
import colorsys
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from helpers import FIXTURES

from clearcli.replay import foxglove as fg
from clearcli.settings import Settings

FRAME = FIXTURES / "isolated_box.pcd"
# foxglove.NumericType (Foxglove's message schemas): UINT8 = 1, FLOAT32 = 7
UINT8, FLOAT32 = 1, 7


@pytest.fixture(scope="module")
def annotated(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    from mcap.reader import make_reader

    from clearcli.tasks import replay

    out = tmp_path_factory.mktemp("foxglove") / "annotated.mcap"
    reports: list[Any] = []
    replay.run(replay.Request(Settings(), out=out), FRAME, None, lambda r, n, t: reports.append(r), lambda s: None)
    messages: dict[str, list[tuple[Any, Any, Any]]] = {}
    with open(out, "rb") as fp:
        for schema, channel, message in make_reader(fp).iter_messages(log_time_order=True):
            messages.setdefault(channel.topic, []).append((schema, channel, message))
    return {"messages": messages, "report": reports[0], "path": out}


def _doc(annotated: dict[str, Any], topic: str) -> dict[str, Any]:
    ((_, _, message),) = annotated["messages"][topic]
    return json.loads(message.data)


def test_the_log_holds_one_message_per_channel_each_valid_against_its_schema(annotated: dict[str, Any]) -> None:
    import jsonschema

    messages = annotated["messages"]
    assert set(messages) == {"/clear/points", fg.SCENE_TOPIC, fg.PREDICATES_TOPIC, fg.PLAN_TOPIC}
    written = {
        "/clear/points": (fg.POINTCLOUD_SCHEMA, fg.POINTCLOUD_JSONSCHEMA),
        fg.SCENE_TOPIC: (fg.SCENE_SCHEMA, fg.SCENE_UPDATE_JSONSCHEMA),
        fg.PREDICATES_TOPIC: ("clear.Predicates", fg.PREDICATES_JSONSCHEMA),
        fg.PLAN_TOPIC: ("clear.Plan", fg.PLAN_JSONSCHEMA),
    }
    for topic, (name, schema_doc) in written.items():
        ((schema, channel, message),) = messages[topic]
        assert (schema.name, schema.encoding, channel.message_encoding) == (name, "jsonschema", "json")
        assert json.loads(schema.data) == schema_doc
        jsonschema.validate(json.loads(message.data), schema_doc)  # raises when it does not fit
    # all four at the frame's time (a PCD's stamp: 0)
    assert {m.log_time for stream in messages.values() for _, _, m in stream} == {0}


def test_the_point_cloud_decodes_to_the_frames_finite_points_and_colours(annotated: dict[str, Any]) -> None:
    from pypcd4 import PointCloud

    doc = _doc(annotated, "/clear/points")
    assert doc["frame_id"] == "camera" and doc["timestamp"] == {"sec": 0, "nsec": 0}
    assert doc["pose"] == fg.IDENTITY_POSE
    fields = {f["name"]: (f["offset"], f["type"]) for f in doc["fields"]}
    assert fields == {
        "x": (0, FLOAT32),
        "y": (4, FLOAT32),
        "z": (8, FLOAT32),
        "red": (12, UINT8),
        "green": (13, UINT8),
        "blue": (14, UINT8),
    }
    assert doc["point_stride"] == 16
    raw = base64.b64decode(doc["data"])
    records = np.frombuffer(raw, dtype=np.dtype([("xyz", "<f4", 3), ("rgb", "u1", 3), ("pad", "u1")]))
    cloud = PointCloud.from_path(FRAME)
    xyz = cloud.numpy(("x", "y", "z")).astype(np.float32)
    keep = np.isfinite(xyz).all(axis=1)
    assert len(raw) == 16 * int(keep.sum())
    assert np.array_equal(records["xyz"], xyz[keep])
    packed = cloud.numpy(("rgb",)).astype(np.float32).ravel().view(np.uint32)[keep]  # PCL's packed float
    rgb = np.column_stack([(packed >> 16) & 255, (packed >> 8) & 255, packed & 255]).astype(np.uint8)
    assert np.array_equal(records["rgb"], rgb)


def test_the_scene_has_the_object_and_the_gripper_at_the_planned_grasp(annotated: dict[str, Any]) -> None:
    report = annotated["report"]
    doc = _doc(annotated, fg.SCENE_TOPIC)
    assert doc["deletions"] == [{"timestamp": {"sec": 0, "nsec": 0}, "type": 1, "id": ""}]  # 1: delete all
    entities = {e["id"]: e for e in doc["entities"]}
    (obj,) = report.objects
    assert set(entities) == {f"object/{obj.track_id}", "gripper"}
    box = entities[f"object/{obj.track_id}"]
    assert box["frame_id"] == "camera"
    assert {m["key"]: m["value"] for m in box["metadata"]} == {"id": str(obj.track_id), "name": obj.name}
    (hull,) = box["triangles"]
    assert hull["color"] == fg.id_color(obj.track_id, 0.7)
    indices = hull["indices"]
    assert len(indices) % 3 == 0 and max(indices) < len(hull["points"])
    assert box["texts"][0]["text"] == f"#{obj.track_id} {obj.name}"
    assert len(box["arrows"]) == 4  # a box has four push directions
    # the gripper's boxes around the planned grasp, within a hand's breadth of the object
    gripper = entities["gripper"]
    assert gripper["metadata"] == [{"key": "action", "value": f"(grasp {obj.name})"}]
    centroid = np.asarray(obj.centroid_m)
    pose = fg.next_action_pose(report)
    assert pose is not None and np.linalg.norm(pose[:3, 3] - centroid) < 0.08
    assert gripper["cubes"] and all(
        np.linalg.norm([c["pose"]["position"][k] for k in "xyz"] - centroid) < 0.2 for c in gripper["cubes"]
    )
    for cube in gripper["cubes"]:
        q = cube["pose"]["orientation"]
        assert math.isclose(sum(q[k] ** 2 for k in "xyzw"), 1.0, abs_tol=1e-6)  # unit quaternions


def test_predicates_and_plan_name_objects_by_their_ids(annotated: dict[str, Any]) -> None:
    report = annotated["report"]
    (obj,) = report.objects
    predicates = _doc(annotated, fg.PREDICATES_TOPIC)
    assert predicates == fg.predicates_json(report)
    assert predicates["objects"] == [{"id": obj.track_id, "name": obj.name}] and predicates["facts"] == []
    plan = _doc(annotated, fg.PLAN_TOPIC)
    assert plan == report.plan_json()
    assert plan["actions"][0]["id"] == obj.track_id and plan["actions"][0]["kind"] == "grasp"


def test_a_frame_without_colours_is_a_cloud_of_xyz_only(tmp_path: Path) -> None:
    from pypcd4 import PointCloud

    from clearcli.pipeline import read

    xyz = np.array([[0.0, 0.1, 1.0], [np.nan, np.nan, np.nan], [0.2, -0.1, 2.0]], dtype=np.float32)
    path = tmp_path / "xyz.pcd"
    PointCloud.from_xyz_points(xyz).save(path)
    doc = fg.pointcloud_json(read(path))
    assert doc["point_stride"] == 12 and [f["name"] for f in doc["fields"]] == ["x", "y", "z"]
    back = np.frombuffer(base64.b64decode(doc["data"]), dtype="<f4").reshape(-1, 3)
    assert np.array_equal(back, xyz[[0, 2]])


def test_colours_by_id_step_round_the_hue_circle_by_the_golden_angle() -> None:
    r, g, b = colorsys.hsv_to_rgb(0.0, 0.75, 0.95)
    assert fg.id_color(0) == {"r": round(r, 4), "g": round(g, 4), "b": round(b, 4), "a": 1.0}
    assert fg.id_color(0) == {"r": 0.95, "g": 0.2375, "b": 0.2375, "a": 1.0}
    hue = (7 * 0.618033988749895) % 1.0
    r, g, b = colorsys.hsv_to_rgb(hue, 0.75, 0.95)
    assert fg.id_color(7, 0.5) == {"r": round(r, 4), "g": round(g, 4), "b": round(b, 4), "a": 0.5}
    colours = {tuple(fg.id_color(i).values()) for i in range(50)}
    assert len(colours) == 50


def test_dumps_writes_compact_json_and_refuses_nan() -> None:
    assert fg.dumps({"a": [1, 2.5], "b": "x"}) == b'{"a":[1,2.5],"b":"x"}'
    with pytest.raises(ValueError):
        fg.dumps({"a": float("nan")})
