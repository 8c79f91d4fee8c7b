"""`replay`: the whole pipeline over a recorded session, frame by frame, with stable
object ids, execution monitoring and push memory; optionally an annotated log.

A task, but of a session, not of one frame: ``run(request, log, topic, on_report, note)``
replays a whole log, reports each frame as it is done (``on_report``: the command prints
a JSON line or moves its progress bar) and gives back the session's `Summary` and the
error that ended a damaged log early. It is never batched: no `Source`, no `Outcome`.
What the log says of itself before its frames (its frame topic, start, frame count,
transforms, whether an annotated log copies it) is the input format's to say
(clearcli/io/inputs.py `log_index`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from clearcli.errors import InputError, PartialLogError
from clearcli.io import read as io_read  # through the module: tests replace io_read.iter_frames
from clearcli.io.frames import Frame
from clearcli.io.inputs import log_index
from clearcli.io.tf import BASE_FRAMES, base_camera_from_log
from clearcli.pipeline import Pipeline
from clearcli.replay.annotate import AnnotatedLog
from clearcli.replay.report import FrameReport, Summary
from clearcli.replay.session import ReplayOptions, Session, replay
from clearcli.settings import Settings

SCHEMA, VERSION = "replay", 1


@dataclass(frozen=True)
class Request:
    settings: Settings
    every: int = 1  # every N-th frame of the log
    from_s: float | None = None  # seconds from the start of the log
    to_s: float | None = None
    fail_fast: bool = False
    base_frame: str | None = None  # the log's name of the robot base frame (its /tf_static)
    out: Path | None = None  # an annotated MCAP to write


def run(
    request: Request,
    log: Path,
    topic: str | None,
    on_report: Callable[[FrameReport, int, int | None], None],
    note: Callable[[str], None],
) -> tuple[Summary, PartialLogError | None]:
    """Replay ``log``; ``on_report`` sees each frame's report (with frames read so far
    and the topic's frame count when known), ``note`` gets remarks for people. Returns
    the summary, and the error that ended a damaged log early (the caller raises it
    after printing)."""
    config = request.settings
    facts = log_index(log, topic)
    topic, total = facts.topic, facts.total

    pipeline = Pipeline(config)
    options = ReplayOptions(
        every=request.every,
        from_s=request.from_s,
        to_s=request.to_s,
        fail_fast=request.fail_fast,
        push_memory=config.replay.push_memory,
        stop_when_cleared=config.replay.stop_when_cleared,
        tracking=config.tracking,
        memory=config.memory,
    )
    session = Session(pipeline, options)
    # the log's name for the robot base: --base-frame, else the resolved arm's base frame
    # first (panda_link0, base_link, wam_link_base), then the names WAM setups use
    own = pipeline.robot.profile.base_frame
    bases = (request.base_frame,) if request.base_frame else (own, *(b for b in BASE_FRAMES if b != own))

    def frames() -> Iterator[Frame]:
        first = True
        for frame in io_read.iter_frames(log, topic, config.images):
            if first and facts.transforms and not config.robot.camera_pose:
                T, base = base_camera_from_log(log, frame.frame_id, bases)
                if T is not None:
                    pipeline.T_base_camera = T
                    note(f"robot base: {base} -> {frame.frame_id} from the log's transforms")
                elif request.base_frame:
                    note(
                        f"robot base: no transform {request.base_frame} -> {frame.frame_id} in the log; "
                        "placing the robot by the plan stage's rules"
                    )
            first = False
            yield frame

    partial: PartialLogError | None = None

    def go(sink: AnnotatedLog | None) -> None:
        nonlocal partial
        try:
            for report in replay(frames(), session, facts.start_s):
                on_report(report, session.summary.frames_read, total)
                if sink is not None:
                    assert report.frame is not None  # a session's reports carry their frame
                    sink.write(report, report.frame)
        except PartialLogError as exc:
            partial = exc
        if session.summary.frames_read == 0 and partial is None and total:
            # A log whose index counts frames gave none, without a word from its reader:
            # never a replay of nothing that exits 0 (raised here, inside the annotated
            # log's block, which then leaves no output).
            raise InputError(
                f"{log}: none of the {total} frame(s) its index counts on {topic or 'its frame topic'} could be read; "
                "the log is damaged or declares another type than its messages are"
            )

    if request.out is not None:
        with AnnotatedLog(request.out, log if facts.copied else None, topic, config) as annotated:
            go(annotated)
    else:
        go(None)
    summary = session.summary
    if summary.frames == 0 and summary.frames_read > 0 and partial is None:
        # --from/--to (or --every past the end) that select nothing: a mistake, not a
        # replay of no frames
        raise InputError(
            f"{log}: --from {request.from_s} --to {request.to_s} --every {request.every} select no frame "
            f"of the {summary.frames_read} on {topic or 'its topic'}"
        )
    return summary, partial
