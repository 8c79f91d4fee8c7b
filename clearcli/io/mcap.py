"""MCAP logs <-> `Frame`s, one message at a time.

Reading: `sensor_msgs/PointCloud2` (ROS 2 cdr and ROS 1), `foxglove.PointCloud` (protobuf
and json) and `foxglove_msgs/msg/PointCloud` (cdr). Messages are decoded with mcap's own
decoder factories; the point blob inside each message is then viewed through a NumPy
structured dtype (offsets, point_step, row_step, byte order from the message), never
walked point by point. With an intact summary the reader seeks chunk by chunk (only the
chunks holding the chosen topic); without one (a truncated log) it streams the records in
file order and, when the data stops making sense, raises PartialLogError after yielding
every complete frame.

foxglove.PointCloud carries a `pose` of the points in `frame_id`; it is APPLIED, so every
Frame's points are in its `frame_id` like PointCloud2's.

Writing: ROS 2 `sensor_msgs/msg/PointCloud2` (cdr, zstd chunks) with x y z, PCL's packed
float `rgb`, and a uint32 `label`; optionally a `/tf_static` transform. Atomic.
"""

from __future__ import annotations

import base64
import contextlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO, Callable, Iterable, Iterator, Sequence

import numpy as np

from clearcli.errors import InputError, OutputError, PartialLogError
from clearcli.io.frames import Frame
from clearcli.transforms import matrix_to_quat, quat_to_matrix
from clearcli.io.pointfields import (
    FOXGLOVE_TYPE_NAMES,
    FOXGLOVE_TYPES,
    ROS_DATATYPES,
    FieldSpec,
    check_specs,
    frame_from_records,
    pack_rgb_float,
    records_from_blob,
)

from clearcli.io.sniff import MCAP_MAGIC  # noqa: E402
DEFAULT_TOPIC = "/camera/depth_registered/points"
DEFAULT_FRAME_ID = "camera_rgb_optical_frame"

POINTCLOUD2_SCHEMAS = frozenset({"sensor_msgs/msg/PointCloud2", "sensor_msgs/PointCloud2"})
FOXGLOVE_SCHEMAS = frozenset({"foxglove.PointCloud", "foxglove_msgs/msg/PointCloud", "foxglove_msgs/PointCloud"})
POINTCLOUD_SCHEMAS = POINTCLOUD2_SCHEMAS | FOXGLOVE_SCHEMAS


@dataclass(frozen=True)
class ChannelInfo:
    """One channel of a log (several channels may share a topic)."""

    id: int
    topic: str
    schema_name: str
    schema_encoding: str
    message_encoding: str
    message_count: int

    @property
    def is_point_cloud(self) -> bool:
        return self.schema_name in POINTCLOUD_SCHEMAS


@dataclass(frozen=True)
class McapSummary:
    """What a log holds, from its summary section or, when that is missing, from a scan."""

    path: Path
    profile: str
    library: str
    channels: tuple[ChannelInfo, ...]
    message_count: int
    start_ns: int | None
    end_ns: int | None
    indexed: bool  # the summary section was read (else: a scan of the records)
    chunk_count: int
    damage: str | None = None  # where and why a scan stopped early, None when whole

    def topics(self) -> list[tuple[str, str]]:
        """(topic, schema name) once per topic, in channel order."""
        seen: dict[str, str] = {}
        for ch in self.channels:
            seen.setdefault(ch.topic, ch.schema_name)
        return list(seen.items())

    def pointcloud_topics(self) -> list[str]:
        return [topic for topic, schema in self.topics() if schema in POINTCLOUD_SCHEMAS]

    def count(self, topic: str) -> int:
        return sum(ch.message_count for ch in self.channels if ch.topic == topic)


def is_mcap(head: bytes) -> bool:
    return head.startswith(MCAP_MAGIC)


def _open(path: Path) -> BinaryIO:
    try:
        fp = open(path, "rb")
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a directory, not an MCAP file") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror})") from None
    head = fp.read(len(MCAP_MAGIC))
    if not is_mcap(head):
        fp.close()
        if not head:
            raise InputError(f"{path}: empty file (0 bytes); expected an MCAP log")
        if head.startswith(b"#ROSBAG"):
            raise InputError(
                f"{path}: not an MCAP file: it is a ROS 1 bag; convert it with `mcap convert {path.name} out.mcap`"
            )
        raise InputError(f"{path}: not an MCAP file (it does not start with the MCAP magic bytes)")
    fp.seek(0)
    return fp


def error_reason(exc: BaseException) -> str:
    text = str(exc).splitlines()[0] if str(exc) else ""
    name = type(exc).__name__
    return f"{name}: {text[:120]}" if text else name


def _schema_name(schema: Any) -> str:
    return schema.name if schema is not None else ""


def _scan(path: Path, fp: BinaryIO) -> McapSummary:
    """Read every record once (decompressing chunks) to learn channels, counts and span.

    Used when the summary section is absent or unreadable, typically a truncated log; it
    stops quietly at the first damaged record and says where in `damage`.
    """
    from mcap.records import Channel, Header, Message, Schema
    from mcap.stream_reader import StreamReader

    schemas: dict[int, Any] = {}
    channels: dict[int, Any] = {}
    counts: dict[int, int] = {}
    profile = library = ""
    start = end = None
    n = 0
    damage = None
    fp.seek(0)
    try:
        for record in StreamReader(fp, skip_magic=False).records:
            if isinstance(record, Header):
                profile, library = record.profile, record.library
            elif isinstance(record, Schema):
                schemas[record.id] = record
            elif isinstance(record, Channel):
                channels[record.id] = record
            elif isinstance(record, Message):
                counts[record.channel_id] = counts.get(record.channel_id, 0) + 1
                n += 1
                start = record.log_time if start is None else min(start, record.log_time)
                end = record.log_time if end is None else max(end, record.log_time)
    except Exception as exc:  # EndOfFile, struct.error, zstd/lz4 errors, CRC errors...
        damage = f"after {n} complete messages ({error_reason(exc)})"
    infos = tuple(
        ChannelInfo(
            id=cid,
            topic=ch.topic,
            schema_name=_schema_name(schemas.get(ch.schema_id)),
            schema_encoding=schemas[ch.schema_id].encoding if ch.schema_id in schemas else "",
            message_encoding=ch.message_encoding,
            message_count=counts.get(cid, 0),
        )
        for cid, ch in channels.items()
    )
    return McapSummary(
        path=path, profile=profile, library=library, channels=infos, message_count=n,
        start_ns=start, end_ns=end, indexed=False, chunk_count=0, damage=damage,
    )


def read_summary(path: Path) -> McapSummary:
    """Channels, counts, time span and profile of the log at `path` (InputError if not MCAP)."""
    from mcap.reader import SeekingReader

    path = Path(path)
    fp = _open(path)
    with fp:
        try:
            reader = SeekingReader(fp)
            header = reader.get_header()
            summary = reader.get_summary()
        except Exception:
            summary = None
        if summary is None or summary.statistics is None:
            # No (usable) summary section: learn everything from the records themselves.
            return _scan(path, fp)
        stats = summary.statistics
        infos = tuple(
            ChannelInfo(
                id=cid,
                topic=ch.topic,
                schema_name=_schema_name(summary.schemas.get(ch.schema_id)),
                schema_encoding=summary.schemas[ch.schema_id].encoding if ch.schema_id in summary.schemas else "",
                message_encoding=ch.message_encoding,
                message_count=int(stats.channel_message_counts.get(cid, 0)),
            )
            for cid, ch in summary.channels.items()
        )
        has_messages = stats.message_count > 0
        return McapSummary(
            path=path,
            profile=header.profile,
            library=header.library,
            channels=infos,
            message_count=int(stats.message_count),
            start_ns=int(stats.message_start_time) if has_messages else None,
            end_ns=int(stats.message_end_time) if has_messages else None,
            indexed=len(summary.chunk_indexes) > 0,
            chunk_count=len(summary.chunk_indexes),
        )


def _topic_list(summary: Any) -> str:
    return ", ".join(f"{t} ({s or 'no type'})" for t, s in summary.topics()) or "none"


def choose_topic(summary: Any, topic: str | None) -> str:
    """The point-cloud topic to read: `topic` if given (checked), else the only one there is.
    ``summary``: an `McapSummary`, or a bag's summary (`clearcli.io.rosbag.BagSummary`):
    anything with ``path``, ``topics()``, ``pointcloud_topics()`` and ``damage``."""
    path = summary.path
    if topic is not None:
        types = dict(summary.topics())
        if topic not in types:
            raise InputError(f"{path}: no topic {topic!r}; topics: {_topic_list(summary)}")
        if types[topic] not in POINTCLOUD_SCHEMAS:
            raise InputError(
                f"{path}: topic {topic} has type {types[topic] or 'unknown'}, not a point cloud "
                f"({', '.join(sorted(POINTCLOUD_SCHEMAS))})"
            )
        return topic
    candidates = summary.pointcloud_topics()
    if not candidates and summary.damage is not None:
        what = getattr(summary, "what", "MCAP log")
        raise InputError(
            f"{path}: truncated or corrupt {what}: it breaks {summary.damage} before any "
            f"point-cloud topic; topics seen: {_topic_list(summary)}"
        )
    if not candidates:
        raise InputError(f"no point-cloud topic in {path}; topics: {_topic_list(summary)}")
    if len(candidates) > 1:
        raise InputError(
            f"{path}: several point-cloud topics ({', '.join(candidates)}); choose one with --topic"
        )
    return candidates[0]


# --- decoding -------------------------------------------------------------------------


class _Decoders:
    """mcap decoder factories, built lazily, one decoder per schema."""

    def __init__(self) -> None:
        self._cache: dict[tuple[int, str], Callable[[bytes], Any]] = {}

    def decode(self, schema: Any, channel: Any, data: bytes) -> Any:
        encoding = channel.message_encoding
        if encoding == "json":
            return json.loads(data)
        key = (schema.id if schema is not None else 0, encoding)
        decoder = self._cache.get(key)
        if decoder is None:
            decoder = self._make(schema, encoding)
            self._cache[key] = decoder
        return decoder(data)

    @staticmethod
    def _make(schema: Any, encoding: str) -> Callable[[bytes], Any]:
        if encoding == "cdr":
            from mcap_ros2.decoder import DecoderFactory
        elif encoding == "ros1":
            from mcap_ros1.decoder import DecoderFactory  # type: ignore[no-redef]
        elif encoding == "protobuf":
            from mcap_protobuf.decoder import DecoderFactory  # type: ignore[no-redef]
        else:
            raise ValueError(f"unsupported message encoding {encoding!r}")
        decoder = DecoderFactory().decoder_for(encoding, schema)
        if decoder is None:
            raise ValueError(f"no decoder for {encoding} schema {_schema_name(schema)!r}")
        return decoder


def _get(msg: Any, *names: str, default: Any = None) -> Any:
    """First present attribute (decoded objects) or key (json dicts) among `names`."""
    for name in names:
        if isinstance(msg, dict):
            if name in msg:
                return msg[name]
        elif hasattr(msg, name):
            return getattr(msg, name)
    return default


def _stamp_s(stamp: Any, log_time_ns: int) -> float:
    """Seconds from a ROS 1/ROS 2/protobuf/json time; the log time when it is zero or absent."""
    if stamp is not None:
        sec = _get(stamp, "sec", "secs", "seconds", default=0) or 0
        nsec = _get(stamp, "nanosec", "nsecs", "nsec", "nanos", default=0) or 0
        if hasattr(stamp, "to_nsec") and not isinstance(stamp, dict):
            with contextlib.suppress(Exception):
                total = int(stamp.to_nsec())
                sec, nsec = divmod(total, 1_000_000_000)
        if int(sec) != 0 or int(nsec) != 0:
            return int(sec) + int(nsec) * 1e-9
    return log_time_ns * 1e-9


def _as_bytes(data: Any) -> bytes | memoryview:
    if isinstance(data, (bytes, bytearray, memoryview)):
        return data
    if isinstance(data, str):  # json: base64
        return base64.b64decode(data)
    if isinstance(data, np.ndarray):
        return data.tobytes()
    return bytes(data)


def pointcloud2_frame(msg: Any, log_time_ns: int, source: str) -> Frame:
    header = _get(msg, "header")
    height, width = int(msg.height), int(msg.width)
    point_step, row_step = int(msg.point_step), int(msg.row_step)
    specs = []
    for f in msg.fields:
        code = ROS_DATATYPES.get(int(f.datatype))
        if code is None:  # unknown datatype: its bytes are skipped, the rest still decodes
            continue
        specs.append(FieldSpec(str(f.name), int(f.offset), code, max(int(f.count), 1)))
    return _frame_from_blob(
        msg.data, specs, point_step, width, height, row_step or width * point_step,
        bool(msg.is_bigendian),
        shape=(height, width) if height > 1 else None,
        stamp_s=_stamp_s(_get(header, "stamp"), log_time_ns),
        frame_id=str(_get(header, "frame_id", default="") or ""),
        source=source,
    )


def quat_matrix(q: Sequence[float]) -> np.ndarray:
    """A message's (x, y, z, w) orientation as a rotation; all zeros (an unset pose) is
    the identity."""
    if not any(float(v) for v in q):
        return np.eye(3)
    try:
        return quat_to_matrix(q)
    except ValueError:
        raise InputError(f"pose orientation {list(q)} is not a rotation (not finite)") from None


def foxglove_frame(msg: Any, log_time_ns: int, source: str) -> Frame:
    stride = int(_get(msg, "point_stride", default=0) or 0)
    specs = []
    for f in _get(msg, "fields", default=[]) or []:
        type_value = _get(f, "type", default=0)
        if isinstance(type_value, str):
            type_value = FOXGLOVE_TYPE_NAMES.get(type_value.upper(), 0)
        code = FOXGLOVE_TYPES.get(int(type_value))
        if code is None:
            continue
        specs.append(FieldSpec(str(_get(f, "name")), int(_get(f, "offset", default=0) or 0), code))
    data = _as_bytes(_get(msg, "data", default=b""))
    if stride <= 0:
        raise ValueError(f"point_stride is {stride}")
    n = len(data) // stride
    frame = _frame_from_blob(
        data, specs, stride, n, 1, n * stride, False, shape=None,
        stamp_s=_stamp_s(_get(msg, "timestamp"), log_time_ns),
        frame_id=str(_get(msg, "frame_id", default="") or ""),
        source=source,
    )
    pose = _get(msg, "pose")
    if pose is None:
        return frame
    pos = _get(pose, "position")
    ori = _get(pose, "orientation")
    t = np.array([float(_get(pos, a, default=0.0) or 0.0) for a in "xyz"]) if pos is not None else np.zeros(3)
    q = [float(_get(ori, a, default=0.0) or 0.0) for a in "xyzw"] if ori is not None else [0, 0, 0, 1]
    if ori is not None and not any(q):
        q = [0.0, 0.0, 0.0, 1.0]  # protobuf leaves an all-default quaternion empty
    R = quat_matrix(q)
    if np.allclose(R, np.eye(3)) and not t.any():
        return frame
    points = (frame.points.astype(np.float64) @ R.T + t).astype(np.float32)
    return Frame(points=points, colors=frame.colors, shape=frame.shape, fields=frame.fields,
                 stamp_s=frame.stamp_s, frame_id=frame.frame_id, source=frame.source)


def _frame_from_blob(
    data: Any, specs: list[FieldSpec], point_step: int, width: int, height: int, row_step: int,
    big_endian: bool, *, shape: tuple[int, int] | None, stamp_s: float, frame_id: str, source: str,
) -> Frame:
    problem = check_specs(specs, point_step)
    if problem:
        raise ValueError(problem)
    names = {s.name for s in specs}
    if not {"x", "y", "z"} <= names:
        raise ValueError(f"the message has no x/y/z fields (fields: {' '.join(sorted(names)) or 'none'})")
    records = records_from_blob(_as_bytes(data), specs, point_step, width, height, row_step, big_endian)
    return frame_from_records(records, shape, stamp_s=stamp_s, frame_id=frame_id, source=source)


def _message_frame(decoders: _Decoders, schema: Any, channel: Any, message: Any, index: int, path: Path) -> Frame:
    source = f"{path.name}#{index} {channel.topic}"
    msg = decoders.decode(schema, channel, message.data)
    if _schema_name(schema) in POINTCLOUD2_SCHEMAS:
        return pointcloud2_frame(msg, message.log_time, source)
    return foxglove_frame(msg, message.log_time, source)


# --- iteration ------------------------------------------------------------------------


def _raw_messages(path: Path, summary: McapSummary, topic: str) -> Iterator[tuple[Any, Any, Any]]:
    """(schema, channel, message) of `topic`, in log-time order when indexed, else file order."""
    from mcap.reader import NonSeekingReader, SeekingReader

    fp = _open(path)
    with fp:
        if summary.indexed:
            reader: Any = SeekingReader(fp)
            yield from reader.iter_messages(topics=[topic], log_time_order=True)
        else:
            reader = NonSeekingReader(fp)
            # File order: sorting by log time would hold the whole log in memory.
            yield from reader.iter_messages(topics=[topic], log_time_order=False)


def _guarded(path: Path, summary: McapSummary, topic: str) -> Iterator[tuple[int, Any, Any, Any]]:
    """Raw messages numbered from 0; damage after k messages -> PartialLogError (k > 0)."""
    it = _raw_messages(path, summary, topic)
    index = 0
    while True:
        try:
            schema, channel, message = next(it)
        except StopIteration:
            return
        except InputError:
            raise
        except Exception as exc:
            _raise_damage(path, topic, index, error_reason(exc))
        yield index, schema, channel, message
        index += 1


def _raise_damage(path: Path, topic: str, complete: int, reason: str) -> None:
    if complete == 0:
        raise InputError(f"{path}: corrupt or truncated log: no complete frame on {topic} ({reason})")
    raise PartialLogError(
        f"{path}: log truncated or corrupt after frame {complete - 1} of {topic} "
        f"({complete} complete frame{'s' if complete != 1 else ''} read; {reason})"
    )


def iter_mcap_frames(path: Path, topic: str | None = None) -> Iterator[Frame]:
    """Every frame of the point-cloud topic, decoded one message at a time."""
    path = Path(path)
    summary = read_summary(path)
    topic = choose_topic(summary, topic)
    decoders = _Decoders()
    for index, schema, channel, message in _guarded(path, summary, topic):
        try:
            frame = _message_frame(decoders, schema, channel, message, index, path)
        except Exception as exc:
            _raise_damage(path, topic, index, f"message {index} cannot be decoded: {error_reason(exc)}")
        yield frame


def require_frame_index(path: Path, summary: McapSummary, topic: str, index: int) -> None:
    """InputError unless frame ``index`` of ``topic`` exists (past the end of a damaged
    log is left to the reader, which stops at the damage)."""
    total = summary.count(topic)
    if index < 0 or (summary.damage is None and index >= total):
        raise InputError(
            f"{path}: --frame {index} does not exist: {topic} has {total} frame{'s' if total != 1 else ''}"
            + (f" (0..{total - 1})" if total else "")
        )


def read_mcap_frame(path: Path, topic: str | None = None, index: int = 0) -> Frame:
    """Frame `index` (from 0) of the point-cloud topic; only that message is decoded."""
    path = Path(path)
    summary = read_summary(path)
    topic = choose_topic(summary, topic)
    require_frame_index(path, summary, topic, index)
    decoders = _Decoders()
    seen = 0
    for i, schema, channel, message in _guarded(path, summary, topic):
        seen = i + 1
        if i == index:
            try:
                return _message_frame(decoders, schema, channel, message, index, path)
            except Exception as exc:
                raise InputError(f"{path}: frame {index} of {topic} cannot be decoded ({error_reason(exc)})") from None
    if summary.damage is not None:
        _raise_damage(path, topic, seen, f"frame {index} is past the damage; the log is {summary.damage}")
    raise InputError(f"{path}: --frame {index} does not exist: {topic} has {seen} frames")


# --- writing --------------------------------------------------------------------------

_TIME_DEF = "int32 sec\nuint32 nanosec\n"
_HEADER_DEF = "builtin_interfaces/Time stamp\nstring frame_id\n"
_SEP = "=" * 80 + "\n"
POINTCLOUD2_MSGDEF = (
    "std_msgs/Header header\nuint32 height\nuint32 width\nPointField[] fields\n"
    "bool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n"
    + _SEP + "MSG: std_msgs/Header\n" + _HEADER_DEF
    + _SEP + "MSG: builtin_interfaces/Time\n" + _TIME_DEF
    + _SEP + "MSG: sensor_msgs/PointField\n"
    "uint8 INT8 = 1\nuint8 UINT8 = 2\nuint8 INT16 = 3\nuint8 UINT16 = 4\n"
    "uint8 INT32 = 5\nuint8 UINT32 = 6\nuint8 FLOAT32 = 7\nuint8 FLOAT64 = 8\n"
    "string name\nuint32 offset\nuint8 datatype\nuint32 count\n"
)
TFMESSAGE_MSGDEF = (
    "geometry_msgs/TransformStamped[] transforms\n"
    + _SEP + "MSG: geometry_msgs/TransformStamped\nstd_msgs/Header header\nstring child_frame_id\n"
    "Transform transform\n"
    + _SEP + "MSG: std_msgs/Header\n" + _HEADER_DEF
    + _SEP + "MSG: builtin_interfaces/Time\n" + _TIME_DEF
    + _SEP + "MSG: geometry_msgs/Transform\nVector3 translation\nQuaternion rotation\n"
    + _SEP + "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n"
    + _SEP + "MSG: geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"
)


@dataclass(frozen=True)
class StaticTransform:
    """`T_parent_child` (4x4, metres): a point in `child` frame maps into `parent` frame."""

    parent_frame: str
    child_frame: str
    T_parent_child: np.ndarray
    stamp_s: float = 0.0


def _time(stamp_s: float) -> dict[str, int]:
    total = int(round(stamp_s * 1e9))
    sec, nanosec = divmod(total, 1_000_000_000)
    return {"sec": int(sec), "nanosec": int(nanosec)}



def _pointcloud2_dict(frame: Frame, labels: np.ndarray | None) -> dict[str, Any]:
    n = frame.n_points
    cols: list[tuple[str, np.dtype, np.ndarray]] = [
        ("x", np.dtype("<f4"), frame.points[:, 0]),
        ("y", np.dtype("<f4"), frame.points[:, 1]),
        ("z", np.dtype("<f4"), frame.points[:, 2]),
    ]
    if frame.colors is not None:
        cols.append(("rgb", np.dtype("<f4"), pack_rgb_float(frame.colors)))
    if labels is None and "label" in frame.fields:
        labels = np.asarray(frame.fields["label"])
    if labels is not None:
        labels = np.asarray(labels)
        if labels.shape != (n,):
            raise ValueError(f"labels must have shape ({n},), got {labels.shape}")
        cols.append(("label", np.dtype("<u4"), labels.astype(np.uint32)))
    record = np.dtype([(name, dt) for name, dt, _ in cols])
    blob = np.empty(n, dtype=record)
    for name, _, values in cols:
        blob[name] = values
    height, width = frame.shape if frame.shape is not None else (1, n)
    datatype = {"f4": 7, "u4": 6}
    fields = [
        {"name": name, "offset": int(record.fields[name][1]), "datatype": datatype[dt.str[1:]], "count": 1}
        for name, dt, _ in cols
    ]
    return {
        "header": {"stamp": _time(frame.stamp_s), "frame_id": frame.frame_id or DEFAULT_FRAME_ID},
        "height": height,
        "width": width,
        "fields": fields,
        "is_bigendian": False,
        "point_step": record.itemsize,
        "row_step": record.itemsize * width,
        "data": blob.tobytes(),
        "is_dense": bool(frame.finite_mask.all()),
    }


def _tf_dict(transforms: Sequence[StaticTransform]) -> dict[str, Any]:
    out = []
    for tf in transforms:
        T = np.asarray(tf.T_parent_child, dtype=float)
        x, y, z, w = matrix_to_quat(T[:3, :3])
        out.append(
            {
                "header": {"stamp": _time(tf.stamp_s), "frame_id": tf.parent_frame},
                "child_frame_id": tf.child_frame,
                "transform": {
                    "translation": {"x": float(T[0, 3]), "y": float(T[1, 3]), "z": float(T[2, 3])},
                    "rotation": {"x": x, "y": y, "z": z, "w": w},
                },
            }
        )
    return {"transforms": out}


def write_pointcloud2_mcap(
    path: Path,
    frames: Iterable[Frame],
    topic: str = DEFAULT_TOPIC,
    labels: Iterable[np.ndarray | None] | None = None,
    tf_static: Sequence[StaticTransform] = (),
) -> int:
    """Write frames as ROS 2 `sensor_msgs/msg/PointCloud2` (cdr) on `topic`; returns the count.

    Fields x y z (float32), `rgb` (PCL's packed float) when the frame has colours, `label`
    (uint32) from `labels[i]` when given, else from the frame's own "label" field. Organized
    frames keep height/width. Stamp = frame.stamp_s (also the log time), frame_id =
    frame.frame_id or "camera_rgb_optical_frame". `tf_static` transforms go on
    `/tf_static` (tf2_msgs/msg/TFMessage) before the first frame. The log appears whole or
    not at all; the caller decides about overwriting.
    """
    from mcap_ros2.writer import Writer

    from clearcli.files import atomic_output

    path = Path(path)
    label_iter = iter(labels) if labels is not None else None
    count = 0
    try:
        with atomic_output(path) as handle:
            writer = Writer(handle)
            if tf_static:
                tf_schema = writer.register_msgdef("tf2_msgs/msg/TFMessage", TFMESSAGE_MSGDEF)
                t_ns = int(round(min(tf.stamp_s for tf in tf_static) * 1e9))
                writer.write_message("/tf_static", tf_schema, _tf_dict(tf_static), log_time=t_ns, publish_time=t_ns)
            schema = writer.register_msgdef("sensor_msgs/msg/PointCloud2", POINTCLOUD2_MSGDEF)
            for frame in frames:
                frame_labels = next(label_iter, None) if label_iter is not None else None
                t_ns = int(round(frame.stamp_s * 1e9))
                writer.write_message(
                    topic, schema, _pointcloud2_dict(frame, frame_labels),
                    log_time=t_ns, publish_time=t_ns, sequence=count,
                )
                count += 1
            writer.finish()
    except OSError as exc:
        raise OutputError(f"{path}: cannot write ({exc.strerror or exc})") from None
    return count


def write_tf_static(path: Path, transforms: Sequence[StaticTransform]) -> None:
    """A log holding only `/tf_static` (for tests and tools); see write_pointcloud2_mcap."""
    write_pointcloud2_mcap(path, [], tf_static=transforms)


# Public names for what other modules (replay) already use under the private ones.
raw_messages = _raw_messages
MessageDecoders = _Decoders
message_field = _get
