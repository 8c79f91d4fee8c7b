"""What the log formats (MCAP, ROS 1 bags, rosbag2) share: the same summary attributes
(`McapSummary`, `BagSummary`), topic rules and frame reading, so one info payload and
one way to count frames."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from clearcli.errors import PartialLogError
from clearcli.io.formats.base import describe_frame


def describe_log(
    path: Path,
    summary: Any,
    access: Any,
    choose_topic: Callable[[Any, str | None], str],
    read_one: Callable[..., Any],
    topic: str | None,
    index: int,
    images: Any,
) -> dict[str, Any]:
    """The ``mcap`` (or ``bag``) object of a log's info payload and its ``frame`` part
    (None when no topic is chosen, or the chosen one holds no message yet)."""
    candidates = summary.frame_topics()  # no point cloud: depth images are the frames
    chosen: str | None = None
    if topic is not None or len(candidates) == 1:
        chosen = choose_topic(summary, topic)
    start = summary.start_ns * 1e-9 if summary.start_ns is not None else None
    end = summary.end_ns * 1e-9 if summary.end_ns is not None else None
    log_part: dict[str, Any] = {
        "profile": summary.profile,
        "library": summary.library,
        "indexed": summary.indexed,
        "complete": summary.damage is None,
        "damage": summary.damage,
        "message_count": summary.message_count,
        "start_s": start,
        "end_s": end,
        "duration_s": (end - start) if start is not None and end is not None else None,
        "channels": [
            {
                "topic": ch.topic,
                "schema": ch.schema_name,
                "schema_encoding": ch.schema_encoding,
                "message_encoding": ch.message_encoding,
                "message_count": ch.message_count,
                "point_cloud": ch.is_point_cloud,
            }
            for ch in summary.channels
        ],
        "pointcloud_topics": candidates,
        "pointcloud_topic": chosen,
        "image_streams": image_streams(access),
        "frame_count": summary.count(chosen) if chosen is not None else None,
    }
    frame_part = None
    if chosen is not None:
        if summary.count(chosen) == 0 and index == 0:
            frame_part = None  # the channel exists but holds no message yet
        else:
            frame_part = describe_frame(read_one(path, chosen, index, images), index)
    return {"log": log_part, "frame": frame_part}


def image_streams(access: Any) -> list[dict[str, Any]]:
    """Each image topic of a log or bag: its encoding and size (from its first message),
    and whether it is read as depth."""
    from clearcli.io.messages import message_field  # noqa: PLC0415  (NumPy and io.messages, ~100 ms: see formats/base.py)

    streams = []
    summary = access.summary
    depth = set(summary.depth_topics())
    for topic in summary.image_topics():
        entry: dict[str, Any] = {
            "topic": topic,
            "depth": topic in depth,
            "encoding": None,
            "width": None,
            "height": None,
        }
        try:
            for _, msg, _ in access.decoded(topic):
                entry.update(
                    encoding=str(message_field(msg, "encoding", default="")),
                    width=int(message_field(msg, "width", default=0)),
                    height=int(message_field(msg, "height", default=0)),
                )
                break
        except Exception:  # a damaged log: the channel list says what is known
            pass
        streams.append(entry)
    return streams


def count_log_frames(
    summary: Any, topic: str | None, choose_topic: Callable[[Any, str | None], str], frames: Callable[[], Iterator[Any]]
) -> tuple[int, Exception | None]:
    """Frames on a log's frame topic, and the PartialLogError that ended it early, if
    any. An intact log or bag is counted from its summary (index); a damaged one is
    read through to its break (``frames()``)."""
    if summary.damage is None:
        return summary.count(choose_topic(summary, topic)), None
    n = 0
    try:
        for _ in frames():
            n += 1
    except PartialLogError as exc:
        return n, exc
    return n, None
