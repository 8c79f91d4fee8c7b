"""clearcli/limits.py and exit 12: a memory limit too small to start is refused at once,
in one line (under it SciPy's OpenBLAS retried its buffer for ever: a process that never
ended and ignored SIGTERM); a MemoryError while working is exit 12, in a batch that
frame's own code."""

from __future__ import annotations

import resource
import subprocess
import sys
from pathlib import Path

import pytest

from clearcli import limits
from clearcli.errors import EXIT_CODES, EXIT_MEMORY

REPO = Path(__file__).resolve().parents[1]
FIXTURE = REPO / "fixtures" / "clutter10.pcd"


def _limited(bytes_: int):  # type: ignore[no-untyped-def]
    def set_limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (bytes_, resource.getrlimit(resource.RLIMIT_AS)[1]))

    return set_limit


def test_exit_12_is_documented() -> None:
    assert EXIT_MEMORY == 12 and "memory" in EXIT_CODES[12]
    assert "| 12 |" in (REPO / "docs" / "exit-codes.md").read_text()


def test_a_limit_under_the_floor_is_refused_at_once_in_one_line() -> None:
    # 200 MB: before this check, `clear plan` hung for ever in OpenBLAS's start-up
    res = subprocess.run(
        [sys.executable, "-m", "clearcli.cli", "plan", str(FIXTURE), "--json"],
        capture_output=True,
        text=True,
        timeout=60,
        preexec_fn=_limited(200 * 2**20),
    )
    assert res.returncode == EXIT_MEMORY, res.stderr
    assert res.stdout == "" and res.stderr.count("\n") == 1
    assert res.stderr.startswith("clear: error: the process may use only 200 MiB") and "384 MiB" in res.stderr


def test_a_limit_over_the_floor_lets_clear_start() -> None:
    res = subprocess.run(
        [sys.executable, "-m", "clearcli.cli", "segment", str(FIXTURE), "--json"],
        capture_output=True,
        text=True,
        timeout=120,
        preexec_fn=_limited(limits.MIN_MEMORY_LIMIT_BYTES),
    )
    assert res.returncode == 0, res.stderr


def test_the_smaller_of_the_two_limits_counts(monkeypatch: pytest.MonkeyPatch) -> None:
    inf = resource.RLIM_INFINITY
    given = {resource.RLIMIT_AS: (inf, inf), resource.RLIMIT_DATA: (inf, inf)}
    monkeypatch.setattr(limits.resource, "getrlimit", lambda which: given[which])
    assert limits.memory_limit_bytes() is None and limits.too_little_memory() is None
    given[resource.RLIMIT_AS] = (2**40, inf)
    given[resource.RLIMIT_DATA] = (limits.MIN_MEMORY_LIMIT_BYTES - 1, inf)
    assert limits.memory_limit_bytes() == limits.MIN_MEMORY_LIMIT_BYTES - 1
    assert "ulimit" in (limits.too_little_memory() or "")
    given[resource.RLIMIT_DATA] = (limits.MIN_MEMORY_LIMIT_BYTES, inf)
    assert limits.too_little_memory() is None


def test_a_memory_error_while_working_is_exit_12_in_one_line(monkeypatch: pytest.MonkeyPatch) -> None:
    from helpers import harness as H

    from clearcli.tasks import segment as task

    def no_memory(*args: object, **kwargs: object) -> None:
        raise MemoryError

    monkeypatch.setattr(task, "run", no_memory)
    res = H.run_inprocess(["segment", str(FIXTURE)])
    assert res.code == EXIT_MEMORY and res.stdout == ""
    assert res.stderr.startswith("clear: error: out of memory") and res.stderr.count("\n") == 1


def test_a_memory_error_in_a_batch_is_that_frames_exit_12(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from clearcli.batch import work
    from clearcli.batch.run import BatchRequest, run_batch
    from clearcli.settings import Settings
    from clearcli.tasks import segment as task

    real = work._run

    def short_of_memory(job: work.Job):  # type: ignore[no-untyped-def]
        if job.source.endswith("clutter10.pcd"):
            raise MemoryError
        return real(job)

    monkeypatch.setattr(work, "_run", short_of_memory)
    frames = [FIXTURE, REPO / "fixtures" / "isolated_box.pcd"]
    lines: list[dict] = []
    code = run_batch(
        BatchRequest("segment", frames, task.Request(Settings()), jobs=1),
        on_line=lines.append,
        render=lambda rows, summary: None,
    )
    assert code == 11
    by_source = {Path(line["source"]).name: line for line in lines}
    assert by_source["clutter10.pcd"]["exit_code"] == EXIT_MEMORY
    assert "out of memory" in by_source["clutter10.pcd"]["error"]["message"]
    assert by_source["isolated_box.pcd"]["exit_code"] == 0
