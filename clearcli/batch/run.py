"""A batch: many frames in one call, on every core (`--jobs`) or a Ray cluster (`--ray`).

Output: with ``--json``, one line per frame in input order (``{"type": "frame", "source",
"frame", "name", "exit_code", "document" | "error" | "skipped"}``: the document a single
call prints, or its error with the message and exit code a single call gives, or why an
entry of a searched folder was not read), then one summary line
(``{"type": "summary", ...}``); schema ``clear.batch`` version 1 on every line. Without it,
a progress bar on stderr and a summary table on stdout. A frame that fails is reported
and the batch goes on (``--fail-fast`` stops starting new ones). Partial plans (10) and
"nothing can be done" (5) are results, not failures. Exit code: 0 when no frame failed,
11 when some did (each failed frame's own code is in its line), 130 on Ctrl-C.

``--out-dir DIR`` writes each frame's outputs as ``<name>.<kind>`` (`work.OUTPUT_FILES`),
each whole or not at all, then ``<name>.json`` with the frame's line, last: the mark that
the frame is done. ``--resume`` skips frames with that mark; every other file of a frame
without one, and every temporary a killed run left, is removed before the frame is done
again, so a batch killed at any moment (SIGKILL during a write included) picks up
without redoing or losing a frame.
"""

from __future__ import annotations

import fcntl
import json
import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from clearcli import interrupts, tasks
from clearcli.batch import cluster
from clearcli.batch.pool import WorkerPool
from clearcli.batch.work import MARK, RESULT_CODES, Job, run_job
from clearcli.console import is_pipe, print_table, stderr, stdout
from clearcli.errors import (
    EXIT_BATCH_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_OUTPUT,
    EXIT_TERMINATED,
    InputError,
    OutputError,
    Terminated,
)
from clearcli.files import atomic_output, stream_kind, temporary_target
from clearcli.provenance import envelope, print_line, stamp
from clearcli.settings import READS, settings_to_toml
from clearcli.tasks.base import OUTPUT_FILES
from clearcli.tasks.sources import (
    BadInput,
    FrameRef,
    Skipped,
    check_unique_names,
    expand,
    files_read,
    run_files,
)

BATCH_SCHEMA_VERSION = 1


SETTINGS_FILE = "settings.toml"


@dataclass
class BatchRequest:
    command: str
    inputs: Sequence[Path]
    request: Any  # the task's Request (clearcli.tasks), settings resolved and checked
    made_by: Mapping[str, Any] = field(default_factory=dict)  # provenance (clearcli.provenance.stamp)
    frame: int | None = None
    every: int | None = None
    topic: str | None = None
    out_dir: Path | None = None
    outputs: tuple[str, ...] = ()
    force: bool = False
    resume: bool = False
    jobs: int = 1
    ray: str | None = None
    fail_fast: bool = False
    json_out: bool = False
    wait: bool = False  # --wait: wait for another batch writing in --out-dir instead of refusing
    reads: tuple[str, ...] = ()  # files the run reads besides its frames (--settings): never an output


def parse_outputs(command: str, text: str | None) -> tuple[str, ...]:
    allowed = tasks.load(command).OUTPUTS
    if not text:
        return ()
    kinds = tuple(k.strip() for k in text.split(",") if k.strip())
    bad = [k for k in kinds if k not in allowed]
    if bad:
        raise InputError(
            f"--outputs: {', '.join(bad)} not made by `{command}`; choose from {', '.join(allowed) or 'none'}"
        )
    return kinds


def default_jobs() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


def frame_files(name: str) -> frozenset[str]:
    """Every file name a frame named ``name`` may write in --out-dir, its mark included:
    what it owns, by exact name (a frame ``b`` owns nothing of a frame ``b.1``)."""
    return frozenset([*(f.format(name=name) for f in OUTPUT_FILES.values()), MARK.format(name=name)])


def _temporaries(out_dir: Path) -> dict[str, list[Path]]:
    """Our temporaries in ``out_dir`` (what killed writes left), by the file each was to
    become: listed once per batch, not once per frame."""
    found: dict[str, list[Path]] = {}
    try:
        entries = list(os.scandir(out_dir))
    except OSError:
        return found
    for entry in entries:
        if entry.name.startswith("."):
            target = temporary_target(entry.name)
            if target is not None:
                found.setdefault(target, []).append(Path(entry.path))
    return found


def _remove_temporaries(temps: Mapping[str, list[Path]], name: str) -> None:
    for target in frame_files(name):
        for p in temps.get(target, ()):
            p.unlink(missing_ok=True)


def _clean_stale(
    out_dir: Path, name: str, resume: bool, force: bool, made_by: Mapping[str, Any], temps: Mapping[str, list[Path]]
) -> bool:
    """Before a frame runs: remove the temporaries killed writes left of its own files.
    With ``--resume``, a frame with its mark is done (True) and the outputs of one
    without are an unfinished run's: removed, each by its exact name. With ``--force``,
    the old mark goes first, so that a mark always means complete outputs. Otherwise
    nothing the user has is touched: the frame refuses existing outputs (exit 8)."""
    _remove_temporaries(temps, name)
    mark = out_dir / MARK.format(name=name)
    if resume:
        if mark.is_file() and not (force and _made_otherwise(mark, made_by)):
            return True
        for f in frame_files(name):
            if stream_kind(out_dir / f) is None:  # a device or FIFO of that name is the user's
                (out_dir / f).unlink(missing_ok=True)
    elif force:
        mark.unlink(missing_ok=True)
    return False


def _resolved(paths: Any) -> set[Path]:
    """The real paths (links followed) of ``paths`` that exist."""
    out: set[Path] = set()
    for p in paths:
        try:
            out.add(Path(p).resolve(strict=True))
        except (OSError, RuntimeError):
            pass
    return out


def _inputs_of_run(req: BatchRequest, items: Sequence[Any]) -> set[Path]:
    """The real paths of every file the batch reads: its frames, and what each frame's
    run reads beside it (paired colour, intrinsics, a URDF, --settings)."""
    settings = getattr(req.request, "settings", None)
    found: set[str | Path] = set(run_files(settings, req.reads))
    for it in items:
        if isinstance(it, FrameRef):
            found.update(files_read(it.source, settings))
        elif isinstance(it, (BadInput, Skipped)):
            found.add(it.source)
    return _resolved(found)


def _input_among_outputs(job: Job, inputs: set[Path]) -> Path | None:
    """The first of ``job``'s output files (its mark included) that is an input of the
    run, through links too: another frame's ``a.labels.pcd`` must never be overwritten
    by ``a.pcd``'s labels."""
    if not inputs:
        return None
    for p in [job.output_path(kind) for kind in job.outputs] + [job.mark_path()]:
        if p is not None and p.exists() and p.resolve() in inputs:
            return p
    return None


def _line_for_bad(item: BadInput) -> dict[str, Any]:
    return {
        "type": "frame",
        "source": item.source,
        "frame": item.index,
        "name": item.name,
        "exit_code": item.exit_code,
        "error": {"message": item.message, "exit_code": item.exit_code},
    }


def _public(line: Mapping[str, Any], made_by: Mapping[str, Any]) -> dict[str, Any]:
    return envelope("batch", BATCH_SCHEMA_VERSION, {k: v for k, v in line.items() if not k.startswith("_")}, made_by)


def settings_record(req: BatchRequest) -> str:
    """What ``settings.toml`` in --out-dir holds: who made the results, for which command,
    and the resolved settings that command reads (TOML that --settings reads back)."""
    m = req.made_by
    head = (
        f"# results of `clear {req.command}` made by clear {m.get('version')} ({m.get('source')}); "
        f"settings digest {m.get('settings_digest')}\n"
    )
    settings = getattr(req.request, "settings", None)
    if settings is None:
        return head
    return head + settings_to_toml(settings, READS[req.command])


def _made_otherwise(mark: Path, made_by: Mapping[str, Any]) -> bool:
    try:
        line = json.loads(mark.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return True
    return line.get("clear") != dict(made_by)


LOCK_FILE = ".clear-batch.lock"


def lock_out_dir(out_dir: Path, command: str, wait: bool) -> Any:
    """Take --out-dir for this batch's life: an exclusive `flock` on a file in it, which
    the OS drops when the process ends however it ends (a SIGKILLed batch never blocks a
    resume). A second batch refuses with one line naming the running one (exit 8), or
    with ``wait`` waits for it. Returns the open lock file (keep it open)."""
    path = out_dir / LOCK_FILE
    try:
        fp = open(path, "a+", encoding="utf-8")
    except OSError as exc:
        raise OutputError(f"--out-dir {out_dir}: cannot take the folder's lock {path} ({exc.strerror})") from None
    try:
        fcntl.flock(fp.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        fp.seek(0)
        holder = fp.read().strip() or "another batch"
        if not wait:
            fp.close()
            raise OutputError(
                f"--out-dir {out_dir}: {holder} is writing there; wait for it to end, or pass --wait"
            ) from None
        stderr.print(f"clear: waiting for {holder} to end (--out-dir {out_dir})", markup=False, highlight=False)
        fcntl.flock(fp.fileno(), fcntl.LOCK_EX)
    fp.seek(0)
    fp.truncate()
    fp.write(f"`clear {command}` (pid {os.getpid()}, started {time.strftime('%Y-%m-%d %H:%M:%S')})\n")
    fp.flush()
    return fp


def claim_out_dir(req: BatchRequest) -> None:
    """Make sure the results in --out-dir are all made alike: the folder's
    ``settings.toml`` must match this batch's (same command, version, source and
    settings), else one line, exit 3, before any work. ``--force`` takes the folder over:
    with ``--resume`` it redoes only the frames made otherwise (`_clean_stale`), and keeps
    the rest. A folder with results but no record is treated as made otherwise."""
    assert req.out_dir is not None
    record = settings_record(req)
    path = req.out_dir / SETTINGS_FILE
    try:
        old = path.read_text(encoding="utf-8") if path.is_file() else None
    except (OSError, UnicodeDecodeError):
        old = ""
    has_results = any(req.out_dir.glob("*.json"))
    if (old is not None and old != record) or (old is None and has_results):
        if not req.force:
            what = (
                f"{path} records other settings or another version"
                if old is not None
                else "it holds results with no settings.toml"
            )
            raise InputError(
                f"--out-dir {req.out_dir}: {what} than this `clear {req.command}`; "
                "use another folder, or --force to redo what was made otherwise (with --resume: only those frames)"
            )
    if old != record:
        with atomic_output(path, "w") as handle:
            handle.write(record)


def _short(line: Mapping[str, Any]) -> str:
    """One cell for people: the frame's result or its error."""
    if "error" in line:
        return line["error"]["message"]
    if "skipped" in line:
        return f"skipped: {line['skipped']}"
    doc = line.get("document", {})
    schema = doc.get("schema", "")
    if schema == "clear.plan":
        return f"{doc['status']}: {len(doc['actions'])} actions, {len(doc['goal'])} removed, {len(doc['left'])} left"
    if schema == "clear.segmentation":
        return f"{len(doc['objects'])} objects"
    if schema == "clear.predicates":
        return f"{len(doc['objects'])} objects, {len(doc['facts'])} facts"
    if schema == "clear.info":
        fr = doc.get("frame")
        if not fr:
            return f"{doc.get('format', '?')}: no point-cloud frame"
        return f"{doc.get('format', '?')}: {fr['points']} points, {fr['finite_points']} finite"
    if schema == "clear.evaluate.frame":
        return f"F1 {doc['f1']:.3f}, {doc['n_true']} true / {doc['n_pred']} found"
    return ""


def run_batch(
    req: BatchRequest,
    on_line: Callable[[dict[str, Any]], None] | None = None,
    extra_summary: Callable[[Sequence[dict[str, Any]]], dict[str, Any]] | None = None,
    render: Callable[[Sequence[dict[str, Any]], Mapping[str, Any]], None] | None = None,
) -> int:
    """Run the batch; print lines (or the progress bar and table); the exit code.
    ``extra_summary`` adds keys to the summary from every frame's line; ``render``
    replaces the summary table for people."""
    t0 = time.perf_counter()
    lock = None  # the --out-dir lock, held until the batch ends
    # What the summary reports, however early a signal stops the batch.
    items: list[Any] = []
    lines: list[dict[str, Any] | None] = []
    job_at: list[int] = []
    skipped = 0
    emitted = 0
    failed = 0
    stopped = False
    counts: dict[int, int] = {}
    rows: list[dict[str, Any]] = []
    ray_init_s = None

    def emit_ready(gaps: bool = False) -> None:
        """Print the lines whose turn has come (input order); with ``gaps`` (the batch
        was interrupted) every finished line, past the frames that did not finish."""
        nonlocal emitted, failed, stopped
        while emitted < len(lines) and (lines[emitted] is not None or gaps):
            line = lines[emitted]
            emitted += 1
            if line is None:
                continue
            code = int(line["exit_code"])
            counts[code] = counts.get(code, 0) + 1
            if code not in RESULT_CODES:
                failed += 1
                if req.fail_fast or line.get("_stop"):
                    stopped = True
            if on_line is not None:
                on_line(line)
            if req.json_out:
                print_line(json.dumps(_public(line, req.made_by), separators=(",", ":"), allow_nan=False))
            else:
                rows.append(line)

    backend = "in-process"
    interrupted = terminated = False
    progress = _progress(req.command)
    try:
        interrupts.release()  # a Ctrl-C/SIGTERM held since start-up stops here, with a summary
        cfg = getattr(req.request, "settings", None)
        items = expand(
            req.inputs,
            frame=req.frame,
            every=req.every,
            topic=req.topic,
            images=cfg.images if cfg is not None else None,
        )
        if req.out_dir is not None:
            check_unique_names(items)
            if req.out_dir.exists() and not req.out_dir.is_dir():
                raise InputError(f"--out-dir {req.out_dir}: exists and is not a folder")
            try:
                req.out_dir.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise OutputError(f"--out-dir {req.out_dir}: cannot make the folder ({exc.strerror})") from None
            lock = lock_out_dir(req.out_dir, req.command, req.wait)
            claim_out_dir(req)
        elif req.outputs or req.resume:
            raise InputError("--outputs and --resume need --out-dir DIR")

        lines = [None] * len(items)
        temps = _temporaries(req.out_dir) if req.out_dir is not None else {}
        inputs_of_run = _inputs_of_run(req, items) if req.out_dir is not None else set()
        jobs: list[Job] = []
        for k, it in enumerate(items):
            if isinstance(it, BadInput):
                lines[k] = _line_for_bad(it)
                continue
            if isinstance(it, Skipped):
                lines[k] = {
                    "type": "frame",
                    "source": it.source,
                    "frame": 0,
                    "name": "",
                    "exit_code": 0,
                    "skipped": it.reason,
                }
                continue
            assert isinstance(it, FrameRef)
            job = Job(
                req.command,
                req.request,
                it.source,
                it.index,
                it.name,
                dict(req.made_by),
                req.topic,
                None if req.out_dir is None else str(req.out_dir),
                req.outputs,
                req.force,
                req.reads,
            )
            # before anything in --out-dir is removed (--force, --resume): a file this
            # batch reads that one of the frame's outputs would name is never touched
            clash = _input_among_outputs(job, inputs_of_run)
            if clash is not None:
                lines[k] = _line_for_bad(
                    BadInput(
                        it.source,
                        f"{clash}: is an input of this batch; refusing to overwrite it (even with --force)",
                        EXIT_OUTPUT,
                        it.index,
                        it.name,
                    )
                )
                continue
            if req.out_dir is not None:
                mark = req.out_dir / MARK.format(name=it.name)
                if _clean_stale(req.out_dir, it.name, req.resume, req.force, req.made_by, temps):
                    try:
                        lines[k] = {**json.loads(mark.read_text(encoding="utf-8")), "_resumed": True}
                        skipped += 1
                        continue
                    except (OSError, ValueError):
                        mark.unlink(missing_ok=True)  # unreadable: do the frame again
            job_at.append(k)
            jobs.append(job)
        with progress:
            task = progress.add_task("frames", total=len(jobs))
            emit_ready()
            if jobs:
                if req.ray is not None:
                    ray_init_s = cluster.connect(req.ray)
                    backend = f"ray ({req.ray})"
                    results = cluster.run(jobs, stop=lambda: stopped)
                elif req.jobs > 1 and len(jobs) > 1:
                    backend = f"{min(req.jobs, len(jobs))} worker processes"
                    results = WorkerPool(req.jobs).run(jobs, stop=lambda: stopped)
                else:
                    results = ((i, run_job(j)) for i, j in enumerate(jobs) if not stopped)
                try:
                    for i, line in results:
                        lines[job_at[i]] = line
                        progress.advance(task)
                        emit_ready()
                finally:
                    close = getattr(results, "close", None)
                    if close is not None:
                        close()
    except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM (Terminated)
        interrupted = True
        terminated = isinstance(exc, Terminated)
        emit_ready(gaps=True)
        if req.out_dir is not None:  # temporaries of writes cut short by the stop
            left = _temporaries(req.out_dir)
            for it in items:
                if isinstance(it, FrameRef):
                    _remove_temporaries(left, it.name)
    n_skipped = sum(1 for it in items if isinstance(it, Skipped))
    done = sum(1 for ln in lines if ln is not None and not ln.get("_resumed") and "skipped" not in ln)
    not_done = len(items) - done - skipped - n_skipped  # a stop during the set-up leaves frames never looked at
    summary = {
        "type": "summary",
        "frames": len(items),
        "done": done,
        "resumed": skipped,
        "not_done": not_done,
        "skipped": n_skipped,
        "failed": failed,
        "exit_codes": {str(k): v for k, v in sorted(counts.items())},
        "interrupted": interrupted,
        "stopped_early": bool(stopped and not_done),
        "backend": backend,
        "ray_init_s": None if ray_init_s is None else round(ray_init_s, 3),
        "wall_s": round(time.perf_counter() - t0, 3),
    }
    if extra_summary is not None:
        summary.update(extra_summary([ln for ln in lines if ln is not None]))
    if req.json_out:
        print_line(json.dumps(_public(summary, req.made_by), separators=(",", ":")))
    elif render is not None:
        render(rows, summary)
    else:
        _print_table(rows, summary, stdout)
    if lock is not None:
        lock.close()
    if interrupted:
        what = "terminated" if terminated else "interrupted"
        stderr.print(f"clear: {what}; the summary covers the frames that finished", markup=False)
        interrupts.told()
        return EXIT_TERMINATED if terminated else EXIT_INTERRUPTED
    return EXIT_OK if failed == 0 else EXIT_BATCH_FAILED


def run_command_batch(
    command: str,
    inputs: Sequence[Path],
    request: Any,
    *,
    outputs: str | None = None,
    jobs: int | None = None,
    on_line: Callable[[dict[str, Any]], None] | None = None,
    extra_summary: Callable[[Sequence[dict[str, Any]]], dict[str, Any]] | None = None,
    render: Callable[[Sequence[dict[str, Any]], Mapping[str, Any]], None] | None = None,
    **fields: Any,
) -> int:
    """A subcommand's batch from its flags: ``outputs`` as given to --outputs, ``jobs``
    None for every core; the other `BatchRequest` fields by name."""
    made_by = stamp(getattr(request, "settings", None), command)
    req = BatchRequest(
        command,
        inputs,
        request,
        made_by,
        outputs=parse_outputs(command, outputs),
        jobs=jobs or default_jobs(),
        **fields,
    )
    return run_batch(req, on_line=on_line, extra_summary=extra_summary, render=render)


class _NoProgress:
    """What run_batch asks of rich's Progress, doing nothing: the bar where stderr is a
    pipe or a file, where rich would draw none."""

    def __enter__(self) -> _NoProgress:
        return self

    def __exit__(self, *exc: Any) -> None:
        return None

    def add_task(self, description: str, total: float | None = None) -> int:
        return 0

    def advance(self, task: int) -> None:
        return None


def _progress(command: str) -> Any:
    """The progress bar on stderr: rich's when stderr may be a terminal, else `_NoProgress`
    (rich.progress and rich.console were ~40 ms of a batch's parent before its workers
    started, for a bar that rich disables on a pipe; issue 39)."""
    if is_pipe(stderr):
        return _NoProgress()
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn  # noqa: PLC0415

    return Progress(
        TextColumn(f"{command}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeRemainingColumn(),
        console=stderr,
        transient=True,
        disable=not stderr.is_terminal,
    )


def _print_table(rows: Sequence[Mapping[str, Any]], summary: Mapping[str, Any], out: Any) -> None:
    # drawn without rich where `print_table` can (a pipe, a file): the same characters
    cells = [[str(line["source"]), str(line["frame"]), str(line["exit_code"]), _short(line)] for line in rows]
    print_table(out, ("source", "frame", "exit", "result"), cells)
    codes = ", ".join(f"exit {k}: {v}" for k, v in summary["exit_codes"].items())
    out.print(
        f"{summary['frames']} frames: {summary['done']} done, {summary['resumed']} resumed, "
        f"{summary['failed']} failed, {summary['not_done']} not done, {summary['skipped']} skipped ({codes}); "
        f"{summary['backend']}, "
        f"{summary['wall_s']:.1f} s",
        markup=False,
        highlight=False,
    )
