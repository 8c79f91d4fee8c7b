"""Tests of clearcli/replay/annotate.py."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from helpers.replay import simulated_session

from clearcli.errors import EXIT_OUTPUT
from clearcli.replay.foxglove import (
    PLAN_TOPIC,
    PREDICATES_TOPIC,
    SCENE_TOPIC,
    SCENE_UPDATE_JSONSCHEMA,
    _arrow,
    id_color,
    scene_update,
)


def _run(capsys, monkeypatch, *args: str) -> tuple[int, str, str]:
    from clearcli import cli

    monkeypatch.setattr(sys, "argv", ["clear", *args])
    with pytest.raises(SystemExit) as exit_info:
        cli.main()
    out, err = capsys.readouterr()
    return int(exit_info.value.code or 0), out, err


@pytest.fixture
def truth_segmentation(monkeypatch: pytest.MonkeyPatch) -> None:
    import clearcli.pipeline as pipeline
    from clearcli.sim.truth import truth_segment

    monkeypatch.setattr(pipeline, "_default_segment", lambda: truth_segment)


@pytest.fixture(scope="module")
def sim_log(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    return simulated_session(tmp_path_factory.mktemp("sim"))


def _read_back(path: Path) -> dict[int, dict[str, Any]]:
    """Messages by log time, by topic: (schema name, schema encoding, message encoding, data)."""
    from mcap.reader import make_reader

    by_time: dict[int, dict[str, Any]] = {}
    with open(path, "rb") as fp:
        reader = make_reader(fp)
        for schema, channel, message in reader.iter_messages(log_time_order=True):
            by_time.setdefault(message.log_time, {})[channel.topic] = (
                schema.name if schema else "",
                schema.encoding if schema else "",
                channel.message_encoding,
                message.data,
            )
    return by_time


def test_annotated_log_matches_the_json_lines(
    sim_log: dict[str, Any], truth_segmentation: None, tmp_path: Path, capsys, monkeypatch
) -> None:
    out = tmp_path / "annotated.mcap"
    code, stdout, err = _run(capsys, monkeypatch, "replay", str(sim_log["path"]), "--json", "--out", str(out))
    assert code == 0, err
    lines = [json.loads(line) for line in stdout.splitlines()]
    frames = [d for d in lines if d["type"] == "frame"]
    assert len(frames) == sim_log["frames"]
    assert [p.name for p in tmp_path.iterdir()] == ["annotated.mcap"]  # no temporary left over
    messages = _read_back(out)
    assert len(messages) == len(frames)
    # the input frames, byte for byte
    from mcap.reader import make_reader

    with open(sim_log["path"], "rb") as fp:
        originals = {
            m.log_time: m.data for _, c, m in make_reader(fp).iter_messages(topics=["/camera/depth_registered/points"])
        }
    pushed_arrows = 0
    for line, (stamp_ns, topics) in zip(frames, sorted(messages.items())):
        assert stamp_ns == int(round(line["stamp_s"] * 1e9))
        schema, _, encoding, data = topics["/camera/depth_registered/points"]
        assert (schema, encoding) == ("sensor_msgs/msg/PointCloud2", "cdr")
        assert data == originals[stamp_ns]
        schema, schema_encoding, encoding, data = topics[SCENE_TOPIC]
        assert (schema, schema_encoding, encoding) == ("foxglove.SceneUpdate", "jsonschema", "json")
        update = json.loads(data)
        assert update["deletions"][0]["type"] == 1  # the previous frame's entities go
        entities = {e["id"]: e for e in update["entities"]}
        object_ids = {f"object/{o['id']}" for o in line["objects"]}
        expected = object_ids | ({"gripper"} if line["first_action"] else set())
        assert set(entities) == expected
        for o in line["objects"]:
            entity = entities[f"object/{o['id']}"]
            assert entity["frame_id"] == "camera_rgb_optical_frame"
            assert entity["triangles"] and entity["triangles"][0]["indices"]  # the hull
            assert entity["triangles"][0]["color"] == id_color(o["id"], 0.7)
            assert {"key": "id", "value": str(o["id"])} in entity["metadata"]
            assert len(entity["arrows"]) == 4  # one per push direction
            assert entity["texts"][0]["text"].startswith(f"#{o['id']}")
            pushed_arrows += sum(1 for a in entity["arrows"] if a["shaft_diameter"] > 0.005)
        if line["plan"] is None:
            assert PLAN_TOPIC not in topics
        else:
            assert json.loads(topics[PLAN_TOPIC][3]) == line["plan"]
            predicates = json.loads(topics[PREDICATES_TOPIC][3])
            assert {p["id"] for p in predicates["objects"]} == {o["id"] for o in line["objects"]}
        if line["first_action"]:
            gripper = entities["gripper"]
            assert len(gripper["cubes"]) == 3  # two fingers and the base
            assert {
                "key": "action",
                "value": f"({line['first_action']['kind']} {line['first_action']['name']}"
                + (f" {line['first_action']['direction']})" if line["first_action"].get("direction") else ")"),
            } in gripper["metadata"]
    pushes = sum(1 for d in frames if d["first_action"] and d["first_action"]["kind"] == "push")
    assert pushes >= 1 and pushed_arrows == pushes  # the planned push stands out


def test_scene_updates_are_valid_against_their_schema(
    sim_log: dict[str, Any], truth_segmentation: None, tmp_path: Path, capsys, monkeypatch
) -> None:
    jsonschema = pytest.importorskip("jsonschema")
    out = tmp_path / "a.mcap"
    code, _, err = _run(capsys, monkeypatch, "replay", str(sim_log["path"]), "--out", str(out), "--to", "1")
    assert code == 0, err
    updates = [json.loads(t[SCENE_TOPIC][3]) for t in _read_back(out).values()]
    assert len(updates) == 2
    for update in updates:
        jsonschema.validate(update, SCENE_UPDATE_JSONSCHEMA)


def test_existing_output_needs_force(
    sim_log: dict[str, Any], truth_segmentation: None, tmp_path: Path, capsys, monkeypatch
) -> None:
    out = tmp_path / "taken.mcap"
    out.write_bytes(b"precious")
    code, _, err = _run(capsys, monkeypatch, "replay", str(sim_log["path"]), "--out", str(out), "--to", "0")
    assert code == EXIT_OUTPUT and "--force" in err
    assert out.read_bytes() == b"precious"
    code, _, err = _run(capsys, monkeypatch, "replay", str(sim_log["path"]), "--out", str(out), "--to", "0", "--force")
    assert code == 0, err
    assert len(_read_back(out)) == 1
    code, _, err = _run(capsys, monkeypatch, "replay", str(sim_log["path"]), "--out", str(sim_log["path"]), "--force")
    assert code == EXIT_OUTPUT and "input" in err


def test_pcd_input_is_written_as_a_foxglove_point_cloud(
    truth_segmentation: None, tmp_path: Path, capsys, monkeypatch
) -> None:
    import base64

    from clearcli.io.pcd import write_pcd
    from clearcli.sim import scene as scenes
    from clearcli.sim.camera import render

    frame = render(scenes.clutter(3, 2), seed=0)
    pcd = tmp_path / "scene.pcd"
    write_pcd(pcd, frame)
    out = tmp_path / "scene.mcap"
    code, _, err = _run(capsys, monkeypatch, "replay", str(pcd), "--out", str(out))
    assert code == 0, err
    (topics,) = _read_back(out).values()
    schema, schema_encoding, encoding, data = topics["/clear/points"]
    assert (schema, schema_encoding, encoding) == ("foxglove.PointCloud", "jsonschema", "json")
    cloud = json.loads(data)
    # x y z float32 then red green blue uint8, padded to 16 bytes
    assert cloud["point_stride"] == 16
    assert [(f["name"], f["offset"], f["type"]) for f in cloud["fields"]] == [
        ("x", 0, 7),
        ("y", 4, 7),
        ("z", 8, 7),
        ("red", 12, 1),
        ("green", 13, 1),
        ("blue", 14, 1),
    ]
    record = np.dtype([("p", "<f4", 3), ("c", "u1", 3), ("pad", "u1")])
    blob = np.frombuffer(base64.b64decode(cloud["data"]), dtype=record)
    keep = frame.finite_mask
    np.testing.assert_array_equal(blob["p"], frame.points[keep])
    assert frame.colors is not None
    np.testing.assert_array_equal(blob["c"], frame.colors[keep])


def test_id_colours_differ_and_arrows_point_along_their_direction() -> None:
    colours = [tuple(id_color(i).values())[:3] for i in range(12)]
    assert len(set(colours)) == 12
    for i in range(11):
        assert np.abs(np.subtract(colours[i], colours[i + 1])).max() > 0.1
    from scipy.spatial.transform import Rotation

    direction = np.array([0.6, 0.0, 0.8])
    arrow = _arrow(np.array([1.0, 2.0, 3.0]), direction, np.array([0.0, -1.0, 0.0]), 0.1, id_color(0), True)
    q = arrow["pose"]["orientation"]
    R = Rotation.from_quat([q["x"], q["y"], q["z"], q["w"]]).as_matrix()
    np.testing.assert_allclose(R[:, 0], direction, atol=1e-9)
    np.testing.assert_allclose(R[:, 2], [0.0, -1.0, 0.0], atol=1e-9)
    assert arrow["shaft_length"] + arrow["head_length"] == pytest.approx(0.1)


def test_frame_without_segmentation_only_clears_the_scene() -> None:
    from clearcli.pipeline import FrameResult
    from clearcli.replay.report import FrameReport

    report = FrameReport(index=3, stamp_s=2.5, time_s=1.0, result=FrameResult(status="no_table"))
    update = scene_update(report, "camera")
    assert update["entities"] == []
    assert update["deletions"] == [{"timestamp": {"sec": 2, "nsec": 500_000_000}, "type": 1, "id": ""}]
