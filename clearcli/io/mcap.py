"""MCAP logs <-> `Frame`s, one message at a time.

Reading: `sensor_msgs/PointCloud2` (ROS 2 cdr and ROS 1), `foxglove.PointCloud` (protobuf
and json) and `foxglove_msgs/msg/PointCloud` (cdr). Messages are decoded with mcap's own
decoder factories; the point blob inside each message is then viewed through a NumPy
structured dtype (offsets, point_step, row_step, byte order from the message), never
walked point by point. With an intact summary the reader seeks chunk by chunk (only the
chunks holding the chosen topic); without one (a truncated log) it streams the records in
file order and, when the data stops making sense, raises PartialLogError after yielding
every complete frame. Each frame message is checked to be the type its schema declares
(`decode_declared`): one that is not is damage, never read as something else.

foxglove.PointCloud carries a `pose` of the points in `frame_id`; it is APPLIED, so every
Frame's points are in its `frame_id` like PointCloud2's.

Messages become Frames in `clearcli.io.messages` (shared with the bag readers); a depth
image's camera info and colour are read through `McapAccess` (the log interface,
`clearcli.io.log_access`); `read_mcap_transforms` reads /tf_static and /tf; writing logs
is `clearcli.io.mcap_write`. The format's entry (what it recognises, how `read`, `info`
and a batch reach this module): `clearcli.io.formats.mcap`.
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO, TypeVar

from clearcli.errors import ClearError, InputError, PartialLogError
from clearcli.io.frames import Frame
from clearcli.io.image_messages import COMPRESSED_SCHEMAS, IMAGE_SCHEMAS
from clearcli.io.log_access import Decoded
from clearcli.io.mcap_images import depth_frame
from clearcli.io.messages import (
    MessageDecoders,
    _as_bytes,
    foxglove_frame,
    message_field,
    pointcloud2_frame,
    schema_name,
)
from clearcli.io.sniff import MCAP_MAGIC, open_input
from clearcli.transforms import pose_to_matrix

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

    def image_topics(self) -> list[str]:
        return [topic for topic, schema in self.topics() if schema in IMAGE_SCHEMAS]

    def depth_topics(self) -> list[str]:
        """Image topics that hold depth by the drivers' naming (RealSense
        `.../aligned_depth_to_color/image_raw`, Azure Kinect `/depth/image_raw`)."""
        return [t for t in self.image_topics() if "depth" in t.lower()]

    def frame_topics(self) -> list[str]:
        """The topics whose messages are frames: the point-cloud topics, or in a log with
        none, its depth image topics. The one rule for an intact log, a damaged one's scan
        (which knows the topics seen before the damage) and a bag."""
        return self.pointcloud_topics() or self.depth_topics()

    def count(self, topic: str) -> int:
        return sum(ch.message_count for ch in self.channels if ch.topic == topic)


def is_mcap(head: bytes) -> bool:
    return head.startswith(MCAP_MAGIC)


def _open(path: Path) -> BinaryIO:
    fp = open_input(path, "an MCAP file")
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


# --- declared types -------------------------------------------------------------------

# The fields a frame message of each type has, and which of them times the height must
# be the bytes of its data: a message that really is its declared type has them, and
# they agree with the data it carries.
_FRAME_LAYOUTS = (
    (POINTCLOUD2_SCHEMAS, "PointCloud2", ("height", "width", "fields", "point_step", "row_step", "data"), "row_step"),
    (IMAGE_SCHEMAS, "image", ("height", "width", "encoding", "step", "data"), "step"),
)
# What to do about an MCAP message that is not its declared type.
_TYPE_REMEDY = (
    "the log is damaged, or its schema for the topic names another type than its messages are: "
    "re-record it, or rewrite the topic with the schema of what it holds"
)


class DeclaredTypeError(ValueError):
    """A message that does not decode as the type its log declares for its topic, or
    decodes to fields that do not add up to the bytes it carries (the CDR of a
    PointCloud2 read as an Image): the log is damaged, or names another type than its
    messages are (an MCAP schema, a rosbag2's metadata.yaml, a ROS 1 connection header).
    Readers report it as damage: exit 3 before any complete frame, 9 after, in one line
    naming the topic, the type and what to do."""

    def __init__(self, declared: str, reason: str) -> None:
        super().__init__(f"does not decode as its declared type {declared or 'unknown'} ({reason})")
        self.declared, self.reason = declared, reason


def _byte_length(data: Any) -> int:
    if isinstance(data, memoryview):
        return data.nbytes
    if hasattr(data, "nbytes"):  # a NumPy array (rosbags)
        return int(data.nbytes)
    if isinstance(data, (bytes, bytearray)):
        return len(data)
    return len(_as_bytes(data))  # json: base64 text


def decode_declared(declared: str, decode: Callable[[], Any]) -> Any:
    """The message ``decode()`` gives, checked to be the ``declared`` type: it decodes, and
    a frame type's fields are there and add up to its data; DeclaredTypeError if not.
    (A decoder that reads past the end of a message quietly returns less: the sizes,
    not the decoder, tell a PointCloud2's bytes read as an Image.)"""
    try:
        msg = decode()
    except Exception as exc:  # SerdeError (size mismatch), struct.error, UnicodeDecodeError...
        raise DeclaredTypeError(declared, error_reason(exc)) from None
    for names, kind, fields, step_name in _FRAME_LAYOUTS:
        if declared not in names:
            continue
        missing = [name for name in fields if message_field(msg, name) is None]
        if missing:
            raise DeclaredTypeError(declared, f"it has no {', '.join(missing)}")
        try:
            height, step = int(message_field(msg, "height")), int(message_field(msg, step_name))
            n_bytes = _byte_length(message_field(msg, "data"))
        except (TypeError, ValueError) as exc:
            raise DeclaredTypeError(declared, error_reason(exc)) from None
        if height * step != n_bytes:
            raise DeclaredTypeError(
                declared,
                f"damaged {kind}: height {height} x {step_name} {step} = {height * step} bytes, "
                f"but it carries {n_bytes}",
            )
    return msg


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
            schema_name=schema_name(schemas.get(ch.schema_id)),
            schema_encoding=schemas[ch.schema_id].encoding if ch.schema_id in schemas else "",
            message_encoding=ch.message_encoding,
            message_count=counts.get(cid, 0),
        )
        for cid, ch in channels.items()
    )
    return McapSummary(
        path=path,
        profile=profile,
        library=library,
        channels=infos,
        message_count=n,
        start_ns=start,
        end_ns=end,
        indexed=False,
        chunk_count=0,
        damage=damage,
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
                schema_name=schema_name(summary.schemas.get(ch.schema_id)),
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
    anything with ``path``, ``topics()``, ``pointcloud_topics()``, ``image_topics()``,
    ``depth_topics()`` and ``damage``.

    An MCAP log with no point-cloud topic may hold depth images instead: its one depth
    image topic is read (`--topic` names it when there are several)."""
    path = summary.path
    if topic is not None:
        types = dict(summary.topics())
        if topic not in types:
            raise InputError(f"{path}: no topic {topic!r}; topics: {_topic_list(summary)}")
        if types[topic] in IMAGE_SCHEMAS:
            return topic  # a depth image topic (its encoding is checked when read)
        if types[topic] in COMPRESSED_SCHEMAS:
            raise InputError(
                f"{path}: topic {topic} holds compressed images ({types[topic]}); clear reads raw depth images "
                "(sensor_msgs/Image 16UC1 or 32FC1): record the raw topic, or decompress the log first"
            )
        if types[topic] not in POINTCLOUD_SCHEMAS:
            raise InputError(
                f"{path}: topic {topic} has type {types[topic] or 'unknown'}, not a point cloud "
                f"({', '.join(sorted(POINTCLOUD_SCHEMAS))})"
            )
        return topic
    # Depth image topics are frame topics as point-cloud topics are, in a damaged log as
    # in an intact one: a cut RGB-D log keeps its whole frames like a cut point-cloud log.
    candidates = summary.frame_topics()
    if not candidates and summary.damage is not None:
        what = getattr(summary, "what", "MCAP log")
        raise InputError(
            f"{path}: truncated or corrupt {what}: it breaks {summary.damage} before any "
            f"frame topic (point cloud or depth image); topics seen: {_topic_list(summary)}"
        )
    if candidates and not summary.pointcloud_topics():
        if len(candidates) > 1:
            raise InputError(f"{path}: several depth image topics ({', '.join(candidates)}); choose one with --topic")
        return candidates[0]
    if not candidates:
        compressed = [t for t, s in summary.topics() if s in COMPRESSED_SCHEMAS and "depth" in t.lower()]
        if compressed:
            raise InputError(
                f"{path}: depth is recorded only compressed ({', '.join(compressed)}); clear reads raw depth images "
                "(sensor_msgs/Image 16UC1 or 32FC1): record the raw topic, or decompress the log first"
            )
        hint = "; for an image topic holding depth, name it with --topic" if summary.image_topics() else ""
        raise InputError(f"no point-cloud topic in {path}; topics: {_topic_list(summary)}{hint}")
    if len(candidates) > 1:
        raise InputError(f"{path}: several point-cloud topics ({', '.join(candidates)}); choose one with --topic")
    return candidates[0]


# --- decoding -------------------------------------------------------------------------


def _message_frame(
    decoders: MessageDecoders,
    schema: Any,
    channel: Any,
    message: Any,
    index: int,
    path: Path,
    images: Any = None,
    summary: McapSummary | None = None,
) -> Frame:
    source = f"{path.name}#{index} {channel.topic}"
    decode = decoders.decoder(schema, channel)
    msg = decode_declared(schema_name(schema), lambda: decode(message.data))
    if schema_name(schema) in IMAGE_SCHEMAS:
        assert summary is not None
        return depth_frame(McapAccess(path, summary, decoders), channel.topic, msg, message.log_time, source, images)
    if schema_name(schema) in POINTCLOUD2_SCHEMAS:
        return pointcloud2_frame(msg, message.log_time, source)
    return foxglove_frame(msg, message.log_time, source)


# --- iteration ------------------------------------------------------------------------


def raw_messages(path: Path, summary: McapSummary, topic: str) -> Iterator[tuple[Any, Any, Any]]:
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


_T = TypeVar("_T")


def until_damage(messages: Iterator[_T]) -> Iterator[_T]:
    """``messages`` up to where the log breaks, ending there quietly. For what a frame is
    paired with (its camera info, its colour): a damaged log's frames before the damage
    keep it, and the frames' own reader reports the damage (exit 9 after them)."""
    try:
        while True:
            try:
                item = next(messages)
            except StopIteration:
                return
            except InputError:  # the log cannot be opened at all: not damage past frames
                raise
            except Exception:  # EndOfFile, CRC and decompression errors, ROS 1 Damage...
                return
            yield item
    finally:
        close = getattr(messages, "close", None)
        if close is not None:
            close()


class McapAccess:
    """An MCAP log's decoded messages by topic: the log interface
    (`clearcli.io.log_access.LogAccess`) for readers that pair messages of several topics
    (a depth image with its camera info and colour: clearcli/io/mcap_images.py). The bag
    readers offer the same (`clearcli.io.rosbag.BagAccess`)."""

    def __init__(self, path: Path, summary: McapSummary, decoders: MessageDecoders | None = None) -> None:
        self.path, self.summary = path, summary
        self.decoders = decoders or MessageDecoders()
        self.can_seek = summary.indexed

    def decoded(self, topic: str) -> Generator[Decoded, None, None]:
        """(schema name, message, log time ns) of ``topic``, up to any damage."""
        for schema, channel, message in until_damage(raw_messages(self.path, self.summary, topic)):
            yield schema_name(schema), self.decoders.decode(schema, channel, message.data), int(message.log_time)

    def window(self, topic: str, start_ns: int, end_ns: int) -> Generator[Decoded, None, None]:
        """The same for messages logged in [start_ns, end_ns] (seeks: the log is indexed),
        up to any damage (a corrupt chunk near a whole frame costs it its colour, not the frame)."""
        from mcap.reader import SeekingReader

        with _open(self.path) as fp:
            for schema, channel, message in until_damage(
                SeekingReader(fp).iter_messages(topics=[topic], starting_at=start_ns, ending_at=end_ns)
            ):
                yield schema_name(schema), self.decoders.decode(schema, channel, message.data), int(message.log_time)


def _guarded(path: Path, summary: McapSummary, topic: str) -> Iterator[tuple[int, Any, Any, Any]]:
    """Raw messages numbered from 0; damage after k messages -> PartialLogError (k > 0).
    Fewer messages than an intact summary counts is damage too, never a quiet end."""
    it = raw_messages(path, summary, topic)
    index = 0
    while True:
        try:
            schema, channel, message = next(it)
        except StopIteration:
            total = summary.count(topic)
            if summary.damage is None and index < total:
                # the summary promises more: never a quiet end short of it
                _raise_damage(
                    path, topic, index, f"its summary counts {total} messages on {topic}, the log holds {index}"
                )
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


def iter_mcap_frames(path: Path, topic: str | None = None, images: Any = None) -> Iterator[Frame]:
    """Every frame of the point-cloud topic, decoded one message at a time."""
    path = Path(path)
    summary = read_summary(path)
    topic = choose_topic(summary, topic)
    decoders = MessageDecoders()
    for index, schema, channel, message in _guarded(path, summary, topic):
        try:
            frame = _message_frame(decoders, schema, channel, message, index, path, images, summary)
        except DeclaredTypeError as exc:  # all of it: it names the type and what to do
            _raise_damage(path, topic, index, f"message {index} {exc}; {_TYPE_REMEDY}")
        except Exception as exc:  # bad input included: exit 3 at the first frame, 9 after complete ones
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


@contextmanager
def decoding_frame(path: Path, topic: str, index: int, remedy: Callable[[], str]) -> Iterator[None]:
    """What goes wrong decoding frame ``index`` of ``topic`` (--frame) as one InputError
    naming it: a message that is not its declared type with ``remedy()`` (what to do
    about it), anything else as "cannot be decoded"; an InputError as it is."""
    try:
        yield
    except InputError:
        raise
    except DeclaredTypeError as exc:
        raise InputError(f"{path}: frame {index} of {topic} {exc}; {remedy()}") from None
    except Exception as exc:
        raise InputError(f"{path}: frame {index} of {topic} cannot be decoded ({error_reason(exc)})") from None


def read_mcap_frame(path: Path, topic: str | None = None, index: int = 0, images: Any = None) -> Frame:
    """Frame `index` (from 0) of the point-cloud topic; only that message is decoded."""
    path = Path(path)
    summary = read_summary(path)
    topic = choose_topic(summary, topic)
    require_frame_index(path, summary, topic, index)
    decoders = MessageDecoders()
    seen = 0
    for i, schema, channel, message in _guarded(path, summary, topic):
        seen = i + 1
        if i == index:
            with decoding_frame(path, topic, index, lambda: _TYPE_REMEDY):
                return _message_frame(decoders, schema, channel, message, index, path, images, summary)
    if summary.damage is not None:
        _raise_damage(path, topic, seen, f"frame {index} is past the damage; the log is {summary.damage}")
    raise InputError(f"{path}: --frame {index} does not exist: {topic} has {seen} frames")


# --- transforms -------------------------------------------------------------------------

TF_TOPICS = ("/tf_static", "/tf")


def _tf_matrix(translation: Any, rotation: Any) -> Any:
    q = [float(message_field(rotation, k) or 0.0) for k in ("x", "y", "z", "w")]
    return pose_to_matrix([float(message_field(translation, k) or 0.0) for k in ("x", "y", "z")], q)


def read_mcap_transforms(path: Path, max_messages: int = 1000) -> dict[tuple[str, str], Any]:
    """T_parent_child (4x4) of every (parent, child) pair on the log's /tf_static and /tf
    (tf2_msgs/TFMessage, foxglove.FrameTransform(s)): the first seen of each; at most
    ``max_messages`` transform messages are read. A log without them, or whose transforms
    cannot be read, gives {} (what `clearcli.io.rosbag.read_bag_transforms` gives for a bag)."""
    try:
        summary = read_summary(path)
    except ClearError:
        return {}
    topics = [t for t, _ in summary.topics() if t in TF_TOPICS]
    if not topics:
        return {}
    from mcap.reader import NonSeekingReader, SeekingReader

    found: dict[tuple[str, str], Any] = {}
    decoders = MessageDecoders()
    try:
        with open(path, "rb") as fp:
            reader: Any = SeekingReader(fp) if summary.indexed else NonSeekingReader(fp)
            for count, (schema, channel, message) in enumerate(reader.iter_messages(topics=topics)):
                if count >= max_messages:
                    break
                try:
                    msg = decoders.decode(schema, channel, message.data)
                except Exception:
                    continue
                items = message_field(msg, "transforms")
                for tf in items if items is not None else [msg]:
                    try:
                        header = message_field(tf, "header")
                        parent = (
                            message_field(header, "frame_id")
                            if header is not None
                            else message_field(tf, "parent_frame_id")
                        )
                        child = message_field(tf, "child_frame_id")
                        inner = message_field(tf, "transform") or tf
                        T = _tf_matrix(message_field(inner, "translation"), message_field(inner, "rotation"))
                    except Exception:
                        continue
                    if parent and child:
                        found.setdefault((str(parent).lstrip("/"), str(child).lstrip("/")), T)
    except Exception:  # a damaged log: whatever was read before the damage
        pass
    return found
