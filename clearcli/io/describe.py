"""What a file holds, as the payload of schema ``clear.info`` (documented in
`clearcli/commands/info.py`): a PCD's header, a log's or bag's channels, one frame's
points, fields and bounds."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from clearcli.io.frames import Frame


def describe_frame(frame: "Frame", index: int = 0) -> dict[str, Any]:
    """The `frame` object of the info schema."""
    import numpy as np

    finite = frame.finite_mask
    n_finite = int(finite.sum())
    fields: list[dict[str, Any]] = [{"name": a, "dtype": str(frame.points.dtype), "count": 1} for a in "xyz"]
    if frame.colors is not None:
        fields.append({"name": "rgb", "dtype": "uint8", "count": 3})
    for name, values in frame.fields.items():
        values = np.asarray(values)
        fields.append({"name": name, "dtype": str(values.dtype), "count": int(np.prod(values.shape[1:], dtype=int))})
    bounds = None
    if n_finite:
        pts = frame.points[finite]
        bounds = {
            "min": [round(float(v), 6) for v in pts.min(axis=0)],
            "max": [round(float(v), 6) for v in pts.max(axis=0)],
        }
    return {
        "index": index,
        "points": frame.n_points,
        "organized": frame.is_organized,
        "shape": list(frame.shape) if frame.shape is not None else None,
        "finite_points": n_finite,
        "has_colors": frame.colors is not None,
        "fields": fields,
        "bounds_m": bounds,
        "stamp_s": float(frame.stamp_s),
        "frame_id": frame.frame_id,
    }


def describe_image(frame: "Frame", path: Path, images: Any = None, color: Path | None = None) -> dict[str, Any]:
    """The info payload of a depth image, from the frame it made: its size, depth range,
    the intrinsics found and the colour image paired with it."""
    from clearcli.io.images import color_pair, find_intrinsics, or_defaults

    images = or_defaults(images)
    z = frame.points[:, 2]
    valid = z[frame.finite_mask]  # a pixel's depth is its point's z
    model = find_intrinsics(path, images)  # read once already: the reader keeps it
    paired = Path(color) if color is not None else color_pair(path, images)
    assert frame.shape is not None  # depth images make organized frames
    image_part = {
        "width": int(frame.shape[1]),
        "height": int(frame.shape[0]),
        "depth_scale_m": images.depth_scale_m,
        "valid_pixels": int(valid.size),
        "depth_min_m": round(float(valid.min()), 6) if valid.size else None,
        "depth_max_m": round(float(valid.max()), 6) if valid.size else None,
        "intrinsics": {
            "fx": model.fx, "fy": model.fy, "cx": model.cx, "cy": model.cy,
            "width": model.width, "height": model.height,
            "distortion_model": model.distortion_model or None,
            "distorted": model.distorted,
            "source": model.source,
        },
        "color": str(paired) if paired is not None else None,
    }
    return {"file": str(path), "format": "depth-image", "image": image_part, "frame": describe_frame(frame, 0)}


def describe_file(path: Path, topic: str | None = None, index: int = 0, images: Any = None,
                  color: Path | None = None) -> dict[str, Any]:
    """The info payload (without envelope) for `path`; raises ClearError on bad input.

    A damaged MCAP log or bag is described (mcap/bag.complete false) without raising; the
    caller decides what exit code that deserves.
    """
    from clearcli.io.read import read_frame, sniff

    path = Path(path)
    kind = sniff(path)
    if kind == "image" or color is not None:  # the reader checks --frame and --color
        return describe_image(read_frame(path, topic, index, images, color), path, images, color)
    if kind == "pcd":
        from clearcli.io.pcd import pcd_header_fields

        header = pcd_header_fields(path)
        frame = read_frame(path, topic, index)
        return {"file": str(path), "format": "pcd", "pcd": header, "frame": describe_frame(frame, index)}

    # A log (MCAP) or a bag: the same summary attributes, topic rules and frame reading.
    if kind == "mcap":
        from clearcli.io.mcap import LogAccess, choose_topic, read_mcap_frame, read_summary

        summary: Any = read_summary(path)
        read_one: Any = read_mcap_frame
        access: Any = LogAccess(path, summary)
    else:
        from clearcli.io.bag_messages import BagDecoders
        from clearcli.io.rosbag import BagAccess, read_bag_frame, read_bag_summary
        from clearcli.io.rosbag import choose_bag_topic as choose_topic  # type: ignore[assignment]

        summary = read_bag_summary(path)
        read_one = read_bag_frame
        access = BagAccess(summary, BagDecoders(ros1=summary.format == "rosbag1"))
    candidates = summary.frame_topics()  # no point cloud: depth images are the frames
    chosen: str | None = None
    if topic is not None or len(candidates) == 1:
        chosen = choose_topic(summary, topic)
    start = summary.start_ns * 1e-9 if summary.start_ns is not None else None
    end = summary.end_ns * 1e-9 if summary.end_ns is not None else None
    mcap_part: dict[str, Any] = {
        "profile": summary.profile,
        "library": summary.library,
        "indexed": summary.indexed,
        "complete": summary.damage is None,
        "damage": summary.damage,
        "message_count": summary.message_count,
        "start_s": start,
        "end_s": end,
        "duration_s": (end - start) if start is not None and end is not None else None,
        "channels": [
            {
                "topic": ch.topic,
                "schema": ch.schema_name,
                "schema_encoding": ch.schema_encoding,
                "message_encoding": ch.message_encoding,
                "message_count": ch.message_count,
                "point_cloud": ch.is_point_cloud,
            }
            for ch in summary.channels
        ],
        "pointcloud_topics": candidates,
        "pointcloud_topic": chosen,
        "image_streams": _image_streams(access),
        "frame_count": summary.count(chosen) if chosen is not None else None,
    }
    frame_part = None
    if chosen is not None:
        if summary.count(chosen) == 0 and index == 0:
            frame_part = None  # the channel exists but holds no message yet
        else:
            frame_part = describe_frame(read_one(path, chosen, index, images), index)
    if kind != "mcap":
        mcap_part["storage"] = summary.storage
        return {"file": str(path), "format": kind, "bag": mcap_part, "frame": frame_part}
    return {"file": str(path), "format": "mcap", "mcap": mcap_part, "frame": frame_part}


def _image_streams(access: Any) -> list[dict[str, Any]]:
    """Each image topic of a log or bag: its encoding and size (from its first message),
    and whether it is read as depth."""
    from clearcli.io.messages import message_field

    streams = []
    summary = access.summary
    depth = set(summary.depth_topics())
    for topic in summary.image_topics():
        entry: dict[str, Any] = {"topic": topic, "depth": topic in depth, "encoding": None, "width": None, "height": None}
        try:
            for _, msg, _ in access.decoded(topic):
                entry.update(encoding=str(message_field(msg, "encoding", default="")),
                             width=int(message_field(msg, "width", default=0)),
                             height=int(message_field(msg, "height", default=0)))
                break
        except Exception:  # a damaged log: the channel list says what is known
            pass
        streams.append(entry)
    return streams


def log_part(info: dict[str, Any]) -> dict[str, Any] | None:
    """The `mcap` or `bag` object of an info payload (None for a PCD)."""
    return info.get("mcap") or info.get("bag")
