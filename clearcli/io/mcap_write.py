"""Writing MCAP logs: ROS 2 `sensor_msgs/msg/PointCloud2` (cdr, zstd chunks) with x y z,
PCL's packed float `rgb` and a uint32 `label`; optionally a `/tf_static` transform.
Written whole or not at all (clearcli/files.py)."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from clearcli.errors import OutputError
from clearcli.files import atomic_output
from clearcli.io.frames import Frame, labels_to_write
from clearcli.io.mcap import DEFAULT_FRAME_ID, DEFAULT_TOPIC
from clearcli.io.pointfields import pack_rgb_float
from clearcli.transforms import matrix_to_quat

_SEP = "=" * 80 + "\n"
# std_msgs/Header and the type it uses, as a message definition that uses it lists them
_HEADER_DEFS = (
    _SEP
    + "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n"
    + _SEP
    + "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
)
POINTCLOUD2_MSGDEF = (
    "std_msgs/Header header\nuint32 height\nuint32 width\nPointField[] fields\n"
    "bool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n"
    + _HEADER_DEFS
    + _SEP
    + "MSG: sensor_msgs/PointField\n"
    "uint8 INT8 = 1\nuint8 UINT8 = 2\nuint8 INT16 = 3\nuint8 UINT16 = 4\n"
    "uint8 INT32 = 5\nuint8 UINT32 = 6\nuint8 FLOAT32 = 7\nuint8 FLOAT64 = 8\n"
    "string name\nuint32 offset\nuint8 datatype\nuint32 count\n"
)
TFMESSAGE_MSGDEF = (
    "geometry_msgs/TransformStamped[] transforms\n"
    + _SEP
    + "MSG: geometry_msgs/TransformStamped\nstd_msgs/Header header\nstring child_frame_id\n"
    "Transform transform\n"
    + _HEADER_DEFS
    + _SEP
    + "MSG: geometry_msgs/Transform\nVector3 translation\nQuaternion rotation\n"
    + _SEP
    + "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n"
    + _SEP
    + "MSG: geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"
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
    labels = labels_to_write(frame, labels)
    if labels is not None:
        cols.append(("label", np.dtype("<u4"), labels.astype(np.uint32)))
    record = np.dtype([(name, dt) for name, dt, _ in cols])
    blob = np.empty(n, dtype=record)
    for name, _, values in cols:
        blob[name] = values
    height, width = frame.shape if frame.shape is not None else (1, n)
    datatype = {"f4": 7, "u4": 6}
    offsets = record.fields
    assert offsets is not None  # a structured dtype has fields
    fields = [
        {"name": name, "offset": int(offsets[name][1]), "datatype": datatype[dt.str[1:]], "count": 1}
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
                    topic,
                    schema,
                    _pointcloud2_dict(frame, frame_labels),
                    log_time=t_ns,
                    publish_time=t_ns,
                    sequence=count,
                )
                count += 1
            writer.finish()  # type: ignore[no-untyped-call]  # mcap_ros2's Writer.finish() is not annotated
    except OSError as exc:
        raise OutputError(f"{path}: cannot write ({exc.strerror or exc})") from None
    return count


def write_tf_static(path: Path, transforms: Sequence[StaticTransform]) -> None:
    """A log holding only `/tf_static` (for tests and tools); see write_pointcloud2_mcap."""
    write_pointcloud2_mcap(path, [], tf_static=transforms)
