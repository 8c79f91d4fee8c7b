"""`clear info FILE`: what a PCD, MCAP or bag file holds, for people (a table) or scripts (--json).

JSON schema (`clear info --json`), envelope {"schema": "clear.info", "version": 1, ...}:

    file:    str, the path as given
    format:  "pcd" | "mcap" | "rosbag1" (a ROS 1 bag) | "rosbag2" (a rosbag2 folder or .db3)
             | "depth-image" | another input format's name (clearcli/io/formats/: its own
             keys, if any, besides file, format and frame)
    pcd:     (format "pcd" only) the header as written:
             {encoding: "ascii"|"binary"|"binary_compressed",
              fields: [{name, type ("F4", "U4", ...), count}], width, height,
              viewpoint: [tx, ty, tz, qw, qx, qy, qz], file_bytes}
    mcap:    (format "mcap" only)
             {profile: str ("ros2", "ros1", "" ...), library: str,
              indexed: bool (summary section with chunk index read),
              complete: bool (false when the log breaks early), damage: str | null,
              message_count: int, start_s: float | null, end_s: float | null,
              duration_s: float | null,
              channels: [{topic, schema, schema_encoding, message_encoding,
                          message_count, point_cloud: bool}],
              pointcloud_topics: [str] (with no point-cloud topic: the depth image topics),
              pointcloud_topic: str | null (the topic frames are read from: --topic, or the
                                only point-cloud topic, else the only depth image topic;
                                null when none or ambiguous),
              frame_count: int | null (messages on pointcloud_topic),
              image_streams: [{topic, depth: bool, encoding, width, height}] (MCAP: each
                             image topic, from its first message)}
    image:   (format "depth-image" only: a depth image file)
             {width, height, depth_scale_m, valid_pixels, depth_min_m, depth_max_m,
              intrinsics: {fx, fy, cx, cy, width, height, distortion_model, distorted,
                           source}, color: path of the colour image | null}
    bag:     (formats "rosbag1" and "rosbag2") the same keys as `mcap` (profile "ros1" or
             "ros2"; channel schema = the message type; indexed false when a ROS 1 bag's
             index is missing and its records were scanned), plus
             storage: "rosbag1" | "sqlite3" | "mcap"
    frame:   the frame read (PCD: its one frame; logs: frame --frame N of pointcloud_topic),
             or null when the log has no (unambiguous) point-cloud topic:
             {index: int, points: int, organized: bool, shape: [height, width] | null,
              finite_points: int, has_colors: bool,
              fields: [{name, dtype ("float32", "uint32", ...), count}] (x y z first,
                       then "rgb" when colours exist, then every other field),
              bounds_m: {min: [x, y, z], max: [x, y, z]} | null (finite points only),
              stamp_s: float, frame_id: str}

A log or bag broken after complete frames is described, then the command exits 9.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from clearcli.commands import options as bo
from clearcli.commands.common import print_json, stdout
from clearcli.errors import PartialLogError
from clearcli.tasks.base import Source


def _fmt_int(n: int) -> str:
    return f"{n:,}".replace(",", " ")


def _frame_rows(frame: dict[str, Any]) -> list[tuple[str, str]]:
    rows = []
    shape = frame["shape"]
    organized = f"organized: {shape[0]} rows x {shape[1]} columns" if shape else "unorganized"
    rows.append(("points", f"{_fmt_int(frame['points'])} ({organized})"))
    pct = 100.0 * frame["finite_points"] / frame["points"] if frame["points"] else 0.0
    rows.append(("finite points", f"{_fmt_int(frame['finite_points'])} ({pct:.1f} %)"))
    rows.append(
        (
            "fields",
            " ".join(
                f["name"] + (f"[{f['count']}]" if f["count"] > 1 else "") + f":{f['dtype']}" for f in frame["fields"]
            ),
        )
    )
    bounds = frame["bounds_m"]
    if bounds:
        rows.append(
            (
                "bounds (m)",
                "  ".join(f"{a} [{lo:.3f}, {hi:.3f}]" for a, lo, hi in zip("xyz", bounds["min"], bounds["max"])),
            )
        )
    else:
        rows.append(("bounds (m)", "none: no finite point"))
    if frame["frame_id"] or frame["stamp_s"]:
        rows.append(("frame_id / stamp", f"{frame['frame_id'] or '-'} / {frame['stamp_s']:.6f} s"))
    return rows


def _print_table(info: dict[str, Any]) -> None:
    from rich.table import Table  # noqa: PLC0415  (~6 ms: not for `clear --help`)

    kv = Table(show_header=False, box=None, pad_edge=False)
    kv.add_column(style="bold")
    kv.add_column()
    kv.add_row("file", info["file"])
    if info["format"] == "pcd":
        pcd = info["pcd"]
        kv.add_row("format", f"PCD, DATA {pcd['encoding']}, {_fmt_int(pcd['file_bytes'])} bytes")
        for key, value in _frame_rows(info["frame"]):
            kv.add_row(key, value)
        stdout.print(kv)
        return
    if info["format"] == "depth-image":
        im = info["image"]
        k = im["intrinsics"]
        kv.add_row(
            "format", f"depth image, {im['width']} x {im['height']}, {im['depth_scale_m']:g} m per unit if integer"
        )
        rng = f"{im['depth_min_m']:.3f} .. {im['depth_max_m']:.3f} m" if im["valid_pixels"] else "none"
        kv.add_row("depth", f"{_fmt_int(im['valid_pixels'])} pixels with a reading, {rng}")
        dist = f", {k['distortion_model']} distortion corrected" if k["distorted"] else ""
        kv.add_row("intrinsics", f"fx {k['fx']:g} fy {k['fy']:g} cx {k['cx']:g} cy {k['cy']:g}{dist} ({k['source']})")
        kv.add_row("colour", im["color"] or "none (no --color, and no <stem>_color image beside it)")
        for key, value in _frame_rows(info["frame"]):
            kv.add_row(key, value)
        stdout.print(kv)
        return
    m = info.get("mcap") or info.get("bag")
    if m is None:  # another format (clearcli/io/formats/): its name and its frame
        kv.add_row("format", info["format"])
        for key, value in _frame_rows(info["frame"]):
            kv.add_row(key, value)
        stdout.print(kv)
        return
    if info["format"] == "rosbag1":
        kv.add_row("format", f"ROS 1 bag, {'indexed' if m['indexed'] else 'index missing: records scanned'}")
    elif info["format"] == "rosbag2":
        kv.add_row("format", m["library"])
    else:
        kv.add_row(
            "format", f"MCAP, profile {m['profile'] or '(none)'}, {'indexed' if m['indexed'] else 'not indexed'}"
        )
    if m["start_s"] is not None:
        kv.add_row("time span", f"{m['start_s']:.3f} .. {m['end_s']:.3f} s ({m['duration_s']:.3f} s)")
    kv.add_row("messages", _fmt_int(m["message_count"]))
    if not m["complete"]:
        kv.add_row("damage", f"the {'log' if info['format'] == 'mcap' else 'bag'} breaks {m['damage']}")
    if m["pointcloud_topic"]:
        n_frames = m["frame_count"]
        depth = any(im["topic"] == m["pointcloud_topic"] for im in m.get("image_streams", []))
        kv.add_row(
            "depth images" if depth else "point cloud",
            f"{m['pointcloud_topic']} ({n_frames} frame{'s' if n_frames != 1 else ''})",
        )
    elif m["pointcloud_topics"]:
        kv.add_row("point cloud", f"several topics ({', '.join(m['pointcloud_topics'])}): choose with --topic")
    else:
        kv.add_row("point cloud", "no point-cloud topic")
    if info["frame"] is not None:
        kv.add_row("frame", str(info["frame"]["index"]))
        for key, value in _frame_rows(info["frame"]):
            kv.add_row(key, value)
    for im in m.get("image_streams", []):
        size = f"{im['width']} x {im['height']}" if im["width"] else "?"
        kv.add_row(
            "image",
            f"{im['topic']}: {im['encoding'] or '?'}, {size}"
            + ("  <- depth" if im["topic"] == m["pointcloud_topic"] else ""),
        )
    stdout.print(kv)
    channels = Table(title="channels" if info["format"] == "mcap" else "topics", title_justify="left")
    for col in ("topic", "schema" if info["format"] == "mcap" else "type", "encoding", "messages", ""):
        # Fold, not ellipsize: topic and type names are what people come here to read.
        channels.add_column(col, justify="right" if col == "messages" else "left", overflow="fold")
    for ch in m["channels"]:
        mark = (
            "<- point cloud" if ch["topic"] == m["pointcloud_topic"] else ("point cloud" if ch["point_cloud"] else "")
        )
        channels.add_row(ch["topic"], ch["schema"] or "-", ch["message_encoding"], _fmt_int(ch["message_count"]), mark)
    stdout.print(channels)


@bo.batch_options(())
def info_cmd(
    inputs: Annotated[
        list[Path],
        typer.Argument(
            help="A .pcd, .mcap or ROS 1 .bag file, or a depth image (told apart by content), or a rosbag2 folder; "
            "several, or folders to search, make a batch.",
        ),
    ],
    json_out: Annotated[bool, typer.Option("--json", help="Machine-readable output (schema clear.info).")] = False,
    topic: bo.Topic = None,
    frame: bo.FrameIndex = 0,
    intrinsics: bo.Intrinsics = None,
    color: bo.Color = None,
    depth_scale: bo.DepthScale = None,
    batch: bo.Batch = bo.Batch(),
) -> None:
    """What a file holds: points, fields, organized shape, finite points, bounds; for
    MCAP logs and ROS bags also the channels/topics, types, message counts and time span."""
    from clearcli.tasks import info as task  # noqa: PLC0415  (the task, ~60 ms: not for `clear --help`)

    settings = bo.with_images(bo.resolve_settings(None, None), intrinsics, depth_scale)
    request = task.Request(settings=settings)
    if batch.wanted(inputs):
        bo.no_color_in_batch(color)
        raise typer.Exit(batch.run("info", inputs, request, frame=frame, topic=topic, force=False, json_out=json_out))
    file = inputs[0]
    outcome = task.run(request, Source(str(file), frame, topic, color=str(color) if color else None))
    info = dict(outcome.payload)
    if json_out:
        print_json(outcome.schema, outcome.version, info, settings, "info")
    else:
        _print_table(info)
    log = info.get("mcap") or info.get("bag")
    if log is not None and not log["complete"]:
        what = "log" if info["format"] == "mcap" else "bag"
        raise PartialLogError(f"{file}: the {what} breaks {log['damage']}; the figures above cover what precedes it")
