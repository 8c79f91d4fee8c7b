"""A depth image message of a log (MCAP, ROS 1 bag, rosbag2) -> a `Frame`, with its
camera info and its colour. The log is reached through an access value (`decoded(topic)`,
`window(topic, start, end)`, `can_seek`, `path`, `summary`): clearcli.io.mcap.LogAccess,
clearcli.io.rosbag.BagAccess.

Depth images come with their `CameraInfo` on the sibling `camera_info` topic (the
drivers' layout: `.../image_raw` beside `.../camera_info`); the camera info recorded last
before the image is used (a log may start with the image: then the first one). Colour is
attached only when a colour image of the same time stamp is *registered* to the depth:
the same frame id, as a driver's `aligned_depth_to_color` gives, and the same size. A
colour stream in another frame (unregistered) is left out with a note on stderr, never
painted on wrongly.
"""

from __future__ import annotations

from contextlib import closing
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from clearcli.errors import InputError
from clearcli.io.frames import Frame
from clearcli.io.image_messages import CAMERA_INFO_SCHEMAS, IMAGE_SCHEMAS, camera_model, color_rgb, depth_m, header_of, stamp_ns
from clearcli.io.messages import _stamp_s

if TYPE_CHECKING:
    from clearcli.io.mcap import LogAccess, McapSummary

# Colour within this log time of its depth image is looked at for a stamp that matches
# exactly (drivers publish the pair within milliseconds; a log's order may interleave).
_COLOR_WINDOW_NS = 1_000_000_000
_noted: set[tuple[str, str]] = set()
# (log path, camera info topic, mtime, size) -> [(log time ns, CameraModel)], read once per log
_infos: dict[tuple[str, str, int, int], list[tuple[int, Any]]] = {}
# (log path, option topic, mtime, size) -> the recorded depth unit (m), read once per log
_units: dict[tuple[str, str, int, int], float | None] = {}


def _note(path: Path, text: str) -> None:
    """Say ``text`` on stderr once per log (a replay reads hundreds of frames)."""
    if (str(path), text) in _noted:
        return
    _noted.add((str(path), text))
    from clearcli.console import stderr

    stderr.print(f"clear: note: {path.name}: {text}", markup=False, highlight=False)


def camera_info_topic(summary: "McapSummary", depth_topic: str) -> str:
    """The camera info of ``depth_topic``: its sibling `camera_info` (ROS drivers), else
    the one camera info topic in the nearest enclosing namespace that has exactly one
    (RealSense SDK bags: `.../Depth_0/image/data` -> `.../Depth_0/info/camera_info`)."""
    types = dict(summary.topics())
    parent = depth_topic.rsplit("/", 1)[0]
    sibling = f"{parent}/camera_info"
    if types.get(sibling) in CAMERA_INFO_SCHEMAS:
        return sibling
    infos = [t for t, s in types.items() if s in CAMERA_INFO_SCHEMAS]
    while parent:
        near = [t for t in infos if t.startswith(parent + "/")]
        if len(near) == 1:
            return near[0]
        if near:
            break  # several in this namespace: which is ambiguous
        parent = parent.rsplit("/", 1)[0]
    raise InputError(
        f"{summary.path}: no camera info for the depth images on {depth_topic} (expected {sibling}"
        + (f"; camera info topics: {', '.join(infos)}" if infos else "; the log holds none")
        + "); record the camera_info topic with the images"
    )


def _log_key(path: Path, topic: str) -> tuple[str, str, int, int]:
    """What a per-log cache is keyed by: a rewritten log (other mtime or size) is read again."""
    try:
        st = path.stat()
        return (str(path.resolve()), topic, st.st_mtime_ns, st.st_size)
    except OSError:
        return (str(path), topic, 0, 0)


def _camera_at(log: "LogAccess", topic: str, log_time_ns: int) -> Any:
    path = log.path
    key = _log_key(path, topic)
    if key not in _infos:
        models: list[tuple[int, Any]] = []
        for _, msg, log_time in log.decoded(topic):
            models.append((log_time, camera_model(msg, f"{path.name} {topic}")))
        _infos[key] = sorted(models, key=lambda m: m[0])
    models = _infos[key]
    if not models:
        raise InputError(f"{path}: {topic} holds no message; the depth images have no camera info")
    before = [m for t, m in models if t <= log_time_ns]
    return before[-1] if before else models[0][1]


def _color_topics(summary: "McapSummary", depth_topic: str) -> list[str]:
    """Colour image topics, those named colour/rgb first."""
    others = [t for t in summary.image_topics() if t != depth_topic and "depth" not in t.lower()]
    return sorted(others, key=lambda t: not any(w in t.lower() for w in ("color", "colour", "rgb")))


def _registered_color(
    log: "LogAccess", depth_topic: str, frame_id: str,
    depth_stamp_ns: int, log_time_ns: int, shape: tuple[int, int],
) -> np.ndarray | None:
    path, summary = log.path, log.summary
    topics = _color_topics(summary, depth_topic)
    if not topics:
        return None
    if not log.can_seek:
        _note(path, "the log has no index: colour is left out (depth only)")
        return None
    if depth_topic.startswith("/device_"):
        # A RealSense SDK recording keeps each sensor's raw stream: colour from another
        # sensor, in its own optics, never aligned to depth (the SDK aligns at run time).
        # Registering it needs the recorded extrinsics and a reprojection; until then it
        # is left out rather than painted on the wrong pixels.
        _note(path, "a RealSense SDK recording: colour is another sensor's, not registered to depth; left out")
        return None
    for topic in topics:
        with closing(log.window(topic, max(0, log_time_ns - _COLOR_WINDOW_NS), log_time_ns + _COLOR_WINDOW_NS)) as window:
            for schema, msg, log_time in window:
                if schema not in IMAGE_SCHEMAS:
                    continue
                if stamp_ns(msg, log_time) != depth_stamp_ns:
                    continue
                color_frame = header_of(msg)[1]
                if not frame_id or not color_frame:
                    _note(path, f"colour on {topic} and the depth carry no frame ids: their registration cannot be "
                                "told, so colour is left out")
                    return None
                if color_frame != frame_id:
                    _note(path, f"colour on {topic} is in frame {color_frame!r}, not registered to the depth "
                                f"({frame_id!r}): left out; record aligned depth (aligned_depth_to_color) for colour")
                    return None
                rgb = color_rgb(msg, f"{path.name} {topic}")
                if rgb is None:
                    continue
                if rgb.shape[:2] != shape:
                    _note(path, f"colour on {topic} is {rgb.shape[1]} x {rgb.shape[0]}, the depth "
                                f"{shape[1]} x {shape[0]}: not registered, left out")
                    return None
                return rgb
    return None


def _recorded_depth_units(log: "LogAccess", depth_topic: str) -> float | None:
    """Metres per depth unit as the recording states it: a RealSense SDK bag keeps the
    sensor's "Depth Units" option (`/device_0/sensor_0/option/Depth Units/value`) beside
    the stream; None when the log does not say (then [images] depth_scale_m)."""
    parts = depth_topic.split("/")
    sensor = "/".join(parts[:3]) if len(parts) > 3 and parts[1].startswith("device_") else None
    if sensor is None:
        return None
    option = f"{sensor}/option/Depth Units/value"
    if option not in dict(log.summary.topics()):
        return None
    key = _log_key(log.path, option)
    if key not in _units:
        from clearcli.io.messages import message_field

        value = None
        for _, msg, _ in log.decoded(option):
            # a float32 in the bag: 0.001 arrives as 0.0010000000475; seven digits are what it holds
            value = float(f"{float(message_field(msg, 'data', default=0.0) or 0.0):.7g}")
            if not (value > 0 and value < 1):
                raise InputError(f"{log.path}: {option} is {value}, not a depth unit in metres; give --depth-scale")
            break
        _units[key] = value
    return _units[key]


def depth_frame(
    log: "LogAccess", topic: str, msg: Any, log_time_ns: int,
    source: str, images: Any = None,
) -> Frame:
    """The organized frame of one depth image message (see the module)."""
    from clearcli.io.images import or_defaults
    from clearcli.io.intrinsics import back_project

    images = or_defaults(images)
    depth = depth_m(msg, source, _recorded_depth_units(log, topic) or images.depth_scale_m)
    h, w = depth.shape
    model = _camera_at(log, camera_info_topic(log.summary, topic), log_time_ns)
    model.check_size(w, h, f"the depth image {source}")
    stamp, frame_id = header_of(msg)
    colors = _registered_color(log, topic, frame_id, stamp_ns(msg, log_time_ns), log_time_ns, (h, w))
    return Frame(
        points=back_project(depth, model),
        colors=None if colors is None else colors.reshape(-1, 3),
        shape=(h, w),
        stamp_s=_stamp_s(stamp, log_time_ns),
        frame_id=frame_id,
        source=source,
    )
