"""Writing RGB-D logs for tests: depth and colour `sensor_msgs/msg/Image` with their
`CameraInfo` (ROS 2, cdr), as a RealSense or Azure Kinect driver records them."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

_TIME = "================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
_HEADER = "================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n"
IMAGE_MSGDEF = "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data\n" + _HEADER + _TIME
CAMERA_INFO_MSGDEF = (
    "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] d\nfloat64[9] k\n"
    "float64[9] r\nfloat64[12] p\nuint32 binning_x\nuint32 binning_y\nsensor_msgs/RegionOfInterest roi\n"
    + _HEADER + _TIME
    + "================================================================================\nMSG: sensor_msgs/RegionOfInterest\n"
    "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n"
)
K_UOIS = (612.937, 613.173, 322.549, 248.158)


def _header(t_ns: int, frame_id: str) -> dict[str, Any]:
    return {"stamp": {"sec": t_ns // 1_000_000_000, "nanosec": t_ns % 1_000_000_000}, "frame_id": frame_id}


def image_msg(pixels: np.ndarray, encoding: str, t_ns: int, frame_id: str, data: bytes | None = None,
              step: int | None = None) -> dict[str, Any]:
    h, w = pixels.shape[:2]
    raw = np.ascontiguousarray(pixels).tobytes()
    return {"header": _header(t_ns, frame_id), "height": h, "width": w, "encoding": encoding, "is_bigendian": 0,
            "step": step if step is not None else len(raw) // h, "data": raw if data is None else data}


def info_msg(w: int, h: int, t_ns: int, frame_id: str, k: tuple[float, float, float, float] = K_UOIS,
             model: str = "plumb_bob", d: tuple[float, ...] = (0.0,) * 5) -> dict[str, Any]:
    fx, fy, cx, cy = k
    return {"header": _header(t_ns, frame_id), "height": h, "width": w, "distortion_model": model, "d": list(d),
            "k": [fx, 0, cx, 0, fy, cy, 0, 0, 1], "r": [1, 0, 0, 0, 1, 0, 0, 0, 1],
            "p": [fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0], "binning_x": 0, "binning_y": 0,
            "roi": {"x_offset": 0, "y_offset": 0, "height": 0, "width": 0, "do_rectify": False}}


def write_rgbd_mcap(path: Path, frames: list[dict[str, Any]], ns: str = "/camera", info: bool = True) -> Path:
    """``frames``: dicts with ``depth`` (array) and ``depth_encoding``, optional ``color``
    and ``color_encoding``, ``frame_id`` (depth) and ``color_frame_id``, ``t_ns``, and
    ``depth_msg`` to replace the depth message whole (a damaged one)."""
    from mcap_ros2.writer import Writer

    with open(path, "wb") as fp:
        writer = Writer(fp)
        image = writer.register_msgdef("sensor_msgs/msg/Image", IMAGE_MSGDEF)
        camera = writer.register_msgdef("sensor_msgs/msg/CameraInfo", CAMERA_INFO_MSGDEF)
        for k, f in enumerate(frames):
            t = f.get("t_ns", 1_700_000_000_000_000_000 + k * 1_000_000_000)
            depth, fid = f["depth"], f.get("frame_id", "camera_color_optical_frame")
            h, w = depth.shape[:2]
            if info:
                writer.write_message(f"{ns}/depth/camera_info", camera, info_msg(w, h, t, fid, **f.get("info", {})),
                                     log_time=t, publish_time=t)
            if f.get("color") is not None:
                cfid = f.get("color_frame_id", fid)
                writer.write_message(f"{ns}/color/image_raw", image,
                                     image_msg(f["color"], f.get("color_encoding", "rgb8"), t, cfid),
                                     log_time=t + 1000, publish_time=t + 1000)
            msg = f.get("depth_msg") or image_msg(depth, f.get("depth_encoding", "16UC1"), t, fid)
            writer.write_message(f"{ns}/depth/image_raw", image, msg, log_time=t + 2000, publish_time=t + 2000)
        writer.finish()
    return path
