"""Image and camera-info messages -> depth (metres), colour (RGB) and a `CameraModel`.

`sensor_msgs/Image` (ROS 1 and ROS 2) and `foxglove.RawImage`; `sensor_msgs/CameraInfo`
and `foxglove.CameraCalibration`. Each message is checked against itself before it is
read (rows of `step` bytes must hold `width` pixels, and `height` rows must be the data),
as PointCloud2 is in clearcli/io/messages.py: a damaged message is never read as whole.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from clearcli.errors import InputError
from clearcli.io.images import _units_to_m
from clearcli.io.intrinsics import from_camera_info
from clearcli.io.messages import _as_bytes, _stamp_s, message_field

IMAGE_SCHEMAS = frozenset(
    {
        "sensor_msgs/msg/Image",
        "sensor_msgs/Image",
        "foxglove.RawImage",
        "foxglove_msgs/msg/RawImage",
    }
)
CAMERA_INFO_SCHEMAS = frozenset(
    {
        "sensor_msgs/msg/CameraInfo",
        "sensor_msgs/CameraInfo",
        "foxglove.CameraCalibration",
        "foxglove_msgs/msg/CameraCalibration",
    }
)
# Depth encodings: integer units ([images] depth_scale_m each, millimetres by default) or float metres.
DEPTH_ENCODINGS = {"16UC1": ("u2", True), "mono16": ("u2", True), "32FC1": ("f4", False)}
# Colour encodings -> (channels, order of R, G, B among them).
COLOR_ENCODINGS = {
    "rgb8": (3, (0, 1, 2)),
    "bgr8": (3, (2, 1, 0)),
    "rgba8": (4, (0, 1, 2)),
    "bgra8": (4, (2, 1, 0)),
    "mono8": (1, (0, 0, 0)),
}
COMPRESSED_SCHEMAS = frozenset(
    {"sensor_msgs/msg/CompressedImage", "sensor_msgs/CompressedImage", "foxglove.CompressedImage"}
)


def header_of(msg: Any) -> tuple[Any, str]:
    """(stamp, frame id) of a ROS message (header) or a Foxglove one (timestamp, frame_id)."""
    header = message_field(msg, "header")
    if header is not None:
        return message_field(header, "stamp"), str(message_field(header, "frame_id", default="") or "")
    return message_field(msg, "timestamp"), str(message_field(msg, "frame_id", default="") or "")


def stamp_ns(msg: Any, log_time_ns: int) -> int:
    """The message's own time stamp in integer nanoseconds (pairs depth with colour exactly)."""
    return int(round(_stamp_s(header_of(msg)[0], log_time_ns) * 1e9))


def _pixels(msg: Any, where: str, itemsize: int, channels: int) -> np.ndarray:
    """(H, W*channels) view of the message's rows, after checking the layout adds up."""
    height, width = int(message_field(msg, "height", default=0)), int(message_field(msg, "width", default=0))
    step = int(message_field(msg, "step", default=0))
    data = _as_bytes(message_field(msg, "data", default=b""))
    if height <= 0 or width <= 0:
        raise ValueError(f"damaged image on {where}: {width} x {height} pixels with {len(data)} bytes of data")
    if step < width * itemsize * channels:
        raise ValueError(
            f"damaged image on {where}: step {step} bytes is less than width {width} x {itemsize * channels}"
        )
    if height * step != len(data):
        raise ValueError(
            f"damaged image on {where}: height {height} x step {step} = {height * step} bytes, but it carries {len(data)}"
        )
    rows = np.frombuffer(data, dtype=np.uint8).reshape(height, step)[:, : width * itemsize * channels]
    return np.ascontiguousarray(rows)


def depth_m(msg: Any, where: str, scale_m: float) -> np.ndarray:
    """(H, W) float32 depth in metres of a depth image message."""
    encoding = str(message_field(msg, "encoding", default=""))
    if encoding not in DEPTH_ENCODINGS:
        raise InputError(
            f"{where}: the image encoding is {encoding or 'empty'!r}, not depth (16UC1 millimetres, 32FC1 metres); "
            "name the depth topic with --topic"
        )
    code, integer = DEPTH_ENCODINGS[encoding]
    rows = _pixels(msg, where, 4 if code == "f4" else 2, 1)
    big = bool(message_field(msg, "is_bigendian", default=False))
    values = rows.view((">" if big else "<") + code)
    return _units_to_m(values, scale_m) if integer else values.astype(np.float32)


def color_rgb(msg: Any, where: str) -> np.ndarray | None:
    """(H, W, 3) uint8 RGB of a colour image message; None for an encoding that is no colour."""
    encoding = str(message_field(msg, "encoding", default=""))
    if encoding not in COLOR_ENCODINGS:
        return None
    channels, order = COLOR_ENCODINGS[encoding]
    rows = _pixels(msg, where, 1, channels)
    pixels = rows.reshape(rows.shape[0], -1, channels)
    return np.ascontiguousarray(pixels[:, :, list(order)])


def _numbers(value: Any) -> list[float]:
    """A message's float array (a list, a tuple or a NumPy array from rosbags) as a list."""
    return [] if value is None else [float(v) for v in np.asarray(value, dtype=np.float64).ravel()]


def camera_model(msg: Any, where: str) -> Any:
    """The `CameraModel` of a CameraInfo / CameraCalibration message."""
    roi = message_field(msg, "roi")
    return from_camera_info(
        int(message_field(msg, "width", default=0)),
        int(message_field(msg, "height", default=0)),
        _numbers(message_field(msg, "k", "K")),
        _numbers(message_field(msg, "d", "D")),
        str(message_field(msg, "distortion_model", default="") or ""),
        int(message_field(msg, "binning_x", default=0) or 0),
        int(message_field(msg, "binning_y", default=0) or 0),
        None
        if roi is None
        else (
            int(message_field(roi, "x_offset", default=0)),
            int(message_field(roi, "y_offset", default=0)),
            int(message_field(roi, "height", default=0)),
            int(message_field(roi, "width", default=0)),
            bool(message_field(roi, "do_rectify", default=False)),
        ),
        source=where,
    )
