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

    def md5_problem(self, msgtype: str, md5sum: str) -> str | None:
        """Why a ROS 1 connection's md5sum is not that of the type it names, else None.

        ROS 1 names a connection's type twice: by name, and by the md5sum of its
        definition. A header whose name was changed (or whose bytes were damaged) keeps
        the md5sum of what the messages are. Compared for the standard types only (a
        custom type has no reference to compare with), and not when the bag gives none."""
        if not self.ros1 or md5sum in ("", "*"):
            return None
        store = self._standard_store()
        want = _standard_md5(store, msgtype)
        if want is None or md5sum == want:
            return None
        other = next((t for t in _FRAME_TYPES if _standard_md5(store, t) == md5sum), None)
        return f"the connection's md5sum {md5sum} is not that of {_ros1_spelling(msgtype)} ({want})" + (
            f" but that of {_ros1_spelling(other)}" if other else ""
        )


# The ROS 1 types clear reads frames from, for naming what a mislabelled connection holds.
_FRAME_TYPES = ("sensor_msgs/msg/PointCloud2", "sensor_msgs/msg/Image", "sensor_msgs/msg/CameraInfo")
# md5sums of the standard ROS 1 types by type (None: not a standard type), computed once.
_MD5: dict[str, str | None] = {}


def _standard_md5(store: Any, msgtype: str) -> str | None:
    if msgtype not in _MD5:
        try:
            _MD5[msgtype] = store.generate_msgdef(msgtype)[1] if msgtype in store.fielddefs else None
        except Exception:  # a type the store cannot define: nothing to compare with
            _MD5[msgtype] = None
    return _MD5[msgtype]


def _ros1_spelling(msgtype: str) -> str:
    """rosbags' normalised `pkg/msg/Type` -> ROS 1's `pkg/Type`."""
    return msgtype.replace("/msg/", "/", 1)


def bag_frame(msgtype: str, msg: Any, time_ns: int, source: str) -> Frame:
    """The frame of a decoded PointCloud2 or foxglove cloud of type ``msgtype``."""
    if msgtype in POINTCLOUD2_SCHEMAS:
        return pointcloud2_frame(_ZeroCopy(msg), time_ns, source)
    return foxglove_frame(_ZeroCopy(msg), time_ns, source)


class _ZeroCopy:
    """A deserialised message whose `data` (a NumPy uint8 array) reads as a memoryview,
    so that the point blob is viewed in place rather than copied to bytes first."""

    def __init__(self, msg: Any) -> None:
        self._msg = msg
        data = getattr(msg, "data", b"")
        self.data = data.data if isinstance(data, np.ndarray) and data.flags.c_contiguous else data  # its memoryview

    def __getattr__(self, name: str) -> Any:
        return getattr(self._msg, name)
