"""`clear info`: the payload's real values, the JSON envelope, and errors through the real CLI."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from clearcli.io.describe import describe_file
from clearcli.errors import EXIT_INPUT, EXIT_PARTIAL
from clearcli.io.pcd import read_pcd
from utils import REPO, shared_path


def _clear(*args: str) -> subprocess.CompletedProcess[str]:
    """Run the installed entry point the way a user does (exit codes, stderr and all)."""
    exe = Path(sys.executable).parent / "clear"
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "clearcli.cli"]
    return subprocess.run([*cmd, *args], capture_output=True, text=True, cwd=REPO, timeout=60)


def _assert_one_line_error(result: subprocess.CompletedProcess[str], code: int, *needles: str) -> None:
    assert result.returncode == code, result.stderr
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    for needle in needles:
        assert needle in lines[0]


def test_info_pcd_values() -> None:
    path = shared_path("mosd/test/test57.pcd")
    info = describe_file(path)
    assert info["format"] == "pcd"
    assert info["pcd"]["encoding"] == "binary_compressed"
    assert [f["name"] for f in info["pcd"]["fields"]] == ["label", "x", "y", "z", "rgba"]
    frame = info["frame"]
    assert frame["points"] == 307200 and frame["shape"] == [480, 640] and frame["organized"]
    assert frame["finite_points"] == 171483 and frame["has_colors"]
    assert [f["name"] for f in frame["fields"]] == ["x", "y", "z", "rgb", "label"]
    pts = read_pcd(path).points
    finite = np.isfinite(pts).all(axis=1)
    assert frame["bounds_m"]["min"] == pytest.approx(pts[finite].min(axis=0).tolist(), abs=1e-6)
    assert frame["bounds_m"]["max"] == pytest.approx(pts[finite].max(axis=0).tolist(), abs=1e-6)
    # The camera is about 0.6 m above the table, looking down: depths between 0.5 and 1.5 m.
    assert 0.5 < frame["bounds_m"]["min"][2] < frame["bounds_m"]["max"][2] < 1.5


def test_info_mcap_values() -> None:
    info = describe_file(shared_path("mcap/ouster_ros1_pointcloud2.mcap"))
    m = info["mcap"]
    assert m["profile"] == "ros1" and m["indexed"] and m["complete"]
    assert m["message_count"] == 273
    assert m["pointcloud_topic"] == "/os1_cloud_node/points" and m["frame_count"] == 2
    assert m["duration_s"] == pytest.approx(0.183, abs=0.001)
    rosout = [c for c in m["channels"] if c["topic"] == "/rosout"]
    assert len(rosout) == 2 and sum(c["message_count"] for c in rosout) == 12
    assert info["frame"]["shape"] == [64, 2048] and info["frame"]["frame_id"] == "os1_lidar"

    ros2 = describe_file(shared_path("mcap/mosd_tabletop_ros2_pointcloud2.mcap"), index=2)
    assert ros2["mcap"]["frame_count"] == 3 and ros2["frame"]["index"] == 2
    assert ros2["frame"]["finite_points"] == int(read_pcd(shared_path("mosd/learn/learn21.pcd")).finite_mask.sum())

    counts = {
        "mcap/mosd_tabletop_foxglove_protobuf.mcap": 2,
        "mcap/mosd_tabletop_foxglove_json.mcap": 1,
    }
    for rel, n in counts.items():
        d = describe_file(shared_path(rel))
        assert d["mcap"]["frame_count"] == n and d["frame"]["shape"] is None

    none = describe_file(shared_path("mcap/rosbag2/talker.mcap"))
    assert none["mcap"]["pointcloud_topic"] is None and none["frame"] is None
    assert {c["topic"] for c in none["mcap"]["channels"]} == {"/rosout", "/parameter_events", "/topic"}


def test_cli_json_envelope_and_table() -> None:
    result = _clear("info", "--json", str(shared_path("pcd_formats/bun0.pcd")))
    assert result.returncode == 0, result.stderr
    doc = json.loads(result.stdout)
    assert doc["schema"] == "clear.info" and doc["version"] == 1
    assert doc["frame"]["points"] == 397 and doc["frame"]["shape"] is None
    assert doc["pcd"]["encoding"] == "ascii"

    result = _clear("info", str(shared_path("mcap/mosd_tabletop_ros2_pointcloud2.mcap")))
    assert result.returncode == 0, result.stderr
    assert "/camera/depth_registered/points" in result.stdout and "307 200" in result.stdout


def test_cli_errors_one_line_exit_3(tmp_path: Path) -> None:
    cut_bag = tmp_path / "cut.bag"
    cut_bag.write_bytes(shared_path("mcap/mosd_tabletop_ros1.bag").read_bytes()[:5000])
    _assert_one_line_error(_clear("segment", str(cut_bag)), EXIT_INPUT, "truncated", "ROS 1 bag")
    _assert_one_line_error(
        _clear("info", str(shared_path("pcd_formats/stereo_left.pcd"))), EXIT_INPUT, "no x/y/z", "stereo_left.pcd"
    )
    _assert_one_line_error(_clear("info", str(tmp_path / "nope.pcd")), EXIT_INPUT, "file not found")
    empty = tmp_path / "empty.pcd"
    empty.write_bytes(b"")
    _assert_one_line_error(_clear("info", "--json", str(empty)), EXIT_INPUT, "empty file")
    log = shared_path("mcap/mosd_tabletop_ros2_pointcloud2.mcap")
    _assert_one_line_error(_clear("info", str(log), "--frame", "7"), EXIT_INPUT, "has 3 frames")
    _assert_one_line_error(_clear("info", str(log), "--topic", "/x"), EXIT_INPUT, "no topic '/x'")


def test_cli_truncated_log_described_then_exit_9(tmp_path: Path) -> None:
    data = shared_path("mcap/mosd_tabletop_ros2_pointcloud2.mcap").read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * 0.7)])
    result = _clear("info", "--json", str(cut))
    _assert_one_line_error(result, EXIT_PARTIAL, "cut.mcap", "2 complete messages")
    doc = json.loads(result.stdout)
    assert doc["mcap"]["complete"] is False and doc["mcap"]["frame_count"] == 2
    assert doc["frame"]["points"] == 307200
