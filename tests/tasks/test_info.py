"""Tests of clearcli/tasks/info.py: what a file holds, through the task layer.

Every number is checked against the file read another way: a PCD's header parsed here
by hand and its points read with pypcd4, an MCAP's records counted with the mcap
library's stream reader (which also stops where a truncated file breaks)."""

from __future__ import annotations

import io
import json
import os
from pathlib import Path

import numpy as np
import pytest
from helpers import FIXTURES, shared_path

from clearcli.errors import EXIT_PARTIAL, InputError
from clearcli.settings import Settings
from clearcli.tasks import info as task
from clearcli.tasks.base import Source

SESSION = FIXTURES / "session.mcap"


def _pcd_header(path: Path) -> dict[str, list[str]]:
    header: dict[str, list[str]] = {}
    with open(path, "rb") as fp:
        for raw in fp:
            line = raw.decode("ascii").strip()
            if not line or line.startswith("#"):
                continue
            key, *values = line.split()
            header[key] = values
            if key == "DATA":
                break
    return header


def _stream_counts(data: bytes) -> tuple[int, dict[str, int], bool]:
    """Messages, messages per topic and whether the file read to its end, by the mcap
    library's stream reader."""
    from mcap.records import Channel, Message
    from mcap.stream_reader import StreamReader

    topics: dict[int, str] = {}
    per: dict[str, int] = {}
    n = 0
    complete = True
    try:
        for record in StreamReader(io.BytesIO(data), skip_magic=False).records:
            if isinstance(record, Channel):
                topics[record.id] = record.topic
            elif isinstance(record, Message):
                n += 1
                per[topics[record.channel_id]] = per.get(topics[record.channel_id], 0) + 1
    except Exception:
        complete = False
    return n, per, complete


@pytest.mark.parametrize("name", ["isolated_box", "clutter10"])
def test_a_pcd_is_described_as_its_header_and_points_say(name: str) -> None:
    from pypcd4 import PointCloud

    path = FIXTURES / f"{name}.pcd"
    outcome = task.run(task.Request(), Source(path))
    assert (outcome.schema, outcome.version, outcome.exit_code) == ("info", 1, 0)
    payload = outcome.payload
    header = _pcd_header(path)
    assert payload["format"] == "pcd"
    pcd = payload["pcd"]
    assert pcd["encoding"] == header["DATA"][0] == "binary_compressed"
    assert [f["name"] for f in pcd["fields"]] == header["FIELDS"]
    assert (pcd["width"], pcd["height"]) == (int(header["WIDTH"][0]), int(header["HEIGHT"][0])) == (640, 480)
    assert pcd["file_bytes"] == os.path.getsize(path)
    frame = payload["frame"]
    assert frame["points"] == int(header["POINTS"][0]) == 640 * 480
    assert frame["organized"] is True and frame["shape"] == [480, 640]
    xyz = PointCloud.from_path(path).numpy(("x", "y", "z")).astype(np.float64)
    finite = np.isfinite(xyz).all(axis=1)
    assert frame["finite_points"] == int(finite.sum())
    assert frame["bounds_m"]["min"] == pytest.approx(xyz[finite].min(axis=0).tolist(), abs=2e-6)
    assert frame["bounds_m"]["max"] == pytest.approx(xyz[finite].max(axis=0).tolist(), abs=2e-6)
    assert frame["has_colors"] is True
    assert [f["name"] for f in frame["fields"]] == ["x", "y", "z", "rgb", "label"]
    json.dumps(payload, allow_nan=False)


def test_an_mcap_log_is_described_as_its_records_say() -> None:
    data = SESSION.read_bytes()
    n, per, complete = _stream_counts(data)
    assert complete
    outcome = task.run(task.Request(settings=Settings()), Source(SESSION, index=2))
    assert outcome.exit_code == 0
    payload = outcome.payload
    assert payload["format"] == "mcap"
    log = payload["mcap"]
    assert log["complete"] is True and log["damage"] is None and log["profile"] == "ros2"
    assert log["message_count"] == n == 5
    assert {c["topic"]: c["message_count"] for c in log["channels"]} == per
    assert log["pointcloud_topic"] == "/camera/depth_registered/points"
    assert log["frame_count"] == per["/camera/depth_registered/points"] == 4
    # fixtures/README.md: frames 0.5 s apart from t = 1763683200.0 s
    assert (log["start_s"], log["end_s"], log["duration_s"]) == pytest.approx((1763683200.0, 1763683201.5, 1.5))
    frame = payload["frame"]
    assert frame["index"] == 2 and frame["stamp_s"] == pytest.approx(1763683201.0)
    assert frame["frame_id"] == "camera_rgb_optical_frame" and frame["points"] == 640 * 480


@pytest.mark.parametrize("share", [0.3, 0.6, 0.9])
def test_a_truncated_log_is_described_up_to_its_break_with_exit_9(share: float, tmp_path: Path) -> None:
    data = SESSION.read_bytes()[: int(SESSION.stat().st_size * share)]
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data)
    n, per, complete = _stream_counts(data)
    assert not complete and per.get("/camera/depth_registered/points", 0) >= 1
    outcome = task.run(task.Request(), Source(cut))
    assert outcome.exit_code == EXIT_PARTIAL == 9
    log = outcome.payload["mcap"]
    assert log["complete"] is False and log["damage"]
    assert log["message_count"] == n
    assert {c["topic"]: c["message_count"] for c in log["channels"] if c["message_count"]} == per


def test_an_ascii_pcd_is_described_as_ascii() -> None:
    path = shared_path("pcd_formats/mosd_test57_ascii.pcd")
    binary = shared_path("pcd_formats/mosd_test57_binary.pcd")
    a = task.run(task.Request(), Source(path)).payload
    b = task.run(task.Request(), Source(binary)).payload
    assert a["pcd"]["encoding"] == _pcd_header(path)["DATA"][0] == "ascii"
    assert b["pcd"]["encoding"] == "binary"
    # the data README: value-identical to each other
    for key in ("points", "finite_points", "shape", "bounds_m"):
        assert a["frame"][key] == b["frame"][key]


def test_what_is_no_frame_is_an_input_error(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="file not found"):
        task.run(task.Request(), Source(tmp_path / "missing.pcd"))
    notes = tmp_path / "notes.txt"
    notes.write_text("hello\n")
    with pytest.raises(InputError):
        task.run(task.Request(), Source(notes))
    with pytest.raises(InputError, match="--frame 7"):
        task.run(task.Request(), Source(SESSION, index=7))
