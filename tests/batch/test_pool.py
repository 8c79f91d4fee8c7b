"""Tests of clearcli/batch/pool.py."""

from __future__ import annotations

from pathlib import Path

from helpers import FIXTURES
from helpers.batch import FRAMES, clear, hooked_env, lines_of

KILL_ONE = """
import os, signal
import clearcli.batch.work as work
_orig = work.run_job
def run_job(job):
    if job.name == "box_on_box":
        os.kill(os.getpid(), signal.SIGKILL)
    return _orig(job)
work.run_job = run_job
import clearcli.batch.pool as pool
pool.run_job = run_job
"""


def test_a_worker_killed_mid_batch_fails_its_frame_only(tmp_path: Path) -> None:
    env = hooked_env(tmp_path, KILL_ONE)
    res = clear("segment", *FRAMES, FIXTURES / "isolated_box.pcd", "--json", "--jobs", "2", env=env)
    assert res.returncode == 11, res.stderr
    rows, summary = lines_of(res.stdout)
    assert len(rows) == 5
    dead = [r for r in rows if "error" in r]
    assert [Path(r["source"]).name for r in dead] == ["box_on_box.pcd"]
    assert dead[0]["exit_code"] == 1 and "worker process died (killed by signal 9)" in dead[0]["error"]["message"]
    assert all(r["exit_code"] == 0 for r in rows if "error" not in r)  # the pool went on
