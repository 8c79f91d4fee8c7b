"""The annotated log: the replayed frames plus what the planner thought of each, for Foxglove.

Channels (all JSON-encoded, schemas in jsonschema encoding, which Foxglove reads):
  <input topic>        the input frame, copied byte for byte from the input MCAP (its own
                       schema and encoding); a PCD input is written as `foxglove.PointCloud`
  /clear/scene         `foxglove.SceneUpdate`: per object its hull (or its box when the
                       predicates did not run) coloured by its stable id, a text label,
                       its push arrows (the planned one thick), and the gripper at the
                       next action's pose
  /clear/predicates    the facts of the frame's state, object names replaced by ids
  /clear/plan          the plan, the same dict as the `plan` of the frame's JSON line

Each scene update first deletes everything of the previous frame. The file is written
to a temporary file beside the output and moved into place only when complete.
"""

from __future__ import annotations

import contextlib
from collections.abc import Generator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from clearcli.errors import OutputError
from clearcli.files import atomic_output
from clearcli.io.mcap import raw_messages, read_summary
from clearcli.replay.foxglove import (
    PLAN_JSONSCHEMA,
    PLAN_TOPIC,
    POINTCLOUD_JSONSCHEMA,
    POINTCLOUD_SCHEMA,
    PREDICATES_JSONSCHEMA,
    PREDICATES_TOPIC,
    SCENE_SCHEMA,
    SCENE_TOPIC,
    SCENE_UPDATE_JSONSCHEMA,
    dumps,
    pointcloud_json,
    predicates_json,
    scene_update,
)

if TYPE_CHECKING:
    from clearcli.io.frames import Frame
    from clearcli.replay.report import FrameReport
    from clearcli.settings import Settings


class AnnotatedLog:
    """Writes the annotated MCAP, frame by frame; use as a context manager.

    ``source`` is the input MCAP (its frames are copied raw from ``topic``), or None to
    write frames as `foxglove.PointCloud` JSON.
    """

    def __init__(
        self,
        out_path: Path,
        source: Path | None,
        topic: str | None,
        settings: Settings | None = None,
    ) -> None:
        self.out_path = Path(out_path)
        self.source = Path(source) if source is not None else None
        self.topic = topic or "/clear/points"
        self.settings = settings
        self._stack = contextlib.ExitStack()
        self._writer: Any = None
        self._raw: Generator[tuple[Any, Any, Any], None, None] | None = None
        self._raw_channel: int | None = None
        self._raw_next = 0  # position on the topic of the next raw message
        self._json_cloud_channel: int | None = None
        self._channels: dict[str, int] = {}
        self._sequence = 0
        self.frames_written = 0

    def __enter__(self) -> AnnotatedLog:
        from mcap.writer import CompressionType, Writer

        try:
            handle = self._stack.enter_context(atomic_output(self.out_path))
            writer = Writer(handle, compression=CompressionType.ZSTD)
            writer.start(profile="", library="clear")
            self._writer = writer
            for topic, title, schema in (
                (SCENE_TOPIC, SCENE_SCHEMA, SCENE_UPDATE_JSONSCHEMA),
                (PREDICATES_TOPIC, "clear.Predicates", PREDICATES_JSONSCHEMA),
                (PLAN_TOPIC, "clear.Plan", PLAN_JSONSCHEMA),
            ):
                schema_id = writer.register_schema(name=title, encoding="jsonschema", data=dumps(schema))
                self._channels[topic] = writer.register_channel(
                    topic=topic, message_encoding="json", schema_id=schema_id
                )
            if self.source is not None:
                self._raw = self._stack.enter_context(contextlib.closing(_raw_iter(self.source, self.topic)))
        except BaseException:
            self._stack.__exit__(None, None, None)
            raise
        return self

    def __exit__(self, exc_type: Any, exc: Any, tb: Any) -> None:
        try:
            if exc_type is None:
                self._writer.finish()
        finally:
            # an exception here leaves no output: atomic_output removes the temporary file
            if exc_type is None:
                self._stack.__exit__(None, None, None)
            else:
                self._stack.__exit__(exc_type, exc, tb)

    def _write(self, channel_id: int, stamp_ns: int, data: bytes) -> None:
        self._writer.add_message(
            channel_id=channel_id, log_time=stamp_ns, publish_time=stamp_ns, data=data, sequence=self._sequence
        )
        self._sequence += 1

    def _copy_frame(self, index: int) -> int | None:
        """Copy the input message of frame ``index`` (its position on the topic: the
        reader and this iterator walk the topic in the same order); its log time, or
        None when the input has no such message."""
        if self._raw is None or index < self._raw_next:
            return None
        for schema, channel, message in self._raw:
            position = self._raw_next
            self._raw_next += 1
            if position < index:
                continue
            if self._raw_channel is None:
                schema_id = 0
                if schema is not None:
                    schema_id = self._writer.register_schema(
                        name=schema.name, encoding=schema.encoding, data=schema.data
                    )
                self._raw_channel = self._writer.register_channel(
                    topic=channel.topic,
                    message_encoding=channel.message_encoding,
                    schema_id=schema_id,
                    metadata=dict(channel.metadata or {}),
                )
            self._writer.add_message(
                channel_id=self._raw_channel,
                log_time=int(message.log_time),
                publish_time=int(message.publish_time),
                data=message.data,
                sequence=self._sequence,
            )
            self._sequence += 1
            return int(message.log_time)
        return None

    def write(self, report: FrameReport, frame: Frame) -> None:
        """The frame (copied from the input when it is an MCAP) and its annotations, all
        at the input message's log time."""
        try:
            log_ns = self._copy_frame(report.index)
            if log_ns is None:
                log_ns = int(round(max(frame.stamp_s, 0.0) * 1e9))
                if self._json_cloud_channel is None:
                    schema_id = self._writer.register_schema(
                        name=POINTCLOUD_SCHEMA, encoding="jsonschema", data=dumps(POINTCLOUD_JSONSCHEMA)
                    )
                    topic = self.topic if self._raw_channel is None else self.topic + "/annotated_copy"
                    self._json_cloud_channel = self._writer.register_channel(
                        topic=topic, message_encoding="json", schema_id=schema_id
                    )
                self._write(self._json_cloud_channel, log_ns, dumps(pointcloud_json(frame)))
            frame_id = frame.frame_id or "camera"
            self._write(self._channels[SCENE_TOPIC], log_ns, dumps(scene_update(report, frame_id, self.settings)))
            predicates = predicates_json(report)
            if predicates is not None:
                self._write(self._channels[PREDICATES_TOPIC], log_ns, dumps(predicates))
            plan = report.plan_json()
            if plan is not None:
                self._write(self._channels[PLAN_TOPIC], log_ns, dumps(plan))
        except OSError as exc:
            raise OutputError(f"{self.out_path}: cannot write ({exc.strerror or exc})") from None
        self.frames_written += 1


def _raw_iter(path: Path, topic: str) -> Generator[tuple[Any, Any, Any], None, None]:
    """(schema, channel, message) of ``topic`` in the input log, in the reader's order;
    ends quietly where the log is damaged (the replay reports that itself)."""
    summary = read_summary(path)
    iterator = raw_messages(path, summary, topic)
    try:
        while True:
            try:
                item = next(iterator)
            except StopIteration:
                return
            except Exception:  # damage past the complete frames: the replay reports it
                return
            yield item
    finally:
        close = getattr(iterator, "close", None)  # a generator: its file is closed now
        if close is not None:
            close()
