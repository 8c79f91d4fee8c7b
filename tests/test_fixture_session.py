"""The simulated session in fixtures/ (made by `clear simulate`), replayed end to end."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from utils import FIXTURES

CLEAR = [sys.executable, "-m", "clearcli.cli"]


def test_replaying_the_simulated_fixture_session_keeps_ids_and_clears_the_table() -> None:
    log = FIXTURES / "simulated_session.mcap"
    run = subprocess.run([*CLEAR, "replay", str(log), "--json"], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    lines = [json.loads(line) for line in run.stdout.splitlines()]
    frames = [d for d in lines if d["type"] == "frame"]
    (summary,) = [d for d in lines if d["type"] == "summary"]
    assert len(frames) == summary["frames"] >= 3
    # nothing enters the table during a clearing session: ids only ever disappear, and an
    # object whose grasp was seen to succeed is gone from the next frame
    previous: set[int] | None = None
    for frame in frames:
        ids = {o["id"] for o in frame["objects"]}
        if previous is not None:
            assert ids <= previous, (frame["index"], ids, previous)
        execution = frame.get("execution")
        if execution and execution["outcome"] == "done" and execution["action"].startswith("(grasp"):
            assert execution["id"] not in ids
        previous = ids
    assert frames[0]["objects"] and len({o["id"] for o in frames[0]["objects"]}) == len(frames[0]["objects"])
    assert frames[-1]["status"] == "cleared" and summary["cleared"] is True
    assert summary["failed"] == 0 and summary["back_and_forth"] == 0


def test_a_replay_in_which_no_frame_has_a_table_exits_4(tmp_path: Path) -> None:
    import numpy as np

    from clearcli.io.frames import Frame
    from clearcli.io.pcd import write_pcd

    path = tmp_path / "nan.pcd"
    write_pcd(path, Frame(points=np.full((480 * 640, 3), np.nan, np.float32), shape=(480, 640)))
    run = subprocess.run([*CLEAR, "replay", str(path), "--json"], capture_output=True, text=True, timeout=120)
    assert run.returncode == 4
    assert run.stderr.strip().count("\n") == 0 and "usable table" in run.stderr
    summary = json.loads(run.stdout.splitlines()[-1])
    assert summary["type"] == "summary" and summary["no_table"] == 1
