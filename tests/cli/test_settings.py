"""Settings on the command line: `--settings`, `--set`, `clear settings`, and ranges
checked once, before any frame is read, for single calls and batches alike."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest
from helpers import FIXTURES
from helpers import run_clear as clear

FIXTURE = FIXTURES / "isolated_box.pcd"
SESSION = FIXTURES / "simulated_session.mcap"


def test_settings_prints_the_resolved_tree_with_set() -> None:
    proc = clear("settings", "--set", "tracking.gate_m=0.05", "--set", "world.frame_interval_s=2.5")
    assert proc.returncode == 0, proc.stderr
    sections: dict[str, dict[str, str]] = {}
    current = ""
    for line in proc.stdout.splitlines():
        if line.startswith("["):
            current = line.strip("[]")
        elif " = " in line:
            k, v = line.split(" = ", 1)
            sections.setdefault(current, {})[k] = v
    assert sections["tracking"]["gate_m"] == "0.05"
    assert sections["world"]["frame_interval_s"] == "2.5"
    assert sections["segment"]["voxel_m"] == "0.005"  # the rest stays default


def _objects_seen(proc: subprocess.CompletedProcess[str]) -> int:
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout.splitlines()[-1])
    assert summary["type"] == "summary"
    return int(summary["objects_seen"])


def test_set_and_settings_reach_replay_tracking(tmp_path: Path) -> None:
    """A tracking gate too tight to keep any id: every frame's objects are new ones."""
    base = _objects_seen(clear("replay", SESSION, "--json"))
    sets = ("--set", "tracking.gate_m=0.0001", "--set", "tracking.rematch_distance_m=0")
    by_set = _objects_seen(clear("replay", SESSION, "--json", *sets))
    file = tmp_path / "tight.toml"
    file.write_text("[tracking]\ngate_m = 0.0001\nrematch_distance_m = 0.0\n")
    by_file = _objects_seen(clear("replay", SESSION, "--json", "--settings", file))
    assert base == 5
    assert by_set == by_file > 3 * base


def _stamps_span_s(log: Path) -> float:
    proc = clear("info", log, "--json")
    assert proc.returncode == 0, proc.stderr
    return float(json.loads(proc.stdout)["mcap"]["duration_s"])


def test_set_and_settings_reach_the_simulated_world(tmp_path: Path) -> None:
    """[world] frame_interval_s spaces the simulated frames' stamps."""
    runs = {}
    file = tmp_path / "slow.toml"
    file.write_text("[world]\nframe_interval_s = 2.5\n")
    for key, extra in (
        ("default", ()),
        ("set", ("--set", "world.frame_interval_s=2.5")),
        ("file", ("--settings", file)),
    ):
        out = tmp_path / f"{key}.mcap"
        proc = clear("simulate", out, "--scene", "isolated_box", "--json", *extra)
        assert proc.returncode == 0, proc.stderr
        frames = json.loads(proc.stdout)["frames"]
        runs[key] = (_stamps_span_s(out), frames)
    span, frames = runs["default"]
    assert frames >= 2
    assert span == pytest.approx(1.0 * (frames - 1))
    for key in ("set", "file"):
        assert runs[key] == (pytest.approx(2.5 * (runs[key][1] - 1)), runs[key][1])


@pytest.mark.parametrize(
    "args, key",
    [
        (("--set", "segment.voxel_m=0"), "voxel_m"),
        (("--set", "segment.seed_m=nan"), "seed_m"),
        (("--set", "plan.time_limit_s=-30"), "time_limit_s"),
        (("--set", "segment.supervoxel_iterations=1000000000"), "supervoxel_iterations"),
        (("--set", "segmnt.voxel_m=0.01"), "segmnt"),
        (("--set", "voxel_m"), "SECTION.KEY=VALUE"),
    ],
)
def test_bad_setting_is_one_line_exit_3(args: tuple[str, ...], key: str) -> None:
    proc = clear("plan", FIXTURE, *args)
    assert proc.returncode == 3
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and key in lines[0] and "Traceback" not in proc.stderr


def test_batch_with_a_bad_settings_file_fails_once_before_any_work(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("[segment]\nvoxel_m = -1\n")
    out = tmp_path / "out"
    frames = [FIXTURES / n for n in ("isolated_box.pcd", "box_on_box.pcd", "two_touching_boxes.pcd")]
    proc = clear("plan", *frames, "--settings", bad, "--json", "--out-dir", out)
    assert proc.returncode == 3
    assert proc.stdout == ""  # no frame line: nothing ran
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "voxel_m" in lines[0] and ">= 0.001" in lines[0]
    assert not out.exists() or not any(out.iterdir())  # no marks to make --resume skip frames
