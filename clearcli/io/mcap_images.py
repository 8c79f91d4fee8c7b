"""A depth image message of a log (MCAP, ROS 1 bag, rosbag2) -> a `Frame`, with its
camera info and its colour. The log is reached through the log interface
(`clearcli.io.log_access.LogAccess`: `decoded(topic)`, `window(topic, start, end)`,
`can_seek`, `path`, `summary`), which MCAP logs and ROS bags offer alike.

Depth images come with their `CameraInfo` on the sibling `camera_info` topic (the
drivers' layout: `.../image_raw` beside `.../camera_info`); the camera info recorded last
before the image is used (a log may start with the image: then the first one). Colour is
attached only when a colour image of the same time stamp is *registered* to the depth:
the same frame id, as a driver's `aligned_depth_to_color` gives, and the same size. A
colour stream in another frame (unregistered) is left out with a note on stderr, never
painted on wrongly. A RealSense SDK recording (`/device_0/sensor_<i>/<Stream>_0/...`)
keeps colour unaligned, with the streams' extrinsics: it is registered to the depth
through them (`_realsense_color`, clearcli/io/register.py).
"""

from __future__ import annotations

from contextlib import closing
from pathlib import Path
from typing import Any

import numpy as np

from clearcli.console import stderr
from clearcli.errors import InputError
from clearcli.io.frames import Frame
from clearcli.io.image_messages import (
    CAMERA_INFO_SCHEMAS,
    COLOR_ENCODINGS,
    IMAGE_SCHEMAS,
    camera_model,
    color_rgb,
    depth_m,
    header_of,
    stamp_ns,
)
from clearcli.io.images import or_defaults
from clearcli.io.intrinsics import back_project
from clearcli.io.log_access import LogAccess, LogSummary
from clearcli.io.messages import _stamp_s, message_field
from clearcli.io.register import CannotRegister, color_for_depth
from clearcli.transforms import pose_to_matrix

# Colour within this log time of its depth image is looked at for a stamp that matches
# exactly (drivers publish the pair within milliseconds; a log's order may interleave).
_COLOR_WINDOW_NS = 1_000_000_000
_noted: set[tuple[str, str]] = set()
# (log path, camera info topic, mtime, size) -> [(log time ns, CameraModel)], read once per log
_infos: dict[tuple[str, str, int, int], list[tuple[int, Any]]] = {}
# (log path, option topic, mtime, size) -> the recorded depth unit (m), read once per log
_units: dict[tuple[str, str, int, int], float | None] = {}
# RealSense SDK recordings: the colour image logged nearest the depth image, within this
# (the recorder logs each sensor's frame as it arrives, a few ms apart; 50 ms is under two
# frame intervals at 30 fps, so the frameset's own colour image is the nearest one).
_RS_COLOR_WINDOW_NS = 50_000_000
# (log path, colour stream, mtime, size) -> T_color_depth (4 x 4, metres), or why not (a note)
_rs_extrinsics: dict[tuple[str, str, int, int], np.ndarray | str] = {}


def _note(path: Path, text: str) -> None:
    """Say ``text`` on stderr once per log (a replay reads hundreds of frames)."""
    if (str(path), text) in _noted:
        return
    _noted.add((str(path), text))
    stderr.print(f"clear: note: {path.name}: {text}", markup=False, highlight=False)


def camera_info_topic(summary: LogSummary, depth_topic: str) -> str:
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
        # up one namespace; a name with no "/" left ("camera", a topic without its
        # leading slash) has none above it (rsplit would give the name back: no end)
        parent = parent.rsplit("/", 1)[0] if "/" in parent else ""
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


def _camera_at(log: LogAccess, topic: str, log_time_ns: int) -> Any:
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


def _color_topics(summary: LogSummary, depth_topic: str) -> list[str]:
    """Colour image topics, those named colour/rgb first."""
    others = [t for t in summary.image_topics() if t != depth_topic and "depth" not in t.lower()]
    return sorted(others, key=lambda t: not any(w in t.lower() for w in ("color", "colour", "rgb")))


def _registered_color(
    log: LogAccess,
    depth_topic: str,
    frame_id: str,
    depth_stamp_ns: int,
    log_time_ns: int,
    shape: tuple[int, int],
    points_depth_m: np.ndarray,
) -> np.ndarray | None:
    path, summary = log.path, log.summary
    topics = _color_topics(summary, depth_topic)
    if not topics:
        return None
    if not log.can_seek:
        _note(path, "the log has no index: colour is left out (depth only)")
        return None
    depth_stream = _rs_stream(depth_topic)
    if depth_stream is not None:
        # A RealSense SDK recording keeps each sensor's raw stream: colour from another
        # sensor, in its own optics, never aligned to depth (the SDK aligns at run time).
        return _realsense_color(log, depth_stream, log_time_ns, points_depth_m)
    for topic in topics:
        with closing(
            log.window(topic, max(0, log_time_ns - _COLOR_WINDOW_NS), log_time_ns + _COLOR_WINDOW_NS)
        ) as window:
            for schema, msg, log_time in window:
                if schema not in IMAGE_SCHEMAS:
                    continue
                if stamp_ns(msg, log_time) != depth_stamp_ns:
                    continue
                color_frame = header_of(msg)[1]
                if not frame_id or not color_frame:
                    _note(
                        path,
                        f"colour on {topic} and the depth carry no frame ids: their registration cannot be "
                        "told, so colour is left out",
                    )
                    return None
                if color_frame != frame_id:
                    _note(
                        path,
                        f"colour on {topic} is in frame {color_frame!r}, not registered to the depth "
                        f"({frame_id!r}): left out; record aligned depth (aligned_depth_to_color) for colour",
                    )
                    return None
                rgb = color_rgb(msg, f"{path.name} {topic}")
                if rgb is None:
                    continue
                if rgb.shape[:2] != shape:
                    _note(
                        path,
                        f"colour on {topic} is {rgb.shape[1]} x {rgb.shape[0]}, the depth "
                        f"{shape[1]} x {shape[0]}: not registered, left out",
                    )
                    return None
                return rgb
    return None


def _rs_stream(topic: str) -> str | None:
    """The stream of a RealSense SDK topic (`/device_0/sensor_1/Color_0/image/data` ->
    `/device_0/sensor_1/Color_0`), None for another layout."""
    parts = topic.split("/")
    if len(parts) > 4 and parts[0] == "" and parts[1].startswith("device_") and parts[2].startswith("sensor_"):
        return "/".join(parts[:4])
    return None


def _rs_name(stream: str) -> str:
    """`Color` of `/device_0/sensor_1/Color_0`."""
    return stream.rsplit("/", 1)[-1].split("_", 1)[0]


def _rs_groups(log: LogAccess, stream: str) -> dict[int, str]:
    """{group index: topic} of the stream's recorded extrinsics (`<stream>/tf/<group>`)."""
    groups = {}
    for topic, _ in log.summary.topics():
        head, _, group = topic.rpartition("/")
        # isdecimal: what int() reads (isdigit also takes "²", which int() refuses)
        if head == f"{stream}/tf" and group.isdecimal() and log.summary.count(topic):
            groups[int(group)] = topic
    return groups


def _rs_transform(log: LogAccess, topic: str) -> np.ndarray | None:
    """The 4 x 4 of the geometry_msgs/Transform on ``topic`` (its first message); None when
    it holds no usable one."""
    for _, msg, _ in log.decoded(topic):
        t, r = message_field(msg, "translation"), message_field(msg, "rotation")
        try:
            xyz = [float(message_field(t, k, default=float("nan"))) for k in ("x", "y", "z")]
            q = [float(message_field(r, k, default=float("nan"))) for k in ("x", "y", "z", "w")]
            T = pose_to_matrix(xyz, q)
        except (TypeError, ValueError):
            return None
        return T if np.isfinite(T).all() else None
    return None


def _rs_color_from_depth(log: LogAccess, depth_stream: str, color_stream: str) -> np.ndarray | str:
    """T_color_depth (4 x 4, metres) from the recorded extrinsics, or the note saying why not.

    The direction, from librealsense's recorder and player (IntelRealSense/librealsense):
    - src/media/ros/ros_writer.cpp, `ros_writer::write_extrinsics`: `std::tie(reference_id,
      ext) = dev.get_extrinsics(*frame->get_stream()); convert(ext, tf_msg);
      write_message(ros_topic::stream_extrinsic_topic(stream_id, reference_id), ...)`;
    - src/device.cpp, `device::get_extrinsics`: `try_fetch_extrinsics(*pin_stream, stream,
      &ext)`, the pin stream being the first registered to the group (`device::
      register_stream_to_extrinsic_group`; src/ds/d400/d400-device.cpp registers
      `*_depth_stream` to group 0 first); an rs2_extrinsics
      "from -> to" maps from's points into to's, `rs2_transform_point_to_point`
      (include/librealsense2/rsutil.h: to = R from + t, R column-major);
    - src/media/ros/ros_file_format.h: `stream_extrinsic_topic` is `<stream>/tf/<ref_id>`,
      and `convert(rs2_extrinsics, geometry_msgs::Transform)` copies the translation and
      makes the quaternion with `rot2quat`, from the column-major r[9] read as
      m[row][col] = r[col*3 + row] (`qx = (m21 - m12) / (4 qw)`, ...), the usual (x, y, z, w)
      of that matrix;
    - src/media/readme.md: the tf topic is the "Extrinsic transformation between some
      point of reference (indexed by group_index) to the stream in the topic";
    - src/media/playback/playback_device.cpp, `calc_extrinsic(from, to)` =
      `to_pose(to) * inverse(to_pose(from))`, registered as the extrinsics from stream 1
      to stream 2: consistent only with each tf being reference -> stream (its comment
      says the opposite; the code, writer and readme agree).
    So `<stream>/tf/<g>` holds T_stream_ref, and T_color_depth = T_color_ref T_ref_depth,
    whichever stream is the reference (depth on D400s, its own tf then the identity)."""
    key = _log_key(log.path, color_stream)
    if key in _rs_extrinsics:
        return _rs_extrinsics[key]
    depth_groups, color_groups = _rs_groups(log, depth_stream), _rs_groups(log, color_stream)
    common = sorted(set(depth_groups) & set(color_groups))
    result: np.ndarray | str
    if not common:
        missing = [
            (s, g)
            for s, g, other in ((depth_stream, depth_groups, color_groups), (color_stream, color_groups, depth_groups))
            if not g
        ]
        if missing:
            group = min(depth_groups or color_groups or {0: ""})
            names = " or ".join(f"{_rs_name(s)} extrinsics ({s}/tf/{group})" for s, _ in missing)
            result = f"a RealSense SDK recording without {names}: colour left out"
        else:
            result = (
                f"a RealSense SDK recording whose {_rs_name(depth_stream)} and {_rs_name(color_stream)} "
                f"extrinsics are relative to different references ({', '.join(depth_groups.values())}; "
                f"{', '.join(color_groups.values())}): colour left out"
            )
    else:
        T_depth_ref = _rs_transform(log, depth_groups[common[0]])
        T_color_ref = _rs_transform(log, color_groups[common[0]])
        bad = [
            topic
            for topic, T in ((depth_groups[common[0]], T_depth_ref), (color_groups[common[0]], T_color_ref))
            if T is None
        ]
        if bad:
            result = f"a RealSense SDK recording whose extrinsics on {', '.join(bad)} are no transform: colour left out"
        else:
            assert T_color_ref is not None and T_depth_ref is not None  # neither is in `bad`
            result = T_color_ref @ np.linalg.inv(T_depth_ref)
    _rs_extrinsics[key] = result
    return result


def _realsense_color(
    log: LogAccess, depth_stream: str, log_time_ns: int, points_depth_m: np.ndarray
) -> np.ndarray | None:
    """(H*W, 3) uint8 colour of a RealSense SDK recording's depth frame, registered to it
    through the recorded extrinsics (clearcli/io/register.py); None, with a note naming
    what is missing, when the recording lacks what that needs."""
    path, summary = log.path, log.summary
    device = depth_stream.split("/")[1]
    types = dict(summary.topics())
    color_topics = sorted(
        (t, s)
        for t in summary.image_topics()
        if (s := _rs_stream(t)) is not None
        and s.split("/")[1] == device
        and _rs_name(s) == "Color"
        and t == f"{s}/image/data"
    )
    if not color_topics:
        return None  # no colour stream recorded
    color_topic, color_stream = color_topics[0]  # the stream of its topic
    info_topic = f"{color_stream}/info/camera_info"
    if types.get(info_topic) not in CAMERA_INFO_SCHEMAS or not summary.count(info_topic):
        _note(path, f"a RealSense SDK recording without Color intrinsics ({info_topic}): colour left out")
        return None
    T_color_depth = _rs_color_from_depth(log, depth_stream, color_stream)
    if isinstance(T_color_depth, str):
        _note(path, T_color_depth)
        return None
    nearest = None
    with closing(
        log.window(color_topic, max(0, log_time_ns - _RS_COLOR_WINDOW_NS), log_time_ns + _RS_COLOR_WINDOW_NS)
    ) as window:
        for schema, msg, log_time in window:
            if schema in IMAGE_SCHEMAS and (
                nearest is None or abs(log_time - log_time_ns) < abs(nearest[1] - log_time_ns)
            ):
                nearest = (msg, log_time)
    if nearest is None:
        _note(
            path,
            f"a RealSense SDK recording with no Color image ({color_topic}) within "
            f"{_RS_COLOR_WINDOW_NS // 1_000_000} ms of a depth image: that frame has no colour",
        )
        return None
    msg, color_log_time = nearest
    rgb = color_rgb(msg, f"{path.name} {color_topic}")
    if rgb is None:
        encoding = str(message_field(msg, "encoding", default=""))
        _note(
            path,
            f"a RealSense SDK recording whose colour on {color_topic} is {encoding or 'empty'!r}, not one "
            f"clear reads ({', '.join(COLOR_ENCODINGS)}): colour left out",
        )
        return None
    try:
        model = _camera_at(log, info_topic, color_log_time)
        model.check_size(rgb.shape[1], rgb.shape[0], f"the colour image on {color_topic}")
        return color_for_depth(points_depth_m, T_color_depth, model, rgb)
    except (InputError, CannotRegister) as e:
        _note(path, f"a RealSense SDK recording: {e}; colour left out")
        return None


def _recorded_depth_units(log: LogAccess, depth_topic: str) -> float | None:
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
        value = None
        for _, msg, _ in log.decoded(option):
            # a float32 in the bag: 0.001 arrives as 0.0010000000475; seven digits are what it holds
            value = float(f"{float(message_field(msg, 'data', default=0.0) or 0.0):.7g}")
            if not (value >= 1e-9 and value < 1):  # as [images] depth_scale_m's range
                raise InputError(f"{log.path}: {option} is {value}, not a depth unit in metres; give --depth-scale")
            break
        _units[key] = value
    return _units[key]


def depth_frame(
    log: LogAccess,
    topic: str,
    msg: Any,
    log_time_ns: int,
    source: str,
    images: Any = None,
) -> Frame:
    """The organized frame of one depth image message (see the module)."""
    images = or_defaults(images)
    depth = depth_m(msg, source, _recorded_depth_units(log, topic) or images.depth_scale_m)
    h, w = depth.shape
    model = _camera_at(log, camera_info_topic(log.summary, topic), log_time_ns)
    model.check_size(w, h, f"the depth image {source}")
    stamp, frame_id = header_of(msg)
    points = back_project(depth, model)
    colors = _registered_color(log, topic, frame_id, stamp_ns(msg, log_time_ns), log_time_ns, (h, w), points)
    return Frame(
        points=points,
        colors=None if colors is None else colors.reshape(-1, 3),
        shape=(h, w),
        stamp_s=_stamp_s(stamp, log_time_ns),
        frame_id=frame_id,
        source=source,
    )
