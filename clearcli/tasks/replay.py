"""`replay`: the whole pipeline over a recorded session, frame by frame, with stable
object ids, execution monitoring and push memory; optionally an annotated log."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from clearcli.settings import Settings

if TYPE_CHECKING:
    from clearcli.errors import PartialLogError
    from clearcli.io.frames import Frame
    from clearcli.replay.report import FrameReport, Summary

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
    from clearcli.errors import PartialLogError
    from clearcli.io.read import iter_frames, sniff
    from clearcli.io.tf import BASE_FRAMES, base_camera_from_log
    from clearcli.pipeline import Pipeline
    from clearcli.replay.session import ReplayOptions, Session, replay

    config = request.settings
    kind = sniff(log)
    log_start_s: float | None = None
    total: int | None = None
    if kind == "mcap":
        from clearcli.io.mcap import choose_topic, read_summary

        summary = read_summary(log)
        topic = choose_topic(summary, topic)
        if summary.start_ns is not None:
            log_start_s = summary.start_ns / 1e9
        total = summary.count(topic) or None
    elif kind in ("rosbag1", "rosbag2"):
        from clearcli.io.rosbag import choose_bag_topic, read_bag_summary

        bag = read_bag_summary(log)
        total = bag.count(choose_bag_topic(bag, topic)) or None
    else:
        total = 1

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
        for frame in iter_frames(log, topic, config.images):
            if first and kind == "mcap" and not config.robot.camera_pose:
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

    def go(sink: Any) -> None:
        nonlocal partial
        try:
            for report in replay(frames(), session, log_start_s):
                on_report(report, session.summary.frames_read, total)
                if sink is not None:
                    sink.write(report, report.frame)
        except PartialLogError as exc:
            partial = exc
        if session.summary.frames_read == 0 and partial is None and total:
            from clearcli.errors import InputError

            # A log whose index counts frames gave none, without a word from its reader:
            # never a replay of nothing that exits 0 (raised here, inside the annotated
            # log's block, which then leaves no output).
            raise InputError(
                f"{log}: none of the {total} frame(s) its index counts on {topic or 'its frame topic'} could be read; "
                "the log is damaged or declares another type than its messages are"
            )

    if request.out is not None:
        from clearcli.replay.annotate import AnnotatedLog

        with AnnotatedLog(request.out, log if kind == "mcap" else None, topic, config) as annotated:
            go(annotated)
    else:
        go(None)
    summary = session.summary
    if summary.frames == 0 and summary.frames_read > 0 and partial is None:
        from clearcli.errors import InputError

        # --from/--to (or --every past the end) that select nothing: a mistake, not a
        # replay of no frames
        raise InputError(
            f"{log}: --from {request.from_s} --to {request.to_s} --every {request.every} select no frame "
            f"of the {summary.frames_read} on {topic or 'its topic'}"
        )
    return summary, partial
