"""One frame's work in a batch (in this process, a worker process or a Ray worker): the
command's task run on the frame, its outputs written whole, then the frame's JSON line
as ``<name>.json`` (the mark that the frame is done).

A `Job` is plain data (picklable): the task's request, built and checked once by the
parent (its settings included), and the frame. `run_job` never raises for anything a
frame can hold: a ClearError becomes the line's error with the exit code a single call
would give; a bug becomes an internal error (code 1), unless CLEAR_DEBUG is set.
"""

from __future__ import annotations

import dataclasses
import errno
import json
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from clearcli import tasks
from clearcli.errors import EXIT_INTERNAL, EXIT_MEMORY, ClearError, OutputError
from clearcli.files import atomic_output, check_output_path
from clearcli.provenance import envelope
from clearcli.tasks.base import OUTPUT_FILES, Outcome, Outputs, Source
from clearcli.tasks.sources import files_read

MARK = "{name}.json"
# Exit codes that are results, not failures: complete (0), nothing can be done (5),
# partial (10).
RESULT_CODES = (0, 5, 10)


@dataclass(frozen=True)
class Job:
    command: str  # a task of clearcli.tasks.TASKS
    request: Any  # that task's Request (outputs left empty: set per frame here)
    source: str
    index: int
    name: str
    made_by: Mapping[str, Any]  # the provenance every line carries
    topic: str | None = None
    out_dir: str | None = None
    outputs: tuple[str, ...] = ()
    force: bool = False
    reads: tuple[str, ...] = ()  # files the run reads besides its frames (--settings)

    def output_path(self, kind: str) -> Path | None:
        if self.out_dir is None or kind not in self.outputs:
            return None
        return Path(self.out_dir) / OUTPUT_FILES[kind].format(name=self.name)

    def mark_path(self) -> Path | None:
        return None if self.out_dir is None else Path(self.out_dir) / MARK.format(name=self.name)


def job_inputs(job: Job) -> tuple[Path, ...]:
    """Every file ``job``'s run reads (clearcli/tasks/sources.files_read): no output of
    it may be one of them, even with --force."""
    return files_read(job.source, getattr(job.request, "settings", None), also=job.reads)


def _check_outputs(job: Job) -> None:
    """Refuse to overwrite a frame's outputs or its mark (without --force): exit 8."""
    paths = [job.output_path(kind) for kind in job.outputs] + [job.mark_path()]
    for p in paths:
        if p is not None:
            check_output_path(p, job.force, job_inputs(job), streams=False)


def _run(job: Job) -> Outcome:
    outputs = Outputs.of(**{kind: job.output_path(kind) for kind in job.outputs})
    request = dataclasses.replace(job.request, outputs=outputs)
    return tasks.load(job.command).run(request, Source(job.source, job.index, job.topic, job.name))


def frame_line(job: Job, outcome: Outcome | None, error: tuple[str, int] | None) -> dict[str, Any]:
    """The frame's JSON line: where it came from and its document, or its error."""
    line: dict[str, Any] = {
        "type": "frame",
        "source": job.source,
        "frame": job.index,
        "name": job.name,
        "clear": dict(job.made_by),
    }
    if outcome is not None:
        line["exit_code"] = outcome.exit_code
        line["document"] = envelope(outcome.schema, outcome.version, outcome.payload, job.made_by)
    else:
        assert error is not None
        line["exit_code"] = error[1]
        line["error"] = {"message": error[0], "exit_code": error[1]}
    return line


def run_job(job: Job) -> dict[str, Any]:
    """One frame, start to end; the line it reports (see `frame_line`)."""
    try:
        _check_outputs(job)
    except OutputError as exc:  # what the user has stays as it is, its mark included
        return frame_line(job, None, (str(exc), exc.exit_code))
    try:
        line = frame_line(job, _run(job), None)
    except ClearError as exc:
        line = frame_line(job, None, (str(exc), exc.exit_code))
        if getattr(exc, "errno", None) == errno.ENOSPC:
            line["_stop"] = "the disk is full"  # no use starting more frames
    except MemoryError:  # this frame is larger than the memory the worker may use: its own failure
        line = frame_line(job, None, ("out of memory: an allocation failed while doing this frame", EXIT_MEMORY))
    except Exception as exc:  # a bug: the batch goes on, the line says so
        if os.environ.get("CLEAR_DEBUG"):
            raise
        line = frame_line(job, None, (f"internal error: {type(exc).__name__}: {exc}", EXIT_INTERNAL))
    mark = job.mark_path()
    if mark is not None and line["exit_code"] in RESULT_CODES:
        # Results only: a frame that failed (bad input, a bug, a failed write) has no
        # mark, so --resume does it again.
        try:
            write_mark(mark, line)
        except ClearError:
            pass
    return line


def write_mark(mark: Path, line: Mapping[str, Any]) -> None:
    """The frame's line as ``<name>.json``, whole or not at all: written last, it says
    that every output of the frame is complete."""
    with atomic_output(mark, "w") as handle:
        handle.write(json.dumps(line, separators=(",", ":"), allow_nan=False) + "\n")
