"""ROS 1 bags and rosbag2 bags <-> `Frame`s, one message at a time, with `rosbags`.

Reading, what `clearcli.io.mcap` offers for MCAP logs: `read_bag_summary` (topics, types,
counts, time span), `choose_bag_topic` (the same topic rules and messages),
`iter_bag_frames` and `read_bag_frame`, and `read_bag_transforms` (/tf_static and /tf).

- ROS 1 (`#ROSBAG V2.0`, a `.bag` file): an intact bag is read through its index with
  `rosbags.rosbag1.Reader`, one chunk in memory at a time; `--frame N` seeks straight to
  the chunk holding message N. A bag whose index is missing or unreadable (a recording cut
  short, a truncated copy, an unindexed bag) is streamed record by record in file order
  by this module instead; when the records stop making sense it raises PartialLogError
  after yielding every complete frame (InputError when there is none). A connection whose
  md5sum is not that of the standard type it names is damage too (the header names
  another type than its messages are).
- rosbag2 (a folder holding `metadata.yaml`, or its `.db3` sqlite storage file alone):
  `rosbags.rosbag2.Reader`, sqlite3 and mcap storage; messages come from a database
  cursor or one MCAP chunk at a time (a bag compressed per file is first unpacked by
  rosbags into a temporary folder). A `.mcap` storage file alone is an MCAP log, read by
  `clearcli.io.mcap`, which also reads a damaged one up to its damage. Every message of a
  topic is read even where metadata.yaml declares another type for it than its storage
  file records (rosbags would pass them over), and decoded as declared: a disagreement
  is damage (exit 3, or 9 after complete frames), never frames silently lost.

Messages are deserialised with a `rosbags.typesys` type store built from the bag's own
message definitions when it carries them (else the standard ROS 1 Noetic / ROS 2 types);
the PointCloud2 point blob is then viewed through a NumPy structured dtype by the MCAP
reader's own PointCloud2 / foxglove converters, so every format agrees on what a point
cloud becomes. Only ClearError subclasses leave the public functions.
"""

from __future__ import annotations

import contextlib
import heapq
import os
from collections.abc import Generator, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO, Literal

import numpy as np

from clearcli.errors import InputError, PartialLogError
from clearcli.io.bag_messages import BagDecoders, _ZeroCopy, bag_frame
from clearcli.io.frames import Frame
from clearcli.io.image_messages import IMAGE_SCHEMAS
from clearcli.io.log_access import Decoded
from clearcli.io.mcap import (
    ChannelInfo,
    DeclaredTypeError,
    McapSummary,
    choose_topic,
    decode_declared,
    decoding_frame,
    error_reason,
    require_frame_index,
    until_damage,
)
from clearcli.io.mcap_images import depth_frame
from clearcli.io.messages import quat_matrix
from clearcli.io.ros1 import Damage, Ros1Msg, Ros1Stream
from clearcli.io.sniff import ROSBAG1_MAGIC, ROSBAG2_METADATA, open_input

TF_TOPICS = ("/tf_static", "/tf")

BagFormat = Literal["rosbag1", "rosbag2"]


@dataclass(frozen=True)
class BagSummary(McapSummary):
    """What a bag holds: an `mcap.McapSummary` (same attributes and methods) plus the bag's
    format and storage.

    channels: one per ROS 1 connection / rosbag2 topic; `schema_name` is the type as the
    bag spells it (ROS 1 `sensor_msgs/PointCloud2`, ROS 2 `sensor_msgs/msg/PointCloud2`).
    ``indexed`` for ROS 1: read through the index (else a scan of the records).
    """

    format: BagFormat = "rosbag1"
    storage: str = "rosbag1"  # "rosbag1", "sqlite3", "mcap"

    @property
    def what(self) -> str:
        return "ROS 1 bag" if self.format == "rosbag1" else "rosbag2 bag"


def _plural(n: int, word: str) -> str:
    return f"{n} {word}{'s' if n != 1 else ''}"


def _ros1_name(msgtype: str) -> str:
    """rosbags' normalised `pkg/msg/Type` -> ROS 1's `pkg/Type`."""
    return msgtype.replace("/msg/", "/", 1)


def _normalize(msgtype: str) -> str:
    from rosbags.typesys.msg import normalize_msgtype

    return normalize_msgtype(msgtype)


def bag_root(path: Path) -> Path:
    """The rosbag2 bag `path` names: the folder itself, the folder of a metadata.yaml, or a .db3."""
    path = Path(path)
    if path.is_file() and path.name == ROSBAG2_METADATA:
        return path.parent
    return path


# --- summaries --------------------------------------------------------------------------


def _open_file(path: Path) -> BinaryIO:
    return open_input(path, "a ROS 1 bag")


def _ros1_channels(conns: list[tuple[int, str, str, str, int]]) -> tuple[ChannelInfo, ...]:
    """(id, topic, ROS 1 type, msgdef, count) -> ChannelInfo."""
    return tuple(
        ChannelInfo(
            id=cid,
            topic=topic,
            schema_name=msgtype,
            schema_encoding="ros1msg" if msgdef else "",
            message_encoding="ros1",
            message_count=n,
        )
        for cid, topic, msgtype, msgdef, n in conns
    )


def _ros1_bag(
    path: Path,
    channels: tuple[ChannelInfo, ...],
    n: int,
    start: int | None,
    end: int | None,
    *,
    indexed: bool,
    chunk_count: int,
    damage: str | None = None,
) -> BagSummary:
    """The summary of a ROS 1 bag (format V2.0, the only one read) of ``n`` messages
    stamped ``start`` to ``end`` (ns; None without messages)."""
    return BagSummary(
        path=path,
        format="rosbag1",
        storage="rosbag1",
        profile="ros1",
        library="ROS 1 bag V2.0",
        channels=channels,
        message_count=n,
        start_ns=start,
        end_ns=end,
        indexed=indexed,
        chunk_count=chunk_count,
        damage=damage,
    )


def _ros1_scan(path: Path) -> BagSummary:
    """Connections, counts and span from the records themselves (no usable index)."""
    counts: dict[int, int] = {}
    n = 0
    start = end = None
    damage = None
    with _open_file(path) as fp:
        stream = Ros1Stream(fp, os.fstat(fp.fileno()).st_size, lambda conn: False)
        try:
            for item in stream.records():
                if isinstance(item, Ros1Msg):
                    counts[item.conn] = counts.get(item.conn, 0) + 1
                    n += 1
                    start = item.time_ns if start is None else min(start, item.time_ns)
                    end = item.time_ns if end is None else max(end, item.time_ns)
        except Damage as exc:
            damage = f"after {_plural(n, 'complete message')} ({exc})"
        except Exception as exc:  # anything else a garbage byte can provoke
            damage = f"after {_plural(n, 'complete message')} ({error_reason(exc)})"
    channels = _ros1_channels(
        [(c.id, c.topic, c.msgtype, c.msgdef, counts.get(c.id, 0)) for c in stream.conns.values()]
    )
    return _ros1_bag(path, channels, n, start, end, indexed=False, chunk_count=stream.chunks, damage=damage)


def _ros1_reader(path: Path) -> Any | None:
    """An open rosbags.rosbag1.Reader, or None when the bag's index cannot be used."""
    from rosbags.rosbag1 import Reader

    reader = Reader(path)
    try:
        reader.open()
    except Exception:  # ReaderError (no/damaged index), struct.error, AssertionError...
        return None
    return reader


def _ros1_summary(path: Path) -> BagSummary:
    with _open_file(path) as fp:  # missing file, directory, permissions: one clear message
        magic = fp.readline(64).rstrip(b"\n")
    if magic.startswith(ROSBAG1_MAGIC) and magic != b"#ROSBAG V2.0":
        version = magic[len(ROSBAG1_MAGIC) :].decode("latin-1", "replace").strip() or "unknown"
        raise InputError(f"{path}: a ROS 1 bag of format {version}; only V2.0 bags (ROS Groovy and later) are read")
    reader = _ros1_reader(path)
    if reader is None:
        return _ros1_scan(path)
    try:
        conns = sorted(reader.connections, key=lambda c: c.id)
        channels = _ros1_channels([(c.id, c.topic, _ros1_name(c.msgtype), c.msgdef.data, c.msgcount) for c in conns])
        n = sum(c.msgcount for c in conns)
        start = int(reader.start_time) if n else None
        end = int(reader.end_time) - 1 if n else None  # rosbags' end_time is exclusive
        return _ros1_bag(path, channels, n, start, end, indexed=True, chunk_count=len(reader.chunk_infos))
    finally:
        reader.close()


def _rosbag2_reader(path: Path) -> Any:
    """An open rosbags.rosbag2.Reader on a bag folder or a .db3 file; InputError otherwise."""
    from rosbags.rosbag2 import Reader

    root = bag_root(path)
    if root.is_file() and root.suffix != ".db3":
        raise InputError(
            f"{path}: an SQLite file but not named .db3; rosbag2 sqlite storage is read from a "
            f".db3 file or from its bag folder (with {ROSBAG2_METADATA})"
        )
    try:
        reader = Reader(root)
        reader.open()
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except PermissionError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror})") from None
    except Exception as exc:  # ReaderError (bad metadata, missing .db3, unsupported), apsw errors
        hint = ""
        if root.is_dir():
            mcaps = sorted(p.name for p in root.glob("*.mcap"))
            if mcaps:  # clearcli's MCAP reader gives what precedes damage in an MCAP file
                hint = f"; its MCAP storage can be read up to any damage: pass {root / mcaps[0]} itself"
        raise InputError(f"{path}: cannot read the rosbag2 bag ({error_reason(exc)}){hint}") from None
    return reader


def _rosbag2_storage(reader: Any) -> str:
    storage = reader.storage
    inner = getattr(storage, "storages", None) or [storage]
    name = type(inner[0]).__name__
    return {"Sqlite3Reader": "sqlite3", "McapReader": "mcap"}.get(name, name)


def _rosbag2_summary(path: Path) -> BagSummary:
    reader = _rosbag2_reader(path)
    try:
        conns = list(reader.connections)
        for c in conns:
            # rosbags takes metadata.yaml's values as they are: a list or a number where a
            # name belongs would fail later, far from its cause
            if not (isinstance(c.topic, str) and isinstance(c.msgtype, str)):
                raise InputError(
                    f"{path}: {ROSBAG2_METADATA} gives a topic whose name ({c.topic!r}) or type ({c.msgtype!r}) "
                    "is not text; fix the bag's metadata"
                )
        channels = tuple(
            ChannelInfo(
                id=c.id,
                topic=c.topic,
                schema_name=c.msgtype,
                schema_encoding={"MSG": "ros2msg", "IDL": "ros2idl"}.get(c.msgdef.format.name, ""),
                message_encoding=getattr(c.ext, "serialization_format", "cdr"),
                message_count=int(c.msgcount),
            )
            for c in conns
        )
        n = int(reader.message_count)
        storage = _rosbag2_storage(reader)
        distro = reader.ros_distro
        compression = reader.compression_mode
        library = (
            f"rosbag2, {storage} storage"
            + (f", {distro}" if distro else "")
            + (f", {reader.compression_format} {compression} compression" if compression else "")
        )
        return BagSummary(
            path=path,
            format="rosbag2",
            storage=storage,
            profile="ros2",
            library=library,
            channels=channels,
            message_count=n,
            start_ns=int(reader.start_time) if n else None,
            end_ns=int(reader.end_time) - 1 if n else None,
            indexed=True,
            chunk_count=0,
        )
    except InputError:
        raise
    except Exception as exc:
        raise InputError(f"{path}: cannot read the rosbag2 bag ({error_reason(exc)})") from None
    finally:
        reader.close()


def bag_format(path: Path) -> BagFormat:
    """ "rosbag1" for a #ROSBAG file, else "rosbag2" (a folder, its metadata.yaml, a .db3)."""
    path = Path(path)
    if path.is_file() and path.name != ROSBAG2_METADATA:
        with _open_file(path) as fp:
            if fp.read(len(ROSBAG1_MAGIC)) == ROSBAG1_MAGIC:
                return "rosbag1"
    return "rosbag2"


def read_bag_summary(path: Path) -> BagSummary:
    """Topics, types, counts and time span of a ROS 1 bag or a rosbag2 bag (InputError if neither)."""
    path = Path(path)
    return _ros1_summary(path) if bag_format(path) == "rosbag1" else _rosbag2_summary(path)


def choose_bag_topic(summary: BagSummary, topic: str | None) -> str:
    """The point-cloud topic to read: the rules and messages of MCAP logs."""
    return choose_topic(summary, topic)


# --- iteration --------------------------------------------------------------------------

# One raw message: (normalised type, definition, definition format, data, log time ns,
# the connection's md5sum: ROS 1 only, else "").
_Raw = tuple[str, str, str, "bytes | memoryview", int, str]


def _ros1_indexed(reader: Any, topic: str, skip_to: int = 0) -> Iterator[_Raw]:
    """Messages of `topic` through the index, in time order, from message `skip_to` on.

    Skipping uses the index: chunks before message `skip_to` are neither read nor
    decompressed.
    """
    conns = [c for c in reader.connections if c.topic == topic]
    start = None
    skip = 0
    if skip_to > 0:
        entries = heapq.merge(*(reader.indexes[c.id] for c in conns))
        times = [e.time for _, e in zip(range(skip_to + 1), entries)]
        if len(times) <= skip_to:
            return  # the index holds no message `skip_to`
        start = times[-1]
        skip = skip_to - sum(1 for t in times[:-1] if t < start)
    for i, (conn, time_ns, data) in enumerate(reader.messages(connections=conns, start=start)):
        if i < skip:
            continue
        yield conn.msgtype, conn.msgdef.data, "MSG", data, int(time_ns), conn.digest


def _ros1_streamed(path: Path, topic: str) -> Iterator[_Raw]:
    """Messages of `topic` in file order (no usable index); Damage where the bag breaks."""
    with _open_file(path) as fp:
        stream = Ros1Stream(fp, os.fstat(fp.fileno()).st_size, lambda conn: conn.topic == topic)
        for item in stream.records():
            if isinstance(item, Ros1Msg) and item.data is not None:
                conn = stream.conns[item.conn]
                yield _normalize(conn.msgtype), conn.msgdef, "MSG", item.data, item.time_ns, conn.md5sum


def _stored(reader: Any, topic: str) -> list[Any]:
    """The connections the storage files of a rosbag2 folder record for ``topic`` (with
    their own types); [] for a storage file read alone (its connections are its own)."""
    storages = getattr(reader.storage, "storages", None) or []
    return [s for storage in storages for s in storage.connections if s.topic == topic]


def _asked(reader: Any, conns: list[Any]) -> list[Any]:
    """What to ask rosbags for, to get every message of ``conns`` (metadata.yaml's). It
    passes over, without a word, the messages whose storage file records another type for
    their topic than metadata.yaml declares: asked with the stored type (and its hash and
    QoS, which it compares too), it gives them all, under the declared connection's id,
    to be decoded as the declared type, where a disagreement shows (DeclaredTypeError)."""
    asked: list[Any] = []
    for conn in conns:
        for stored in _stored(reader, conn.topic) or [conn]:
            mine = conn._replace(msgtype=stored.msgtype, digest=stored.digest, ext=stored.ext)
            if mine not in asked:
                asked.append(mine)
    return asked


def _rosbag2_messages(path: Path, topic: str) -> Iterator[_Raw]:
    reader = _rosbag2_reader(path)
    try:
        declared = {c.id: c for c in reader.connections if c.topic == topic}
        for asked, time_ns, data in reader.messages(connections=_asked(reader, list(declared.values()))):
            conn = declared[asked.id]
            yield conn.msgtype, conn.msgdef.data, conn.msgdef.format.name, data, int(time_ns), ""
    finally:
        reader.close()


def _type_remedy(summary: BagSummary, topic: str) -> str:
    """What to do about messages on ``topic`` that are not their declared type."""
    if summary.format == "rosbag1":
        return (
            "the bag is damaged, or its connection header names another type than its messages are: "
            "re-record it, or rewrite the connection with the type (and md5sum) of what it holds"
        )
    declared = {ch.schema_name for ch in summary.channels if ch.topic == topic}
    try:
        reader = _rosbag2_reader(summary.path)
        try:
            stored = sorted({s.msgtype for s in _stored(reader, topic)} - declared)
        finally:
            reader.close()
    except Exception:  # a hint only
        stored = []
    records = f" (its storage file records {', '.join(stored)})" if stored else ""
    return (
        f"the bag is damaged, or its {ROSBAG2_METADATA} declares another type for the topic than its "
        f"messages are{records}: correct the type in {ROSBAG2_METADATA}, or re-record the bag"
    )


def _seeks(summary: BagSummary) -> bool:
    """Whether frame N is found through the bag's index (else by reading the ones before)."""
    return summary.format == "rosbag1" and summary.indexed


def _raw_messages(summary: BagSummary, topic: str, skip_to: int = 0) -> Generator[tuple[int, _Raw], None, None]:
    """(index, raw message) of `topic`: from message `skip_to` on when the bag seeks
    (`_seeks`), else from message 0 (the caller passes over the first ones)."""
    path = summary.path
    if summary.format == "rosbag2":
        yield from enumerate(_rosbag2_messages(path, topic))
        return
    reader = _ros1_reader(path) if summary.indexed else None
    if reader is None:
        yield from enumerate(_ros1_streamed(path, topic))
        return
    try:
        yield from enumerate(_ros1_indexed(reader, topic, skip_to), start=skip_to)
    finally:
        reader.close()


def _raise_damage(summary: BagSummary, topic: str, complete: int, reason: str) -> None:
    path = summary.path
    if complete == 0:
        raise InputError(f"{path}: corrupt or truncated {summary.what}: no complete frame on {topic} ({reason})")
    raise PartialLogError(
        f"{path}: {summary.what} truncated or corrupt after frame {complete - 1} of {topic} "
        f"({complete} complete frame{'s' if complete != 1 else ''} read; {reason})"
    )


def _guarded(summary: BagSummary, topic: str, skip_to: int = 0) -> Iterator[tuple[int, _Raw]]:
    """Raw messages from `skip_to` on; damage after k complete messages -> PartialLogError
    (k > 0), else InputError. Messages passed over through the index count as complete."""
    it = _raw_messages(summary, topic, skip_to)
    complete = skip_to if _seeks(summary) else 0
    try:
        while True:
            try:
                index, raw = next(it)
            except StopIteration:
                total = summary.count(topic)
                if summary.damage is None and complete < total:
                    # the index promises more: never a quiet end short of it
                    _raise_damage(
                        summary,
                        topic,
                        complete,
                        f"its index counts {total} messages on {topic}, the bag holds {complete}",
                    )
                return
            except InputError:
                raise
            except Damage as exc:
                _raise_damage(summary, topic, complete, str(exc))
            except Exception as exc:  # rosbags ReaderError, apsw errors, struct.error...
                _raise_damage(summary, topic, complete, error_reason(exc))
            complete = index + 1
            if index >= skip_to:
                yield index, raw
    finally:
        it.close()


class BagAccess:
    """A bag's decoded messages by topic: the log interface
    (`clearcli.io.log_access.LogAccess`, what `clearcli.io.mcap.McapAccess` is for an MCAP
    log), for a depth image's camera info and colour (clearcli/io/mcap_images.py)."""

    def __init__(self, summary: BagSummary, decoders: BagDecoders) -> None:
        self.path, self.summary, self.decoders = summary.path, summary, decoders
        self.can_seek = summary.format == "rosbag2" or summary.indexed

    def _decoded(self, msgtype: str, msgdef: str, fmt: str, data: Any, time_ns: int) -> tuple[str, Any, int]:
        return msgtype, _ZeroCopy(self.decoders.decode(msgtype, msgdef, fmt, data)), int(time_ns)

    def decoded(self, topic: str) -> Generator[Decoded, None, None]:
        """(type, message, log time ns) of ``topic``, up to any damage."""
        for _, (msgtype, msgdef, fmt, data, time_ns, _md5) in until_damage(_raw_messages(self.summary, topic)):
            yield self._decoded(msgtype, msgdef, fmt, data, time_ns)

    def window(self, topic: str, start_ns: int, end_ns: int) -> Generator[Decoded, None, None]:
        """Messages of ``topic`` logged in [start_ns, end_ns], through the bag's index."""
        reader = _rosbag2_reader(self.path) if self.summary.format == "rosbag2" else _ros1_reader(self.path)
        if reader is None:
            return
        try:
            declared = {c.id: c for c in reader.connections if c.topic == topic}
            conns = list(declared.values())
            if self.summary.format == "rosbag2":
                conns = _asked(reader, conns)
            messages = reader.messages(connections=conns, start=start_ns, stop=end_ns + 1)
            for asked, time_ns, data in until_damage(messages):
                conn = declared[asked.id]
                fmt = "MSG" if self.summary.format == "rosbag1" else conn.msgdef.format.name
                yield self._decoded(conn.msgtype, conn.msgdef.data, fmt, data, time_ns)
        finally:
            reader.close()


def _decode(decoders: BagDecoders, summary: BagSummary, topic: str, index: int, raw: _Raw, images: Any = None) -> Frame:
    """The frame of one raw message; DeclaredTypeError when it is not its declared type
    (its ROS 1 md5sum is another type's, it does not decode as the type, or to the wrong size)."""
    msgtype, msgdef, fmt, data, time_ns, md5sum = raw
    source = f"{summary.path.name}#{index} {topic}"
    declared = _ros1_name(msgtype) if decoders.ros1 else msgtype  # as the bag spells it
    problem = decoders.md5_problem(msgtype, md5sum)
    if problem is not None:
        raise DeclaredTypeError(declared, problem)
    msg = decode_declared(declared, lambda: decoders.decode(msgtype, msgdef, fmt, data))
    if msgtype in IMAGE_SCHEMAS:
        return depth_frame(BagAccess(summary, decoders), topic, _ZeroCopy(msg), int(time_ns), source, images)
    return bag_frame(msgtype, msg, time_ns, source)


def iter_bag_frames(path: Path, topic: str | None = None, images: Any = None) -> Iterator[Frame]:
    """Every frame of the point-cloud topic, decoded one message at a time."""
    path = Path(path)
    summary = read_bag_summary(path)
    topic = choose_bag_topic(summary, topic)
    decoders = BagDecoders(ros1=summary.format == "rosbag1")
    for index, raw in _guarded(summary, topic):
        try:
            frame = _decode(decoders, summary, topic, index, raw, images)
        except DeclaredTypeError as exc:  # all of it: it names the type and what to do
            _raise_damage(summary, topic, index, f"message {index} {exc}; {_type_remedy(summary, topic)}")
        except Exception as exc:
            _raise_damage(summary, topic, index, f"message {index} cannot be decoded: {error_reason(exc)}")
        yield frame


def read_bag_frame(path: Path, topic: str | None = None, index: int = 0, images: Any = None) -> Frame:
    """Frame `index` (from 0) of the point-cloud topic; only that message is decoded."""
    path = Path(path)
    summary = read_bag_summary(path)
    topic = choose_bag_topic(summary, topic)
    require_frame_index(path, summary, topic, index)
    decoders = BagDecoders(ros1=summary.format == "rosbag1")
    for i, raw in _guarded(summary, topic, skip_to=index):
        if i == index:
            with decoding_frame(path, topic, index, lambda: _type_remedy(summary, topic)):
                return _decode(decoders, summary, topic, index, raw, images)
    total = summary.count(topic)
    if summary.damage is not None:
        _raise_damage(summary, topic, total, f"frame {index} is past the damage; the bag breaks {summary.damage}")
    raise InputError(f"{path}: --frame {index} does not exist: {topic} has {_plural(total, 'frame')}")


# --- transforms -------------------------------------------------------------------------


def read_bag_transforms(path: Path, max_messages: int = 1000) -> dict[tuple[str, str], np.ndarray]:
    """T_parent_child (4x4) of every (parent, child) pair on the bag's /tf_static and /tf.

    The first seen of each pair; at most `max_messages` transform messages are read. A bag
    without them, or whose transforms cannot be read, gives {} (what
    `clearcli.replay.session.read_transforms` gives for an MCAP log).
    """
    try:
        summary = read_bag_summary(Path(path))
    except InputError:
        return {}
    decoders = BagDecoders(ros1=summary.format == "rosbag1")
    found: dict[tuple[str, str], np.ndarray] = {}
    budget = max_messages
    present = dict(summary.topics())
    for topic in (t for t in TF_TOPICS if t in present):
        with contextlib.closing(_raw_messages(summary, topic)) as messages:
            try:
                for _, (msgtype, msgdef, fmt, data, _t, _md5) in messages:
                    if budget <= 0:
                        return found
                    budget -= 1
                    try:
                        items = list(decoders.decode(msgtype, msgdef, fmt, data).transforms)
                    except Exception:
                        continue
                    for tf in items:
                        pair, T = _transform(tf)
                        if T is not None:
                            found.setdefault(pair, T)
            except Exception:  # a damaged bag: whatever was read before the damage
                continue
    return found


def _transform(tf: Any) -> tuple[tuple[str, str], np.ndarray | None]:
    """((parent, child), T_parent_child) of a geometry_msgs/TransformStamped; T None if unusable."""
    try:
        pair = (str(tf.header.frame_id).lstrip("/"), str(tf.child_frame_id).lstrip("/"))
        r, t = tf.transform.rotation, tf.transform.translation
        q = [float(r.x), float(r.y), float(r.z), float(r.w)]
        if not all(pair) or not np.isfinite(q).all() or np.linalg.norm(q) < 1e-9:
            return pair, None
        T = np.eye(4)
        T[:3, :3] = quat_matrix(q)
        T[:3, 3] = [float(t.x), float(t.y), float(t.z)]
    except Exception:
        return ("", ""), None
    return pair, T
