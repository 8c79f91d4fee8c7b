"""Decoding the messages of ROS bags with `rosbags`: a type store per message definition
(the bag's own when it carries one, else ROS 1 Noetic's / the latest ROS 2's), built
lazily and kept for the process; the decoded PointCloud2 or foxglove cloud becomes a
Frame through `clearcli.io.messages`, its point blob viewed in place (no copy)."""

from __future__ import annotations

from typing import Any

import numpy as np

from clearcli.io.frames import Frame
from clearcli.io.mcap import POINTCLOUD2_SCHEMAS
from clearcli.io.messages import foxglove_frame, pointcloud2_frame

# Type stores by (ros1, type, definition), for the whole process: building one and
# generating its deserialisers costs tens of milliseconds, more than reading a frame.
_STORES: dict[tuple[bool, str, str], Any] = {}
_STANDARD: dict[bool, Any] = {}


class BagDecoders:
    """rosbags type stores, one per message definition, built lazily and kept.

    A type is taken from the definition the bag carries when there is one (a ROS 1
    connection always has it; newer rosbag2 bags too), else from the standard types of
    ROS 1 Noetic / the latest ROS 2.
    """

    def __init__(self, ros1: bool) -> None:
        self.ros1 = ros1

    def _standard_store(self) -> Any:
        from rosbags.typesys import Stores, get_typestore

        if self.ros1 not in _STANDARD:
            _STANDARD[self.ros1] = get_typestore(Stores.ROS1_NOETIC if self.ros1 else Stores.LATEST)
        return _STANDARD[self.ros1]

    def _store(self, msgtype: str, msgdef: str, fmt: str) -> Any:
        key = (self.ros1, msgtype, msgdef)
        store = _STORES.get(key)
        if store is None:
            store = self._standard_store()
            if msgdef and (self.ros1 or msgtype not in store.fielddefs):
                from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore

                try:
                    own = get_typestore(Stores.EMPTY)
                    types = get_types_from_idl(msgdef) if fmt == "IDL" else get_types_from_msg(msgdef, msgtype)
                    own.register(types)
                    if msgtype in own.fielddefs:
                        store = own
                except Exception:  # an unparsable definition: the standard types, if they have it
                    pass
            _STORES[key] = store
        return store

    def decode(self, msgtype: str, msgdef: str, fmt: str, data: bytes | memoryview) -> Any:
        store = self._store(msgtype, msgdef, fmt)
        if self.ros1:
            return store.deserialize_ros1(data, msgtype)
        return store.deserialize_cdr(data, msgtype)


def bag_frame(decoders: BagDecoders, msgtype: str, msgdef: str, fmt: str, data: bytes | memoryview,
           time_ns: int, source: str) -> Frame:
    msg = decoders.decode(msgtype, msgdef, fmt, data)
    if msgtype in POINTCLOUD2_SCHEMAS:
        return pointcloud2_frame(_ZeroCopy(msg), time_ns, source)
    return foxglove_frame(_ZeroCopy(msg), time_ns, source)


class _ZeroCopy:
    """A deserialised message whose `data` (a NumPy uint8 array) reads as a memoryview,
    so that the point blob is viewed in place rather than copied to bytes first."""

    def __init__(self, msg: Any) -> None:
        self._msg = msg
        data = getattr(msg, "data", b"")
        self.data = memoryview(data) if isinstance(data, np.ndarray) and data.flags.c_contiguous else data

    def __getattr__(self, name: str) -> Any:
        return getattr(self._msg, name)
