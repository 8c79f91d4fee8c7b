"""One frame's work for each frame command, as a batch runs it (in this process, a
worker process or a Ray worker): read, compute, write the chosen outputs whole, then the
frame's JSON line as ``<name>.json`` (the mark that the frame is done).

A `Job` is plain data (picklable); `run_job` never raises for anything a frame can hold:
a ClearError becomes the line's error with the exit code a single call would give; a
bug becomes an internal error (code 1), unless CLEAR_DEBUG is set.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

# Output kinds per command, and the file each is written to in --out-dir.
OUTPUT_FILES: dict[str, str] = {
    "labels": "{name}.labels.pcd",
    "problem": "{name}.problem.pddl",
    "domain": "{name}.domain.pddl",
    "plan": "{name}.plan",
    "png": "{name}.png",
}
OUTPUT_KINDS: dict[str, tuple[str, ...]] = {
    "info": (),
    "segment": ("labels", "png"),
    "predicates": ("problem", "png"),
    "plan": ("problem", "domain", "plan", "png"),
    "evaluate": ("labels",),
}
MARK = "{name}.json"


@dataclass(frozen=True)
class Job:
    command: str  # "info" | "segment" | "predicates" | "plan" | "evaluate"
    source: str
    index: int
    name: str
    options: Mapping[str, Any] = field(default_factory=dict)  # the command's options, plain values
    out_dir: str | None = None
    outputs: tuple[str, ...] = ()
    force: bool = False

    def output_path(self, kind: str) -> Path | None:
        if self.out_dir is None or kind not in self.outputs:
            return None
        return Path(self.out_dir) / OUTPUT_FILES[kind].format(name=self.name)

    def mark_path(self) -> Path | None:
        return None if self.out_dir is None else Path(self.out_dir) / MARK.format(name=self.name)


@dataclass
class Outcome:
    """What one frame gave: its document (schema, version, payload) and exit code."""

    schema: str
    version: int
    payload: dict[str, Any]
    exit_code: int = 0


_SETTINGS_CACHE: dict[tuple[str | None, str], Any] = {}


def settings_for(options: Mapping[str, Any]) -> Any:
    """Settings from the job's file and flag overrides, parsed once per worker."""
    from clearcli.settings import load_settings, settings_from_dict

    path = options.get("settings")
    overrides = options.get("overrides") or {}
    key = (path, json.dumps(overrides, sort_keys=True))
    got = _SETTINGS_CACHE.get(key)
    if got is None:
        base = load_settings(Path(path) if path else None)
        given = {sec: {k: v for k, v in vals.items() if v is not None} for sec, vals in overrides.items()}
        given = {sec: vals for sec, vals in given.items() if vals}
        got = _SETTINGS_CACHE[key] = settings_from_dict(given, base=base) if given else base
    return got


def _check_outputs(job: Job) -> None:
    """Refuse to overwrite a frame's outputs or its mark (without --force): exit 8."""
    from clearcli.io.files import check_output_path

    paths = [job.output_path(kind) for kind in job.outputs] + [job.mark_path()]
    for p in paths:
        if p is not None:
            check_output_path(p, job.force, (Path(job.source),))


def _info(job: Job) -> Outcome:
    from clearcli.commands.info import describe_file

    from clearcli.commands.info import log_part

    info = describe_file(Path(job.source), job.options.get("topic"), job.index)
    log = log_part(info)
    return Outcome("info", 1, info, 0 if log is None or log["complete"] else 9)


def _segment(job: Job) -> Outcome:
    from clearcli.commands.segment import segmentation_payload
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment

    cfg = settings_for(job.options)
    frame = read_frame(Path(job.source), job.options.get("topic"), job.index)
    seg = segment(frame, cfg.segment)
    labels = job.output_path("labels")
    if labels is not None:
        from clearcli.io.pcd import write_pcd

        write_pcd(labels, frame, seg.labels())
    png = job.output_path("png")
    if png is not None:
        from clearcli.io.files import atomic_path
        from clearcli.render.segment_png import render_segmentation

        with atomic_path(png) as tmp:
            render_segmentation(tmp, frame, seg)
    return Outcome("segmentation", 1, segmentation_payload(seg))


def _predicates(job: Job) -> Outcome:
    from clearcli.commands.predicates import predicates_payload
    from clearcli.io.read import read_frame
    from clearcli.predicates.state_builder import compute_state

    cfg = settings_for(job.options)
    frame = read_frame(Path(job.source), job.options.get("topic"), job.index)
    if job.options.get("ground_truth"):
        from clearcli.commands.predicates import ground_truth_segmentation

        seg = ground_truth_segmentation(frame, Path(job.source))
    else:
        from clearcli.perception.segment import segment

        seg = segment(frame, cfg.segment)
    state = compute_state(frame, seg, cfg)
    problem = job.output_path("problem")
    if problem is not None:
        from clearcli.io.files import atomic_output
        from clearcli.planning.pddl import write_problem

        text = write_problem(state)
        with atomic_output(problem, "w") as handle:
            handle.write(text)
    png = job.output_path("png")
    if png is not None:
        from clearcli.io.files import atomic_path
        from clearcli.render.predicates_png import render_predicates_png

        with atomic_path(png) as tmp:
            render_predicates_png(state, tmp, title=job.source)
    return Outcome("predicates", 1, predicates_payload(state))


def _plan(job: Job) -> Outcome:
    from clearcli.commands.plan import plan_frame

    doc, code = plan_frame(
        Path(job.source),
        job.index,
        settings_for(job.options),
        topic=job.options.get("topic"),
        camera_pose=job.options.get("camera_pose"),
        first_only=bool(job.options.get("first_only")),
        problem=job.output_path("problem"),
        domain=job.output_path("domain"),
        output=job.output_path("plan"),
        png=job.output_path("png"),
    )
    from clearcli.commands.plan import PLAN_SCHEMA_VERSION

    return Outcome("plan", PLAN_SCHEMA_VERSION, doc, code)


def _evaluate(job: Job) -> Outcome:
    from clearcli.evaluate.dataset import evaluate_frame

    payload = evaluate_frame(job, settings_for(job.options))
    return Outcome("evaluate.frame", 1, payload)


WORK: dict[str, Callable[[Job], Outcome]] = {
    "info": _info,
    "segment": _segment,
    "predicates": _predicates,
    "plan": _plan,
    "evaluate": _evaluate,
}


def frame_line(job: Job, outcome: Outcome | None, error: tuple[str, int] | None) -> dict[str, Any]:
    """The frame's JSON line: where it came from and its document, or its error."""
    line: dict[str, Any] = {"type": "frame", "source": job.source, "frame": job.index, "name": job.name}
    if outcome is not None:
        line["exit_code"] = outcome.exit_code
        line["document"] = {"schema": f"clear.{outcome.schema}", "version": outcome.version, **outcome.payload}
    else:
        assert error is not None
        line["exit_code"] = error[1]
        line["error"] = {"message": error[0], "exit_code": error[1]}
    return line


def run_job(job: Job) -> dict[str, Any]:
    """One frame, start to end; the line it reports (see `frame_line`)."""
    from clearcli.errors import EXIT_INTERNAL, EXIT_OUTPUT, ClearError, OutputError

    try:
        _check_outputs(job)
    except OutputError as exc:  # what the user has stays as it is, its mark included
        return frame_line(job, None, (str(exc), exc.exit_code))
    try:
        outcome = WORK[job.command](job)
        line = frame_line(job, outcome, None)
    except ClearError as exc:
        line = frame_line(job, None, (str(exc), exc.exit_code))
    except Exception as exc:  # a bug: the batch goes on, the line says so
        if os.environ.get("CLEAR_DEBUG"):
            raise
        line = frame_line(job, None, (f"internal error: {type(exc).__name__}: {exc}", EXIT_INTERNAL))
    mark = job.mark_path()
    if mark is not None and line["exit_code"] not in (EXIT_INTERNAL, EXIT_OUTPUT):
        # (a bug or a failed write may be passing: without a mark --resume does the
        # frame again)
        try:
            write_mark(mark, line)
        except ClearError:
            pass
    return line


def write_mark(mark: Path, line: Mapping[str, Any]) -> None:
    """The frame's line as ``<name>.json``, whole or not at all: written last, it says
    that every output of the frame is complete."""
    from clearcli.io.files import atomic_output

    with atomic_output(mark, "w") as handle:
        handle.write(json.dumps(line, separators=(",", ":"), allow_nan=False) + "\n")
