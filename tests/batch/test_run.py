"""Tests of clearcli/batch/run.py."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from helpers import FIXTURES
from helpers.batch import FRAMES, clear, comparable, lines_of


def test_plan_lines_equal_single_calls_and_jobs_2_equals_jobs_1() -> None:
    one = clear("plan", *FRAMES, "--json", "--jobs", "1")
    two = clear("plan", *FRAMES, "--json", "--jobs", "2")
    assert one.returncode == two.returncode == 0, one.stderr + two.stderr  # 10s are results
    rows1, summary1 = lines_of(one.stdout)
    rows2, summary2 = lines_of(two.stdout)
    assert [r["source"] for r in rows1] == [str(p) for p in FRAMES]  # input order
    assert summary1["frames"] == 4 and summary1["failed"] == 0 and summary2["backend"] == "2 worker processes"
    for r1, r2, path in zip(rows1, rows2, FRAMES):
        single = clear("plan", path, "--json")
        doc = json.loads(single.stdout)
        assert r1["exit_code"] == r2["exit_code"] == single.returncode
        assert comparable(r1["document"]) == comparable(r2["document"]) == comparable(doc)


def test_bad_inputs_reported_each_in_its_line(tmp_path: Path) -> None:
    empty = tmp_path / "empty.pcd"
    empty.write_bytes(b"")
    text = tmp_path / "notes.pcd"
    text.write_text("this is not a point cloud\n")
    corrupt = tmp_path / "corrupt.pcd"
    corrupt.write_bytes((FIXTURES / "isolated_box.pcd").read_bytes()[:2000])
    truncated = tmp_path / "cut.mcap"
    truncated.write_bytes((FIXTURES / "session.mcap").read_bytes()[:5000])
    nothing = tmp_path / "nothing"
    nothing.mkdir()
    out = tmp_path / "out"
    res = clear(
        "plan", FRAMES[0], empty, corrupt, truncated, text, nothing, FRAMES[1], "--json",
        "--out-dir", out, "--outputs", "plan,problem", "--jobs", "2",
    )
    assert res.returncode == 11, res.stderr  # some frames failed
    rows, summary = lines_of(res.stdout)
    by_source = {Path(r["source"]).name: r for r in rows}
    assert by_source["isolated_box.pcd"]["exit_code"] == 0 and by_source["two_touching_boxes.pcd"]["exit_code"] == 0
    for name in ("empty.pcd", "corrupt.pcd", "cut.mcap", "notes.pcd", "nothing"):
        err = by_source[name]["error"]
        assert err["exit_code"] in (3, 9) and name in err["message"], (name, err)
        single = clear("plan", tmp_path / name) if name != "nothing" else None
        if single is not None:  # the message and code a single call gives
            assert single.returncode == err["exit_code"] and err["message"] in single.stderr
    assert summary["failed"] == 5 and summary["done"] == 7
    # the good frames are complete; nothing half-written
    # the good frames complete, the bad ones only their line (a file that cannot be read
    # fails the same way again: --resume does not retry it); nothing half-written
    names = sorted(p.name for p in out.iterdir())
    good = [f"{s}.{e}" for s in ("isolated_box", "two_touching_boxes") for e in ("json", "plan", "problem.pddl")]
    # (and settings.toml: what made the results)
    assert names == sorted(good + ["corrupt.json", "cut_f0.json", "empty.json", "notes.json", "settings.toml"])


SLOW_WRITES = '''
import time
import clearcli.files as files
_orig = files.atomic_output
import contextlib
@contextlib.contextmanager
def slow(path, mode="wb"):
    with _orig(path, mode) as handle:
        yield handle
        handle.flush()
        time.sleep(0.4)  # the write is half done: the temporary exists, the target not yet
files.atomic_output = slow
'''


def test_sigkill_during_a_write_then_resume(tmp_path: Path) -> None:
    hook = tmp_path / "hook"
    hook.mkdir()
    (hook / "sitecustomize.py").write_text(SLOW_WRITES)
    env = dict(os.environ, PYTHONPATH=str(hook))
    out = tmp_path / "out"
    args = [sys.executable, "-m", "clearcli.cli", "plan", *map(str, FRAMES), "--json", "--out-dir", str(out),
            "--outputs", "plan,problem", "--jobs", "1"]
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env, start_new_session=True)
    deadline = time.time() + 300
    killed_during_write = False
    while time.time() < deadline and proc.poll() is None:
        marks = list(out.glob("*.json")) if out.exists() else []
        parts = [p for p in out.glob(".*")] if out.exists() else []
        if len(marks) >= 2 and parts:  # two frames done, a third being written
            os.killpg(proc.pid, signal.SIGKILL)
            killed_during_write = True
            break
        time.sleep(0.01)
    proc.wait(30)
    assert killed_during_write, "the batch finished before it could be killed mid-write"
    assert [p for p in out.glob(".*")], "a temporary of the killed write is left"
    done_before = {p.name: p.stat().st_mtime_ns for p in out.glob("*.json")}
    res = clear("plan", *FRAMES, "--json", "--out-dir", out, "--outputs", "plan,problem", "--resume", "--jobs", "1")
    assert res.returncode == 0, res.stderr
    rows, summary = lines_of(res.stdout)
    assert summary["resumed"] == len(done_before) and summary["done"] == len(FRAMES) - len(done_before)
    assert [r["name"] for r in rows] == [p.stem for p in FRAMES]  # no frame lost
    for name, mtime in done_before.items():  # none redone
        assert (out / name).stat().st_mtime_ns == mtime
    assert not [p for p in out.glob(".*")]  # no stale temporary
    assert sorted(p.name for p in out.iterdir()) == sorted(
        [f"{p.stem}.{ext}" for p in FRAMES for ext in ("json", "plan", "problem.pddl")] + ["settings.toml"]
    )
    for p in FRAMES:  # every plan file is whole
        assert (out / f"{p.stem}.plan").read_text().splitlines()[-1].startswith("; cost = ")


def test_fail_fast_stops_after_the_first_failure(tmp_path: Path) -> None:
    bad = tmp_path / "bad.pcd"
    bad.write_text("not a cloud")
    res = clear("segment", bad, *FRAMES, "--json", "--fail-fast", "--jobs", "1")
    assert res.returncode == 11
    rows, summary = lines_of(res.stdout)
    assert [Path(r["source"]).name for r in rows] == ["bad.pcd"] and rows[0]["exit_code"] == 3
    assert summary["stopped_early"] and summary["not_done"] == len(FRAMES)


def test_ctrl_c_stops_cleanly(tmp_path: Path) -> None:
    """SIGINT to the whole process group (what a terminal's Ctrl-C sends) mid-batch:
    exit 130, the summary of what finished, no worker left, no temporary left."""
    out = tmp_path / "out"
    # many frames: on a loaded machine the signal can come late, and the batch must
    # still be running when it does
    frames = [tmp_path / f"f{k}.pcd" for k in range(len(FRAMES) * 10)]
    for f, src in zip(frames, FRAMES * 10):
        f.write_bytes(src.read_bytes())
    args = [sys.executable, "-m", "clearcli.cli", "plan", *map(str, frames), "--json", "--jobs", "2",
            "--out-dir", str(out), "--outputs", "plan,problem,png"]
    # SIGINT back to its default in the child: a test run started in the background of
    # a non-interactive shell (`cmd &`) inherits SIGINT ignored, and Python then keeps
    # ignoring it, as a shell's background job should (the batch ran to the end: exit 0)
    proc = subprocess.Popen(
        args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    deadline = time.time() + 300
    while time.time() < deadline and not (out.exists() and list(out.glob("*.json"))):
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, stderr
    rows, summary = lines_of(stdout)
    assert summary["interrupted"] and summary["done"] == len(rows) < len(frames)
    assert "interrupted" in stderr and "Traceback" not in stderr
    time.sleep(0.5)
    ps = subprocess.run(["ps", "-o", "pid=,stat=", "-g", str(proc.pid)], capture_output=True, text=True).stdout
    # (exited processes whose parent is gone stay zombies here: this sandbox's init does
    # not reap them; they run nothing)
    alive = [row for row in ps.splitlines() if row.split() and not row.split()[1].startswith("Z")]
    assert not alive, f"processes left running in the batch's group: {alive}"
    assert not [p for p in out.glob(".*")]  # no half-written file
    for r in rows:  # every reported frame is complete on disk
        assert (out / f"{r['name']}.json").is_file() and (out / f"{r['name']}.plan").is_file()


def test_out_dir_outputs_are_not_overwritten_without_force(tmp_path: Path) -> None:
    out = tmp_path / "out"
    first = clear("segment", *FRAMES[:2], "--json", "--out-dir", out, "--outputs", "labels", "--jobs", "1")
    assert first.returncode == 0, first.stderr
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    again = clear("segment", *FRAMES[:2], "--json", "--out-dir", out, "--outputs", "labels", "--jobs", "1")
    assert again.returncode == 11
    rows, _ = lines_of(again.stdout)
    assert all(r["exit_code"] == 8 and "--force" in r["error"]["message"] for r in rows)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # nothing the user had is lost
    forced = clear("segment", *FRAMES[:2], "--json", "--out-dir", out, "--outputs", "labels", "--force", "--jobs", "1")
    assert forced.returncode == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(before)


def test_every_frame_of_a_truncated_log_then_its_break(tmp_path: Path) -> None:
    cut = tmp_path / "cut.mcap"
    cut.write_bytes((FIXTURES / "session.mcap").read_bytes()[:1_500_000])
    res = clear("segment", cut, "--every", "1", "--json", "--jobs", "1")
    assert res.returncode == 11
    rows, summary = lines_of(res.stdout)
    assert [(r["frame"], r["exit_code"]) for r in rows] == [(0, 0), (1, 0), (2, 9)]
    assert "2 complete frames read" in rows[-1]["error"]["message"]
    assert [r["name"] for r in rows[:2]] == ["cut_f0", "cut_f1"]
