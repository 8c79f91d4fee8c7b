"""Writing RGB-D logs for tests: depth and colour `sensor_msgs/msg/Image` with their
`CameraInfo` (ROS 2, cdr), as a RealSense or Azure Kinect driver records them."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

_TIME = "================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
_HEADER = "================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n"
IMAGE_MSGDEF = (
    "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data\n"
    + _HEADER
    + _TIME
)
CAMERA_INFO_MSGDEF = (
    "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] d\nfloat64[9] k\n"
    "float64[9] r\nfloat64[12] p\nuint32 binning_x\nuint32 binning_y\nsensor_msgs/RegionOfInterest roi\n"
    + _HEADER
    + _TIME
    + "================================================================================\nMSG: sensor_msgs/RegionOfInterest\n"
    "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n"
)
K_UOIS = (612.937, 613.173, 322.549, 248.158)


def _header(t_ns: int, frame_id: str) -> dict[str, Any]:
    return {"stamp": {"sec": t_ns // 1_000_000_000, "nanosec": t_ns % 1_000_000_000}, "frame_id": frame_id}


def image_msg(
    pixels: np.ndarray, encoding: str, t_ns: int, frame_id: str, data: bytes | None = None, step: int | None = None
) -> dict[str, Any]:
    h, w = pixels.shape[:2]
    raw = np.ascontiguousarray(pixels).tobytes()
    return {
        "header": _header(t_ns, frame_id),
        "height": h,
        "width": w,
        "encoding": encoding,
        "is_bigendian": 0,
        "step": step if step is not None else len(raw) // h,
        "data": raw if data is None else data,
    }


def info_msg(
    w: int,
    h: int,
    t_ns: int,
    frame_id: str,
    k: tuple[float, float, float, float] = K_UOIS,
    model: str = "plumb_bob",
    d: tuple[float, ...] = (0.0,) * 5,
) -> dict[str, Any]:
    fx, fy, cx, cy = k
    return {
        "header": _header(t_ns, frame_id),
        "height": h,
        "width": w,
        "distortion_model": model,
        "d": list(d),
        "k": [fx, 0, cx, 0, fy, cy, 0, 0, 1],
        "r": [1, 0, 0, 0, 1, 0, 0, 0, 1],
        "p": [fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0],
        "binning_x": 0,
        "binning_y": 0,
        "roi": {"x_offset": 0, "y_offset": 0, "height": 0, "width": 0, "do_rectify": False},
    }


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
                writer.write_message(
                    f"{ns}/depth/camera_info",
                    camera,
                    info_msg(w, h, t, fid, **f.get("info", {})),
                    log_time=t,
                    publish_time=t,
                )
            if f.get("color") is not None:
                cfid = f.get("color_frame_id", fid)
                writer.write_message(
                    f"{ns}/color/image_raw",
                    image,
                    image_msg(f["color"], f.get("color_encoding", "rgb8"), t, cfid),
                    log_time=t + 1000,
                    publish_time=t + 1000,
                )
            msg = f.get("depth_msg") or image_msg(depth, f.get("depth_encoding", "16UC1"), t, fid)
            writer.write_message(f"{ns}/depth/image_raw", image, msg, log_time=t + 2000, publish_time=t + 2000)
        writer.finish()
    return path


def _store(ros1: bool) -> Any:
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.LATEST)


def _bag_header(store: Any, ros1: bool, t_ns: int, frame_id: str) -> Any:
    time = store.types["builtin_interfaces/msg/Time"](sec=t_ns // 1_000_000_000, nanosec=t_ns % 1_000_000_000)
    header = store.types["std_msgs/msg/Header"]
    return header(seq=0, stamp=time, frame_id=frame_id) if ros1 else header(stamp=time, frame_id=frame_id)


def _stamped_size(store: Any, ros1: bool, t_ns: int, frame_id: str, w: int, h: int) -> dict[str, Any]:
    """What an Image and its CameraInfo share: the stamped header, the image's size."""
    return {"header": _bag_header(store, ros1, t_ns, frame_id), "height": h, "width": w}


def bag_image(store: Any, ros1: bool, pixels: np.ndarray, encoding: str, t_ns: int, frame_id: str) -> Any:
    h, w = pixels.shape[:2]
    raw = np.frombuffer(np.ascontiguousarray(pixels).tobytes(), dtype=np.uint8)
    return store.types["sensor_msgs/msg/Image"](
        **_stamped_size(store, ros1, t_ns, frame_id, w, h),
        encoding=encoding,
        is_bigendian=0,
        step=len(raw) // h,
        data=raw,
    )


def bag_info(
    store: Any,
    ros1: bool,
    w: int,
    h: int,
    t_ns: int,
    frame_id: str,
    k: tuple[float, float, float, float] = K_UOIS,
    d: tuple[float, ...] = (0.0,) * 5,
    model: str = "plumb_bob",
) -> Any:
    fx, fy, cx, cy = k
    roi = store.types["sensor_msgs/msg/RegionOfInterest"](x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
    mats = {
        "d": np.array(d, dtype=np.float64),
        "k": np.array([fx, 0, cx, 0, fy, cy, 0, 0, 1], dtype=np.float64),
        "r": np.eye(3).ravel(),
        "p": np.array([fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0], dtype=np.float64),
    }
    if ros1:
        mats = {key.upper(): v for key, v in mats.items()}
    return store.types["sensor_msgs/msg/CameraInfo"](
        **_stamped_size(store, ros1, t_ns, frame_id, w, h),
        distortion_model=model,
        binning_x=0,
        binning_y=0,
        roi=roi,
        **mats,
    )


def write_rgbd_bag(
    path: Path,
    depth: list[np.ndarray],
    color: list[np.ndarray] | None = None,
    *,
    ros1: bool = True,
    ns: str = "/camera",
    frame_id: str = "camera_color_optical_frame",
    color_frame_id: str | None = None,
    storage: str = "sqlite3",
) -> Path:
    """A ROS 1 bag or a rosbag2 bag written by rosbags: depth (16UC1) and colour (rgb8)
    images with the depth's camera info, one frame a second."""
    store = _store(ros1)
    ser = store.serialize_ros1 if ros1 else store.serialize_cdr
    if ros1:
        from rosbags.rosbag1 import Writer

        writer: Any = Writer(path)
    else:
        from rosbags.rosbag2 import StoragePlugin, Writer

        plugin = {"sqlite3": StoragePlugin.SQLITE3, "mcap": StoragePlugin.MCAP}[storage]
        writer = Writer(path, version=Writer.VERSION_LATEST, storage_plugin=plugin)
    with writer:
        info_c = writer.add_connection(
            f"{ns}/aligned_depth_to_color/camera_info", "sensor_msgs/msg/CameraInfo", typestore=store
        )
        depth_c = writer.add_connection(
            f"{ns}/aligned_depth_to_color/image_raw", "sensor_msgs/msg/Image", typestore=store
        )
        color_c = (
            writer.add_connection(f"{ns}/color/image_raw", "sensor_msgs/msg/Image", typestore=store) if color else None
        )
        for k, d in enumerate(depth):
            t = 1_700_000_000_000_000_000 + k * 1_000_000_000
            h, w = d.shape
            writer.write(info_c, t, ser(bag_info(store, ros1, w, h, t, frame_id), "sensor_msgs/msg/CameraInfo"))
            if color_c is not None:
                msg = bag_image(store, ros1, color[k], "rgb8", t, color_frame_id or frame_id)
                writer.write(color_c, t + 1000, ser(msg, "sensor_msgs/msg/Image"))
            writer.write(
                depth_c, t + 2000, ser(bag_image(store, ros1, d, "16UC1", t, frame_id), "sensor_msgs/msg/Image")
            )
    return path


# (translation x, y, z in metres), (quaternion x, y, z, w) of a geometry_msgs/Transform
Extrinsic = tuple[tuple[float, float, float], tuple[float, float, float, float]]


def write_realsense_sdk_bag(
    path: Path,
    depth: list[np.ndarray],
    color: list[np.ndarray],
    *,
    depth_units: float = 0.001,
    depth_frame_id: str = "0",
    color_frame_id: str = "0",
    depth_k: tuple[float, float, float, float] = K_UOIS,
    color_k: tuple[float, float, float, float] = K_UOIS,
    color_model: str = "plumb_bob",
    color_d: tuple[float, ...] = (0.0,) * 5,
    color_encoding: str = "rgb8",
    color_info: bool = True,
    color_at_ns: list[int] | None = None,
    extrinsics: dict[str, Extrinsic] | None = None,
) -> Path:
    """A ROS 1 bag laid out as librealsense's recorder writes one (realsense-viewer,
    rs2::recorder; its record-and-playback documentation): each stream under
    /device_0/sensor_<i>/<Stream>_<index>/ with `image/data` and `info/camera_info`, the
    sensor's options as std_msgs/Float32 under `option/<name>/value`, the streams'
    extrinsics as geometry_msgs/Transform under `tf/<group>` (group 0: from the reference
    stream to that stream, as ros_writer::write_extrinsics records them).

    Depth k is logged at 1_700_000_000 s + k * 33 ms; colour j at the same time as depth j,
    or at 1_700_000_000 s + ``color_at_ns[j]``. ``extrinsics``: {"Depth": ..., "Color": ...}
    (a stream left out has no tf topic); by default only Color's, 15 mm along x, so that
    colour is not registered (no Depth extrinsics). ``color_info`` False leaves out the
    colour's camera info."""
    from rosbags.rosbag1 import Writer

    store = _store(True)
    ser = store.serialize_ros1
    t0 = 1_700_000_000_000_000_000
    streams = {"Depth": "/device_0/sensor_0/Depth_0", "Color": "/device_0/sensor_1/Color_0"}
    if extrinsics is None:
        extrinsics = {"Color": ((0.015, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))}
    with Writer(path) as writer:
        units = writer.add_connection(
            "/device_0/sensor_0/option/Depth Units/value", "std_msgs/msg/Float32", typestore=store
        )
        writer.write(units, t0 - 1, ser(store.types["std_msgs/msg/Float32"](data=depth_units), "std_msgs/msg/Float32"))
        for name, (xyz, q) in extrinsics.items():
            tf_c = writer.add_connection(f"{streams[name]}/tf/0", "geometry_msgs/msg/Transform", typestore=store)
            tf = store.types["geometry_msgs/msg/Transform"](
                translation=store.types["geometry_msgs/msg/Vector3"](x=xyz[0], y=xyz[1], z=xyz[2]),
                rotation=store.types["geometry_msgs/msg/Quaternion"](x=q[0], y=q[1], z=q[2], w=q[3]),
            )
            writer.write(tf_c, t0 - 1, ser(tf, "geometry_msgs/msg/Transform"))
        conns = {}
        for name, ns in streams.items():
            info = name == "Depth" or color_info
            conns[name] = (
                writer.add_connection(f"{ns}/info/camera_info", "sensor_msgs/msg/CameraInfo", typestore=store)
                if info
                else None,
                writer.add_connection(f"{ns}/image/data", "sensor_msgs/msg/Image", typestore=store),
            )
        messages = [
            ("Depth", t0 + k * 33_000_000, d, "16UC1", depth_frame_id, {"k": depth_k}) for k, d in enumerate(depth)
        ]
        messages += [
            (
                "Color",
                t0 + (color_at_ns[j] if color_at_ns is not None else j * 33_000_000),
                c,
                color_encoding,
                color_frame_id,
                {"k": color_k, "d": color_d, "model": color_model},
            )
            for j, c in enumerate(color)
        ]
        for name, t, pixels, enc, fid, intrinsics in sorted(messages, key=lambda m: m[1]):
            h, w = pixels.shape[:2]
            info_c, image_c = conns[name]
            if info_c is not None:
                writer.write(
                    info_c, t, ser(bag_info(store, True, w, h, t, fid, **intrinsics), "sensor_msgs/msg/CameraInfo")
                )
            writer.write(image_c, t + 1, ser(bag_image(store, True, pixels, enc, t, fid), "sensor_msgs/msg/Image"))
    return path


def write_foxglove_json_mcap(
    path: Path, depth_m: np.ndarray, color: np.ndarray | None = None, frame_id: str = "camera_color_optical_frame"
) -> Path:
    """One frame as foxglove.RawImage (32FC1 depth, rgb8 colour) with a
    foxglove.CameraCalibration, JSON-encoded (the Foxglove schemas, as Foxglove Studio
    and foxglove-sdk write them)."""
    import base64
    import json

    from mcap.writer import Writer

    fx, fy, cx, cy = K_UOIS
    t = 1_700_000_000_000_000_000
    stamp = {"sec": t // 1_000_000_000, "nsec": t % 1_000_000_000}

    def raw_image(pixels: np.ndarray, encoding: str) -> bytes:
        h, w = pixels.shape[:2]
        data = np.ascontiguousarray(pixels).tobytes()
        return json.dumps(
            {
                "timestamp": stamp,
                "frame_id": frame_id,
                "width": w,
                "height": h,
                "encoding": encoding,
                "step": len(data) // h,
                "data": base64.b64encode(data).decode(),
            }
        ).encode()

    h, w = depth_m.shape
    calibration = json.dumps(
        {
            "timestamp": stamp,
            "frame_id": frame_id,
            "width": w,
            "height": h,
            "distortion_model": "",
            "D": [],
            "K": [fx, 0, cx, 0, fy, cy, 0, 0, 1],
            "R": [1, 0, 0, 0, 1, 0, 0, 0, 1],
            "P": [fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0],
        }
    ).encode()
    with open(path, "wb") as fp:
        writer = Writer(fp)
        writer.start(profile="", library="tests")
        image_schema = writer.register_schema("foxglove.RawImage", "jsonschema", b"{}")
        cal_schema = writer.register_schema("foxglove.CameraCalibration", "jsonschema", b"{}")
        cal = writer.register_channel("/depth/calibration", "json", cal_schema)
        dep = writer.register_channel("/depth/image", "json", image_schema)
        writer.add_message(cal, log_time=t, publish_time=t, data=calibration)
        if color is not None:
            col = writer.register_channel("/color/image", "json", image_schema)
            writer.add_message(col, log_time=t + 1, publish_time=t + 1, data=raw_image(color, "rgb8"))
        writer.add_message(dep, log_time=t + 2, publish_time=t + 2, data=raw_image(depth_m.astype(np.float32), "32FC1"))
        writer.finish()
    return path


def write_ros1_mcap(path: Path, depth: np.ndarray, color: np.ndarray) -> Path:
    """One frame as ROS 1 messages in an MCAP log (profile ros1: `ros1msg` schemas, `ros1`
    encoding), as `mcap convert` makes of a ROS 1 bag."""
    from mcap.writer import Writer

    store = _store(True)
    t = 1_700_000_000_000_000_000
    fid = "camera_color_optical_frame"
    with open(path, "wb") as fp:
        writer = Writer(fp)
        writer.start(profile="ros1", library="tests")
        schemas = {
            name: writer.register_schema(name.replace("/msg/", "/"), "ros1msg", store.generate_msgdef(name)[0].encode())
            for name in ("sensor_msgs/msg/Image", "sensor_msgs/msg/CameraInfo")
        }
        info = writer.register_channel("/camera/depth/camera_info", "ros1", schemas["sensor_msgs/msg/CameraInfo"])
        col = writer.register_channel("/camera/color/image_raw", "ros1", schemas["sensor_msgs/msg/Image"])
        dep = writer.register_channel("/camera/depth/image_raw", "ros1", schemas["sensor_msgs/msg/Image"])
        h, w = depth.shape
        writer.add_message(
            info,
            log_time=t,
            publish_time=t,
            data=store.serialize_ros1(bag_info(store, True, w, h, t, fid), "sensor_msgs/msg/CameraInfo").tobytes(),
        )
        writer.add_message(
            col,
            log_time=t + 1,
            publish_time=t + 1,
            data=store.serialize_ros1(bag_image(store, True, color, "rgb8", t, fid), "sensor_msgs/msg/Image").tobytes(),
        )
        writer.add_message(
            dep,
            log_time=t + 2,
            publish_time=t + 2,
            data=store.serialize_ros1(
                bag_image(store, True, depth, "16UC1", t, fid), "sensor_msgs/msg/Image"
            ).tobytes(),
        )
        writer.finish()
    return path
