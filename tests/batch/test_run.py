"""Tests of clearcli/batch/run.py."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import time
from pathlib import Path

import pytest
from helpers import FIXTURES, start_clear
from helpers.batch import FRAMES, clear, comparable, hooked_env, lines_of


def _temporaries(out: Path) -> list[Path]:
    """What killed writes leave in --out-dir: hidden files other than the batch lock."""
    return [p for p in out.glob(".*") if p.name != ".clear-batch.lock"]


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
        "plan",
        FRAMES[0],
        empty,
        corrupt,
        truncated,
        text,
        nothing,
        FRAMES[1],
        "--json",
        "--out-dir",
        out,
        "--outputs",
        "plan,problem",
        "--jobs",
        "2",
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
    # the good frames complete with their marks; the bad ones only their line and no
    # mark (a mark is for results: --resume does them again); nothing half-written;
    # settings.toml says what made the results, the lock file what is writing them
    names = sorted(p.name for p in out.iterdir())
    good = [f"{s}.{e}" for s in ("isolated_box", "two_touching_boxes") for e in ("json", "plan", "problem.pddl")]
    assert names == sorted(good + ["settings.toml", ".clear-batch.lock"])


SLOW_WRITES = """
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
"""


def test_sigkill_during_a_write_then_resume(tmp_path: Path) -> None:
    env = hooked_env(tmp_path, SLOW_WRITES)
    out = tmp_path / "out"
    args = ["plan", *FRAMES, "--json", "--out-dir", out, "--outputs", "plan,problem", "--jobs", "1"]
    proc = start_clear(*args, env=env, start_new_session=True)
    deadline = time.time() + 300
    killed_during_write = False
    while time.time() < deadline and proc.poll() is None:
        marks = list(out.glob("*.json")) if out.exists() else []
        parts = _temporaries(out) if out.exists() else []
        if len(marks) >= 2 and parts:  # two frames done, a third being written
            os.killpg(proc.pid, signal.SIGKILL)
            killed_during_write = True
            break
        time.sleep(0.01)
    proc.wait(30)
    assert killed_during_write, "the batch finished before it could be killed mid-write"
    assert _temporaries(out), "a temporary of the killed write is left"
    done_before = {p.name: p.stat().st_mtime_ns for p in out.glob("*.json")}
    res = clear("plan", *FRAMES, "--json", "--out-dir", out, "--outputs", "plan,problem", "--resume", "--jobs", "1")
    assert res.returncode == 0, res.stderr
    rows, summary = lines_of(res.stdout)
    assert summary["resumed"] == len(done_before) and summary["done"] == len(FRAMES) - len(done_before)
    assert [r["name"] for r in rows] == [p.stem for p in FRAMES]  # no frame lost
    for name, mtime in done_before.items():  # none redone
        assert (out / name).stat().st_mtime_ns == mtime
    assert not _temporaries(out)  # no stale temporary
    assert sorted(p.name for p in out.iterdir()) == sorted(
        [f"{p.stem}.{ext}" for p in FRAMES for ext in ("json", "plan", "problem.pddl")]
        + ["settings.toml", ".clear-batch.lock"]
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
    args = ["plan", *frames, "--json", "--jobs", "2", "--out-dir", out, "--outputs", "plan,problem,png"]
    # SIGINT back to its default in the child: a test run started in the background of
    # a non-interactive shell (`cmd &`) inherits SIGINT ignored, and Python then keeps
    # ignoring it, as a shell's background job should (the batch ran to the end: exit 0)
    proc = start_clear(
        *args,
        text=True,
        start_new_session=True,
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
    assert not _temporaries(out)  # no half-written file
    for r in rows:  # every reported frame is complete on disk
        assert (out / f"{r['name']}.json").is_file() and (out / f"{r['name']}.plan").is_file()


def test_out_dir_outputs_are_not_overwritten_without_force(tmp_path: Path) -> None:
    out = tmp_path / "out"
    first = clear("segment", *FRAMES[:2], "--json", "--out-dir", out, "--outputs", "labels", "--jobs", "1")
    assert first.returncode == 0, first.stderr
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.name != ".clear-batch.lock"}
    again = clear("segment", *FRAMES[:2], "--json", "--out-dir", out, "--outputs", "labels", "--jobs", "1")
    assert again.returncode == 11
    rows, _ = lines_of(again.stdout)
    assert all(r["exit_code"] == 8 and "--force" in r["error"]["message"] for r in rows)
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.name != ".clear-batch.lock"} == before  # nothing lost
    forced = clear("segment", *FRAMES[:2], "--json", "--out-dir", out, "--outputs", "labels", "--force", "--jobs", "1")
    assert forced.returncode == 0
    assert sorted(p.name for p in out.iterdir() if p.name != ".clear-batch.lock") == sorted(before)


def test_every_frame_of_a_truncated_log_then_its_break(tmp_path: Path) -> None:
    cut = tmp_path / "cut.mcap"
    cut.write_bytes((FIXTURES / "session.mcap").read_bytes()[:1_500_000])
    res = clear("segment", cut, "--every", "1", "--json", "--jobs", "1")
    assert res.returncode == 11
    rows, summary = lines_of(res.stdout)
    assert [(r["frame"], r["exit_code"]) for r in rows] == [(0, 0), (1, 0), (2, 9)]
    assert "2 complete frames read" in rows[-1]["error"]["message"]
    assert [r["name"] for r in rows[:2]] == ["cut_f0", "cut_f1"]


# --- reliability: outputs owned by exact name, one batch per folder, results only marked


def _copy(folder: Path, names: list[str]) -> None:
    import shutil

    folder.mkdir(parents=True, exist_ok=True)
    for n in names:
        shutil.copy(FIXTURES / "isolated_box.pcd", folder / n)


def test_resume_removes_only_what_a_frame_owns_by_exact_name(tmp_path: Path) -> None:
    """Frames whose names are prefixes or glob patterns of others: resuming one never
    touches another's files (the glob `{name}.*` of before deleted b.1's and x1's)."""
    src, out = tmp_path / "src", tmp_path / "out"
    names = ["b.pcd", "b.1.pcd", "x[1].pcd", "x1.pcd", "run_*.pcd", "run_a.pcd", "a b.pcd", "grün.pcd", "new\nline.pcd"]
    _copy(src, names)
    first = clear("segment", src, "--out-dir", out, "--outputs", "labels", "--json", "--jobs", "1")
    assert first.returncode == 0, first.stderr
    stems = [Path(n).stem for n in names]
    for stem in stems:
        assert (out / f"{stem}.json").is_file() and (out / f"{stem}.labels.pcd").is_file()
    before = {p.name: p.stat().st_mtime_ns for p in out.iterdir() if not p.name.startswith(".")}
    # an unfinished b, x[1] and run_*: no mark, a temporary of a killed write
    for stem in ("b", "x[1]", "run_*", "new\nline"):
        (out / f"{stem}.json").unlink()
        (out / f".{stem}.json.abcd1234.part").write_text("half")
    again = clear("segment", src, "--out-dir", out, "--outputs", "labels", "--json", "--resume", "--jobs", "1")
    assert again.returncode == 0, again.stderr
    rows, summary = lines_of(again.stdout)
    assert (summary["done"], summary["resumed"]) == (4, 5)
    after = {p.name: p.stat().st_mtime_ns for p in out.iterdir() if not p.name.startswith(".")}
    assert set(after) == set(before)  # nothing lost
    for stem in ("b.1", "x1", "run_a", "a b", "grün"):  # the look-alikes and the rest were not touched
        for f in (f"{stem}.json", f"{stem}.labels.pcd"):
            assert after[f] == before[f], f
    assert not _temporaries(out)


def test_a_failed_frame_has_no_mark_and_resume_does_it_again(tmp_path: Path) -> None:
    src, out = tmp_path / "src", tmp_path / "out"
    _copy(src, ["good.pcd"])
    (src / "bad.pcd").write_text("VERSION .7\nnot a pcd at all\n")
    res = clear("segment", src, "--out-dir", out, "--json", "--jobs", "1")
    assert res.returncode == 11
    assert (out / "good.json").is_file() and not (out / "bad.json").exists()
    (src / "bad.pcd").write_bytes((FIXTURES / "box_on_box.pcd").read_bytes())  # fixed
    again = clear("segment", src, "--out-dir", out, "--json", "--resume", "--jobs", "1")
    assert again.returncode == 0, again.stderr
    rows, summary = lines_of(again.stdout)
    assert (summary["done"], summary["resumed"]) == (1, 1) and (out / "bad.json").is_file()


def test_a_second_batch_on_the_folder_refuses_or_waits(tmp_path: Path) -> None:
    from clearcli.batch.run import lock_out_dir

    out = tmp_path / "out"
    out.mkdir()
    held = lock_out_dir(out, "plan", wait=False)  # a batch of this process holds the folder
    try:
        res = clear("segment", FIXTURES / "isolated_box.pcd", "--out-dir", out, "--json")
        assert res.returncode == 8
        line = res.stderr.strip().splitlines()
        assert len(line) == 1 and f"pid {os.getpid()}" in line[0] and "--wait" in line[0]
        assert not list(out.glob("*.json"))  # nothing written
        waiting = start_clear("segment", FIXTURES / "isolated_box.pcd", "--out-dir", out, "--json", "--wait", text=True)
        time.sleep(1.5)
        assert waiting.poll() is None  # still waiting for the lock
    finally:
        held.close()
    out_text, err_text = waiting.communicate(timeout=120)
    assert waiting.returncode == 0, err_text
    assert "waiting for `clear plan`" in err_text and (out / "isolated_box.json").is_file()


def test_an_output_that_is_an_input_of_the_batch_is_refused_even_with_force(tmp_path: Path) -> None:
    """`segment DIR --out-dir DIR --outputs labels --force` must not write a.pcd's labels
    over a.labels.pcd, another input of the run."""
    d = tmp_path / "d"
    _copy(d, ["a.pcd"])
    (d / "a.labels.pcd").write_bytes((FIXTURES / "box_on_box.pcd").read_bytes())
    kept = (d / "a.labels.pcd").read_bytes()
    res = clear("segment", d, "--out-dir", d, "--outputs", "labels", "--force", "--json", "--jobs", "1")
    rows, summary = lines_of(res.stdout)
    by_name = {r["name"]: r for r in rows}
    assert by_name["a"]["exit_code"] == 8 and "is an input of this batch" in by_name["a"]["error"]["message"]
    assert (d / "a.labels.pcd").read_bytes() == kept
    assert res.returncode == 11


def test_a_full_disk_fails_the_frame_with_exit_8_and_stops_the_batch(tmp_path: Path, monkeypatch) -> None:
    """ENOSPC while writing (injected: no small tmpfs here): that frame's line says so
    with exit 8, nothing half-written is left, and no new frame is started."""
    import errno

    import clearcli.files as files
    from clearcli.batch.run import BatchRequest, run_batch
    from clearcli.settings import Settings
    from clearcli.tasks import segment as task

    def full(src: str, dst: str) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    out = tmp_path / "out"

    def batch(frames: list[Path]) -> tuple[int, list[dict]]:
        lines: list[dict] = []
        req = BatchRequest("segment", frames, task.Request(Settings()), out_dir=out, outputs=("labels",), jobs=1)
        code = run_batch(req, on_line=lines.append, render=lambda rows, summary: lines.append(dict(summary)))
        return code, lines

    assert batch(FRAMES[3:])[0] == 0  # the folder, its settings.toml and one frame, written
    monkeypatch.setattr(files.os, "replace", full)  # then the disk fills up
    code, lines = batch(FRAMES[:3])
    assert code == 11
    first = lines[0]
    assert first["exit_code"] == 8 and "No space left on device" in first["error"]["message"]
    summary = lines[-1]
    assert summary["not_done"] == 2 and summary["stopped_early"]
    assert not _temporaries(out) and [p.name for p in out.glob("*.labels.pcd")] == ["clutter10.labels.pcd"]


def test_a_name_too_long_for_the_file_system_is_exit_8(tmp_path: Path) -> None:
    src = tmp_path / "src"
    _copy(src, ["n" * 240 + ".pcd"])
    res = clear("segment", src, "--out-dir", tmp_path / "out", "--outputs", "labels", "--json", "--jobs", "1")
    rows, _ = lines_of(res.stdout)
    assert rows[0]["exit_code"] == 8 and "File name too long" in rows[0]["error"]["message"]


def _many_frames() -> list[str]:
    """A batch long enough to be still running after a few seconds: the mOSD learn
    frames, three times over (named file by file: a folder named again is searched
    once, a file named again is done again)."""
    from helpers import shared_path

    return [str(p) for p in sorted(shared_path("mosd/learn").glob("*.pcd"))] * 3


def test_sigterm_stops_a_batch_with_its_summary_and_exit_143(tmp_path: Path) -> None:
    frames = _many_frames()
    proc = start_clear("plan", *frames, "--json", "--jobs", "2", text=True, start_new_session=True)
    # signalled once its first frame's line is out, however loaded the machine is (a fixed
    # sleep could signal a batch still starting, or one with no frame done yet)
    assert proc.stdout is not None
    # the first line read from the pipe's descriptor itself, as communicate() reads the
    # rest: a readline() on the file object reads ahead into its buffer, which
    # communicate() never sees, and a loaded machine's batch had more lines out by then
    # (a document cut in two, its head lost: a stop-59 CI run)
    head = b""
    while b"\n" not in head:
        chunk = os.read(proc.stdout.fileno(), 65536)
        if not chunk:
            break
        head += chunk
    proc.send_signal(signal.SIGTERM)
    rest, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 143, stderr
    rows, summary = lines_of(head.decode("utf-8") + rest)
    assert summary["interrupted"] and "terminated" in stderr and "Traceback" not in stderr
    assert 0 < len(rows) < summary["frames"] == 135 and summary["not_done"] > 0


def _alive_in_group(pgid: int) -> list[str]:
    """Processes of a process group that still run (zombies, which only wait for a
    reaper, are not counted)."""
    ps = subprocess.run(["ps", "-o", "pid=,stat=", "-g", str(pgid)], capture_output=True, text=True).stdout
    return [line.split()[0] for line in ps.splitlines() if line.split() and not line.split()[1].startswith("Z")]


def test_workers_die_with_a_killed_batch(tmp_path: Path) -> None:
    frames = _many_frames()
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    proc = start_clear("plan", *frames, "--json", "--jobs", "2", **quiet, start_new_session=True)
    started = time.time() + 60  # the workers' start-up, on a loaded machine too
    while len(_alive_in_group(proc.pid)) < 3 and time.time() < started:
        time.sleep(0.2)
    assert len(_alive_in_group(proc.pid)) >= 3  # the batch and its two workers (and a tracker)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(10)
    deadline = time.time() + 5
    left = _alive_in_group(proc.pid)
    while left and time.time() < deadline:
        time.sleep(0.1)
        left = _alive_in_group(proc.pid)
    assert not left, f"processes outlived their batch: {left}"


def test_walking_a_folder_skips_fifos_and_link_cycles(tmp_path: Path) -> None:
    d = tmp_path / "d"
    _copy(d, ["a.pcd"])
    os.mkfifo(d / "recorder.pcd")
    (d / "again").symlink_to(".")
    (d / "loop.pcd").symlink_to("loop.pcd")
    res = clear("segment", d, "--json", "--jobs", "1", timeout=120)
    assert res.returncode == 0, res.stderr
    rows, summary = lines_of(res.stdout)
    skipped = {Path(r["source"]).name: r["skipped"] for r in rows if "skipped" in r}
    assert skipped == {
        "recorder.pcd": "a FIFO (named pipe)",
        "again": "a link to a folder already searched",
        "loop.pcd": "a symbolic link loop",
    }
    assert [Path(r["source"]).name for r in rows if "document" in r] == ["a.pcd"]  # found once
    assert summary["skipped"] == 3 and summary["failed"] == 0


def test_a_selection_that_selects_nothing_is_exit_3_with_the_count(tmp_path: Path) -> None:
    res = clear("plan", FIXTURES / "session.mcap", "--every", "1", "--frame", "50", "--json")
    rows, summary = lines_of(res.stdout)
    assert res.returncode == 11 and rows[0]["exit_code"] == 3
    assert "selects no frame" in rows[0]["error"]["message"] and "frame(s)" in rows[0]["error"]["message"]


def _catches(pid: int, signum: int) -> bool:
    """Whether process ``pid`` has a handler for ``signum`` (its SigCgt mask): clear
    holds SIGINT/SIGTERM from its first line, so this says its start-up has begun."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    mask = next(int(line.split()[1], 16) for line in status.splitlines() if line.startswith("SigCgt:"))
    return bool(mask >> (signum - 1) & 1)


def test_a_signal_during_start_up_still_gives_the_summary_and_its_exit_code(tmp_path: Path) -> None:
    if not Path("/proc/self/status").is_file():
        import pytest

        pytest.skip("needs Linux's /proc to see when start-up begins")
    for signum, code, word in ((signal.SIGTERM, 143, "terminated"), (signal.SIGINT, 130, "interrupted")):
        out = tmp_path / f"out-{code}"
        proc = start_clear("plan", FIXTURES, "--json", "--out-dir", out, text=True)
        deadline = time.time() + 10
        # SIGTERM's handler, not SIGINT's: Python catches SIGINT from its own start
        while not _catches(proc.pid, signal.SIGTERM) and time.time() < deadline:
            time.sleep(0.002)
        proc.send_signal(signum)  # while typer, the command and the settings load
        stdout, stderr = proc.communicate(timeout=60)
        assert proc.returncode == code, stderr
        assert "Traceback" not in stderr and "Exception" not in stderr and word in stderr
        rows, summary = lines_of(stdout)
        assert (
            summary["interrupted"]
            and summary["done"] == len(rows)
            and summary["not_done"] == summary["frames"] - len(rows)
        )
        if out.exists():  # no temporaries
            assert [p.name for p in out.iterdir() if p.name.startswith(".")] in ([], [".clear-batch.lock"])


def test_progress_bar_only_where_stderr_may_be_a_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    """`_progress`: nothing (and no rich import) on a pipe; rich's bar, enabled, where rich
    takes the stream for a terminal (FORCE_COLOR makes it one, as a terminal would)."""
    from rich.progress import Progress

    from clearcli import console
    from clearcli.batch import run

    for name in ("FORCE_COLOR", "TTY_COMPATIBLE", "JUPYTER_COLUMNS", "JUPYTER_LINES"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setattr(run, "stderr", console._OnFirstUse(stderr=True))  # not built: a pipe here
    bar = run._progress("plan")
    assert isinstance(bar, run._NoProgress)
    with bar:
        assert bar.add_task("frames", total=3) == 0
        bar.advance(0)
    monkeypatch.setenv("FORCE_COLOR", "1")
    monkeypatch.setattr(run, "stderr", console._OnFirstUse(stderr=True))
    bar = run._progress("plan")
    assert isinstance(bar, Progress) and not bar.disable
