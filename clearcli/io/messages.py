"""Decoded log messages -> `Frame`s: one definition of what a `sensor_msgs/PointCloud2`
or a `foxglove.PointCloud` becomes, shared by the MCAP and the bag readers.

Messages are decoded with mcap's own decoder factories (one per schema, built lazily);
the point blob inside each message is viewed through a NumPy structured dtype (offsets,
point_step, row_step, byte order from the message), never walked point by point.
foxglove.PointCloud carries a `pose` of the points in `frame_id`; it is APPLIED, so every
Frame's points are in its `frame_id` like PointCloud2's.
"""

from __future__ import annotations

import base64
import contextlib
import json
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from clearcli.errors import InputError
from clearcli.io.frames import Frame
from clearcli.io.pointfields import (
    FOXGLOVE_TYPE_NAMES,
    FOXGLOVE_TYPES,
    ROS_DATATYPES,
    FieldSpec,
    check_specs,
    frame_from_records,
    records_from_blob,
)
from clearcli.transforms import quat_to_matrix


def schema_name(schema: Any) -> str:
    return schema.name if schema is not None else ""


class MessageDecoders:
    """mcap decoder factories, built lazily, one decoder per schema."""

    def __init__(self) -> None:
        self._cache: dict[tuple[int, str], Callable[[bytes], Any]] = {}

    def decode(self, schema: Any, channel: Any, data: bytes) -> Any:
        return self.decoder(schema, channel)(data)

    def decoder(self, schema: Any, channel: Any) -> Callable[[bytes], Any]:
        """The function that decodes ``channel``'s messages; raises when clear has no
        decoder for its encoding or schema (apart from a message that fails to decode)."""
        encoding = channel.message_encoding
        if encoding == "json":
            return json.loads
        key = (schema.id if schema is not None else 0, encoding)
        decoder = self._cache.get(key)
        if decoder is None:
            decoder = self._make(schema, encoding)
            self._cache[key] = decoder
        return decoder

    @staticmethod
    def _make(schema: Any, encoding: str) -> Callable[[bytes], Any]:
        decoder: Callable[[bytes], Any] | None
        if encoding == "cdr":
            from mcap_ros2.decoder import DecoderFactory as Ros2Decoders

            decoder = Ros2Decoders().decoder_for(encoding, schema)
        elif encoding == "ros1":
            from mcap_ros1.decoder import DecoderFactory as Ros1Decoders

            decoder = Ros1Decoders().decoder_for(encoding, schema)
        elif encoding == "protobuf":
            from mcap_protobuf.decoder import DecoderFactory as ProtobufDecoders

            decoder = ProtobufDecoders().decoder_for(encoding, schema)
        else:
            raise ValueError(f"unsupported message encoding {encoding!r}")
        if decoder is None:
            raise ValueError(f"no decoder for {encoding} schema {schema_name(schema)!r}")
        return decoder


def message_field(msg: Any, *names: str, default: Any = None) -> Any:
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
        sec = message_field(stamp, "sec", "secs", "seconds", default=0) or 0
        nsec = message_field(stamp, "nanosec", "nsecs", "nsec", "nanos", default=0) or 0
        if hasattr(stamp, "to_nsec") and not isinstance(stamp, dict):
            with contextlib.suppress(Exception):
                total = int(stamp.to_nsec())
                sec, nsec = divmod(total, 1_000_000_000)
        if int(sec) != 0 or int(nsec) != 0:
            return int(sec) + int(nsec) * 1e-9
    return log_time_ns * 1e-9


def _as_bytes(data: Any) -> bytes | bytearray | memoryview:
    if isinstance(data, (bytes, bytearray, memoryview)):
        return data
    if isinstance(data, str):  # json: base64
        return base64.b64decode(data)
    if isinstance(data, np.ndarray):
        return data.tobytes()
    return bytes(data)


def pointcloud2_frame(msg: Any, log_time_ns: int, source: str) -> Frame:
    header = message_field(msg, "header")
    height, width = int(msg.height), int(msg.width)
    point_step, row_step = int(msg.point_step), int(msg.row_step)
    n_bytes = len(_as_bytes(msg.data))
    # A message checked against itself: what it says of its layout must add up to the
    # data it carries (a height of 0 with data, a halved width, a row_step or data cut
    # short is a damaged message, never read as if whole).
    if height * row_step != n_bytes:
        raise ValueError(
            f"damaged PointCloud2: height {height} x row_step {row_step} = {height * row_step} bytes, "
            f"but the message carries {n_bytes}"
        )
    if width * point_step > row_step:
        raise ValueError(f"damaged PointCloud2: width {width} x point_step {point_step} exceeds row_step {row_step}")
    specs = []
    for f in msg.fields:
        code = ROS_DATATYPES.get(int(f.datatype))
        if code is None:  # unknown datatype: its bytes are skipped, the rest still decodes
            continue
        specs.append(FieldSpec(str(f.name), int(f.offset), code, max(int(f.count), 1)))
    return _frame_from_blob(
        msg.data,
        specs,
        point_step,
        width,
        height,
        row_step,
        bool(msg.is_bigendian),
        shape=(height, width) if height > 1 else None,
        stamp_s=_stamp_s(message_field(header, "stamp"), log_time_ns),
        frame_id=str(message_field(header, "frame_id", default="") or ""),
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
    stride = int(message_field(msg, "point_stride", default=0) or 0)
    specs = []
    for f in message_field(msg, "fields", default=[]) or []:
        type_value = message_field(f, "type", default=0)
        if isinstance(type_value, str):
            type_value = FOXGLOVE_TYPE_NAMES.get(type_value.upper(), 0)
        code = FOXGLOVE_TYPES.get(int(type_value))
        if code is None:
            continue
        specs.append(FieldSpec(str(message_field(f, "name")), int(message_field(f, "offset", default=0) or 0), code))
    data = _as_bytes(message_field(msg, "data", default=b""))
    if stride <= 0:
        raise ValueError(f"point_stride is {stride}")
    n = len(data) // stride
    frame = _frame_from_blob(
        data,
        specs,
        stride,
        n,
        1,
        n * stride,
        False,
        shape=None,
        stamp_s=_stamp_s(message_field(msg, "timestamp"), log_time_ns),
        frame_id=str(message_field(msg, "frame_id", default="") or ""),
        source=source,
    )
    pose = message_field(msg, "pose")
    if pose is None:
        return frame
    pos = message_field(pose, "position")
    ori = message_field(pose, "orientation")
    t = np.array([float(message_field(pos, a, default=0.0) or 0.0) for a in "xyz"]) if pos is not None else np.zeros(3)
    q = [float(message_field(ori, a, default=0.0) or 0.0) for a in "xyzw"] if ori is not None else [0, 0, 0, 1]
    if ori is not None and not any(q):
        q = [0.0, 0.0, 0.0, 1.0]  # protobuf leaves an all-default quaternion empty
    R = quat_matrix(q)
    if np.allclose(R, np.eye(3)) and not t.any():
        return frame
    points = (frame.points.astype(np.float64) @ R.T + t).astype(np.float32)
    return Frame(
        points=points,
        colors=frame.colors,
        shape=frame.shape,
        fields=frame.fields,
        stamp_s=frame.stamp_s,
        frame_id=frame.frame_id,
        source=frame.source,
    )


def _frame_from_blob(
    data: Any,
    specs: list[FieldSpec],
    point_step: int,
    width: int,
    height: int,
    row_step: int,
    big_endian: bool,
    *,
    shape: tuple[int, int] | None,
    stamp_s: float,
    frame_id: str,
    source: str,
) -> Frame:
    problem = check_specs(specs, point_step)
    if problem:
        raise ValueError(problem)
    names = {s.name for s in specs}
    if not {"x", "y", "z"} <= names:
        raise ValueError(f"the message has no x/y/z fields (fields: {' '.join(sorted(names)) or 'none'})")
    records = records_from_blob(_as_bytes(data), specs, point_step, width, height, row_step, big_endian)
    return frame_from_records(records, shape, stamp_s=stamp_s, frame_id=frame_id, source=source)
