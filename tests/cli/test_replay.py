"""`clear replay` on the command line, as a user or a script runs it."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from helpers import REPO, shared_path
from helpers.replay_session import (
    _clear_inprocess,
    _lines,
    sim_log,  # noqa: F401  (fixtures)
)

from clearcli.errors import EXIT_PARTIAL
from clearcli.sim.truth import truth_segment


def _clear_subprocess(*args: str) -> subprocess.CompletedProcess[str]:
    exe = Path(sys.executable).parent / "clear"
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "clearcli.cli"]
    return subprocess.run([*cmd, *args], capture_output=True, text=True, cwd=REPO, timeout=120)


@pytest.fixture
def truth_segmentation(monkeypatch: pytest.MonkeyPatch) -> None:
    """Segment simulated frames from their labels: fast, and it isolates the replay loop
    from the segmenter's errors."""
    import clearcli.pipeline as pipeline

    monkeypatch.setattr(pipeline, "_default_segment", lambda: truth_segment)


def test_cli_json_lines(sim_log: dict[str, Any], truth_segmentation: None, capsys, monkeypatch) -> None:
    code, out, err = _clear_inprocess(capsys, monkeypatch, "replay", str(sim_log["path"]), "--json")
    assert code == 0, err
    lines = _lines(out)
    assert all(d["schema"] == "clear.replay" and d["version"] == 1 for d in lines)
    assert [d["type"] for d in lines] == ["frame"] * sim_log["frames"] + ["summary"]
    frames, summary = lines[:-1], lines[-1]
    assert [d["index"] for d in frames] == list(range(sim_log["frames"]))
    assert [d["time_s"] for d in frames] == pytest.approx([float(i) for i in range(sim_log["frames"])])
    assert frames[-1]["status"] == "cleared" and all(d["status"] == "ok" for d in frames[:-1])
    for d in frames[:-1]:
        first = d["first_action"]
        assert first["id"] in {o["id"] for o in d["objects"]}
        assert d["plan"]["actions"][0] == {k: first[k] for k in d["plan"]["actions"][0]}
        assert d["plan_length"] == len(d["plan"]["actions"])
        assert set(d["timings_s"]) >= {"read", "segment", "predicates", "plan", "total"}
    assert summary["frames"] == sim_log["frames"] and summary["cleared"] is True
    assert summary["actions"] == sim_log["frames"] - 1
    # the world lets grasps of objects near the opening width slip: the monitor sees it
    slipped = sum(1 for step in sim_log["result"].steps if step.outcome == "slipped")
    assert summary["executions"] == {"done": summary["actions"] - slipped, "failed": slipped}
    assert summary["back_and_forth"] == 0
    assert "robot base: wam_base" in err


def test_every_from_to(sim_log: dict[str, Any], truth_segmentation: None, capsys, monkeypatch) -> None:
    code, out, _ = _clear_inprocess(capsys, monkeypatch, "replay", str(sim_log["path"]), "--json", "--every", "2")
    assert code == 0
    assert [d["index"] for d in _lines(out) if d["type"] == "frame"] == list(range(0, sim_log["frames"], 2))
    code, out, _ = _clear_inprocess(
        capsys, monkeypatch, "replay", str(sim_log["path"]), "--json", "--from", "1.5", "--to", "3.5"
    )
    assert code == 0
    lines = _lines(out)
    assert [d["index"] for d in lines if d["type"] == "frame"] == [2, 3]
    assert lines[-1]["frames"] == 2


def test_truncated_log_replays_complete_frames_then_exit_9(
    sim_log: dict[str, Any], truth_segmentation: None, tmp_path: Path, capsys, monkeypatch
) -> None:
    data = sim_log["path"].read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * 0.55)])
    annotated = tmp_path / "cut-annotated.mcap"
    code, out, err = _clear_inprocess(capsys, monkeypatch, "replay", str(cut), "--json", "--out", str(annotated))
    assert code == EXIT_PARTIAL
    lines = _lines(out)
    frames = [d for d in lines if d["type"] == "frame"]
    assert 1 <= len(frames) < sim_log["frames"]
    assert lines[-1]["type"] == "summary" and lines[-1]["frames"] == len(frames)
    assert "truncated or corrupt" in lines[-1]["stopped"]
    assert "truncated or corrupt" in err.strip().splitlines()[-1] and "Traceback" not in err
    # the annotated log holds every complete frame
    from clearcli.io.mcap import read_summary

    assert read_summary(annotated).count("/clear/scene") == len(frames)


@pytest.mark.parametrize(
    ("name", "n_frames"),
    [
        ("mosd_tabletop_ros2_pointcloud2.mcap", 3),
        ("mosd_tabletop_foxglove_protobuf.mcap", 2),
        ("mosd_tabletop_foxglove_json.mcap", 1),
    ],
)
def test_replay_real_logs(name: str, n_frames: int, capsys, monkeypatch) -> None:
    path = shared_path(f"mcap/{name}")
    code, out, err = _clear_inprocess(capsys, monkeypatch, "replay", str(path), "--json")
    assert code == 0, err
    lines = _lines(out)
    assert [d["type"] for d in lines] == ["frame"] * n_frames + ["summary"]
    for d in lines[:-1]:
        # mOSD test57 / test55 / learn21: cluttered tables (learn21's stacked boxes are
        # all too wide for the gripper: no plan, with the reason)
        assert d["status"] in ("ok", "no_plan"), d["error"]
        assert len(d["objects"]) >= 2
        if d["status"] == "ok":
            assert d["first_action"]["id"] in {o["id"] for o in d["objects"]}
            assert d["plan_length"] == len(d["plan"]["actions"]) >= 1
        else:
            assert d["error"].startswith("no plan")
        assert len({o["id"] for o in d["objects"]}) == len(d["objects"])
    assert lines[0]["status"] == "ok"  # test57
    assert [d["time_s"] for d in lines[:-1]] == pytest.approx([0.5 * i for i in range(n_frames)])
    assert lines[-1]["frames"] == n_frames and lines[-1]["failed"] == 0


def test_user_errors_are_one_line_with_their_exit_codes(tmp_path: Path) -> None:
    from clearcli.errors import EXIT_INPUT

    result = _clear_subprocess("replay", str(tmp_path / "missing.mcap"))
    assert result.returncode == EXIT_INPUT and "file not found" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and "Traceback" not in result.stderr
    rosbag = shared_path("mcap/rosbag2")
    logs = sorted(rosbag.rglob("*.mcap"))
    if logs:
        result = _clear_subprocess("replay", str(logs[0]))
        assert result.returncode == EXIT_INPUT and "point-cloud topic" in result.stderr
    result = _clear_subprocess("replay", str(tmp_path / "missing.mcap"), "--from", "3", "--to", "1")
    assert result.returncode == EXIT_INPUT and "--to" in result.stderr


def test_from_and_to_that_select_nothing_are_exit_3(tmp_path: Path) -> None:
    from helpers import FIXTURES, run_clear

    res = run_clear("replay", FIXTURES / "simulated_session.mcap", "--from", "1000")
    assert res.returncode == 3 and "select no frame" in res.stderr and "7" in res.stderr
