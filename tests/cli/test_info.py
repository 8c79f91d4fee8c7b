"""`clear info` on the command line, as a user or a script runs it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from helpers import REPO, shared_path

from clearcli.errors import EXIT_INPUT, EXIT_PARTIAL


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
