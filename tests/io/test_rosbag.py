"""Tests of clearcli/io/rosbag.py."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from helpers import FIXTURES, REPO, shared_path  # noqa: E402
from rosbags.rosbag1 import Writer as Writer1  # noqa: E402
from rosbags.rosbag2 import StoragePlugin  # noqa: E402
from rosbags.rosbag2 import Writer as Writer2  # noqa: E402
from rosbags.typesys import Stores, get_types_from_msg, get_typestore  # noqa: E402

from clearcli.errors import (  # noqa: E402
    EXIT_INPUT,
    EXIT_PARTIAL,
    ClearError,
    InputError,
    PartialLogError,
)
from clearcli.io.frames import Frame  # noqa: E402
from clearcli.io.pcd import read_pcd  # noqa: E402
from clearcli.io.pointfields import pack_rgb_float  # noqa: E402
from clearcli.io.read import iter_frames, read_frame, sniff  # noqa: E402
from clearcli.io.rosbag import read_bag_summary, read_bag_transforms  # noqa: E402

pytest.importorskip("rosbags")


TOPIC = "/camera/depth_registered/points"


REAL_BAG = "mcap/mosd_tabletop_ros1.bag"


def _clear(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "clearcli.cli", *args], capture_output=True, text=True, cwd=REPO, timeout=300
    )


def _one_line_error(result: subprocess.CompletedProcess[str], codes: tuple[int, ...], *needles: str) -> str:
    assert result.returncode in codes, (result.returncode, result.stderr)
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    for needle in needles:
        assert needle in lines[0], lines[0]
    return lines[0]


def _same(a: np.ndarray | None, b: np.ndarray | None) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return a.shape == b.shape and a.dtype == b.dtype and bool(np.array_equal(a, b, equal_nan=True))


def _assert_same_frame(got: Frame, want: Frame) -> None:
    assert got.shape == want.shape
    assert _same(got.points, want.points)
    assert _same(got.colors, want.colors)
    assert set(got.fields) == set(want.fields)
    for name in want.fields:
        assert _same(np.asarray(got.fields[name]), np.asarray(want.fields[name])), name
    assert got.frame_id == want.frame_id
    assert got.stamp_s == pytest.approx(want.stamp_s, abs=1e-9)


def _box() -> Frame:
    return read_frame(FIXTURES / "isolated_box.pcd")


def _frames(n: int, rows: int | None = None) -> list[Frame]:
    """n distinct organized frames from the fixture (optionally its first `rows` rows)."""
    box = _box()
    h, w = box.shape
    rows = rows or h
    k = rows * w
    out = []
    for i in range(n):
        points = box.points[:k].copy()
        points[:, 0] += np.float32(0.01 * i)
        out.append(
            Frame(
                points=points,
                colors=box.colors[:k].copy(),
                shape=(rows, w),
                fields={"label": (np.asarray(box.fields["label"])[:k] + i).astype(np.uint32)},
                stamp_s=100.0 + 0.5 * i,
                frame_id="camera_rgb_optical_frame",
            )
        )
    return out


def _cloud_msg(store: Any, frame: Frame, ros1: bool) -> Any:
    """sensor_msgs/PointCloud2 of `frame`: x y z float32, PCL's packed float rgb, uint32 label."""
    T = store.types
    n = frame.n_points
    record = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("rgb", "<f4"), ("label", "<u4")])
    blob = np.empty(n, dtype=record)
    for axis, name in enumerate("xyz"):
        blob[name] = frame.points[:, axis]
    blob["rgb"] = pack_rgb_float(frame.colors)
    blob["label"] = frame.fields["label"]
    height, width = frame.shape if frame.shape else (1, n)
    PointField = T["sensor_msgs/msg/PointField"]
    fields = [
        PointField(name=name, offset=record.fields[name][1], datatype=6 if name == "label" else 7, count=1)
        for name in record.names
    ]
    sec, nsec = divmod(int(round(frame.stamp_s * 1e9)), 1_000_000_000)
    stamp = T["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)
    Header = T["std_msgs/msg/Header"]
    if ros1:
        header = Header(seq=0, stamp=stamp, frame_id=frame.frame_id)
    else:
        header = Header(stamp=stamp, frame_id=frame.frame_id)
    return T["sensor_msgs/msg/PointCloud2"](
        header=header,
        height=height,
        width=width,
        fields=fields,
        is_bigendian=False,
        point_step=record.itemsize,
        row_step=record.itemsize * width,
        data=np.frombuffer(blob.tobytes(), dtype=np.uint8),
        is_dense=False,
    )


def _tf_msg(store: Any, parent: str, child: str, xyz: Iterable[float], quat_xyzw: Iterable[float], ros1: bool) -> Any:
    T = store.types
    stamp = T["builtin_interfaces/msg/Time"](sec=100, nanosec=0)
    Header = T["std_msgs/msg/Header"]
    header = Header(seq=0, stamp=stamp, frame_id=parent) if ros1 else Header(stamp=stamp, frame_id=parent)
    x, y, z = xyz
    qx, qy, qz, qw = quat_xyzw
    tf = T["geometry_msgs/msg/TransformStamped"](
        header=header,
        child_frame_id=child,
        transform=T["geometry_msgs/msg/Transform"](
            translation=T["geometry_msgs/msg/Vector3"](x=x, y=y, z=z),
            rotation=T["geometry_msgs/msg/Quaternion"](x=qx, y=qy, z=qz, w=qw),
        ),
    )
    return T["tf2_msgs/msg/TFMessage"](transforms=[tf])


def _string(store: Any, text: str) -> Any:
    return store.types["std_msgs/msg/String"](data=text)


def _ros1_store() -> Any:
    store = get_typestore(Stores.ROS1_NOETIC)
    store.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"))
    return store


def _write_messages(
    writer: Any,
    store: Any,
    ros1: bool,
    clouds: dict[str, list[Frame]],
    strings: dict[str, int] | None,
    tf: tuple[str, str, list[float], list[float]] | None,
    times: list[float] | None = None,
) -> None:
    """What both bag writers write (ROS 1 or cdr messages): a /tf_static (latched
    in ROS 1), ``strings`` String messages on each of their topics, the frames of
    ``clouds`` as PointCloud2 stamped by ``times`` or their own stamps."""
    serialize = store.serialize_ros1 if ros1 else store.serialize_cdr
    if tf is not None:
        latched = {"latching": 1} if ros1 else {}
        conn = writer.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=store, **latched)
        writer.write(conn, 99_000_000_000, serialize(_tf_msg(store, *tf, ros1=ros1), "tf2_msgs/msg/TFMessage"))
    for topic, count in (strings or {}).items():
        conn = writer.add_connection(topic, "std_msgs/msg/String", typestore=store)
        for i in range(count):
            writer.write(conn, 100_000_000_000 + i, serialize(_string(store, f"hello {i}"), "std_msgs/msg/String"))
    for topic, frames in clouds.items():
        conn = writer.add_connection(topic, "sensor_msgs/msg/PointCloud2", typestore=store)
        for i, frame in enumerate(frames):
            t = times[i] if times is not None else frame.stamp_s
            data = serialize(_cloud_msg(store, frame, ros1=ros1), "sensor_msgs/msg/PointCloud2")
            writer.write(conn, int(round(t * 1e9)), data)


def write_ros1(
    path: Path,
    clouds: dict[str, list[Frame]],
    *,
    strings: dict[str, int] | None = None,
    tf: tuple[str, str, list[float], list[float]] | None = None,
    times: list[float] | None = None,
    compression: str | None = None,
) -> Path:
    """A ROS 1 bag written by rosbags: PointCloud2 on each topic of `clouds`, String topics, a /tf_static."""
    store = _ros1_store()
    writer = Writer1(path)
    if compression:
        writer.set_compression(getattr(Writer1.CompressionFormat, compression.upper()))
    with writer:
        _write_messages(writer, store, True, clouds, strings, tf, times)
    return path


def write_rosbag2(
    path: Path,
    clouds: dict[str, list[Frame]],
    *,
    storage: str = "sqlite3",
    strings: dict[str, int] | None = None,
    tf: tuple[str, str, list[float], list[float]] | None = None,
) -> Path:
    """A rosbag2 bag folder written by rosbags (sqlite3 or mcap storage), cdr messages."""
    store = get_typestore(Stores.LATEST)
    plugin = {"sqlite3": StoragePlugin.SQLITE3, "mcap": StoragePlugin.MCAP}[storage]
    with Writer2(path, version=Writer2.VERSION_LATEST, storage_plugin=plugin) as writer:
        _write_messages(writer, store, False, clouds, strings, tf)
    return path


def test_real_ros1_bag_reads_as_test57() -> None:
    bag = shared_path(REAL_BAG)
    assert sniff(bag) == "rosbag1"
    frames = list(iter_frames(bag))
    assert len(frames) == 1
    frame = frames[0]
    assert frame.shape == (480, 640) and frame.n_points == 307200
    finite = frame.finite_mask
    assert int(finite.sum()) == 171483
    assert np.isfinite(frame.points[finite]).all()
    assert frame.frame_id == "camera_rgb_optical_frame" and frame.stamp_s == pytest.approx(1.3e9)
    assert frame.source == f"{bag.name}#0 {TOPIC}"
    # The bag holds mOSD test57: the same points and colours as the PCD, NaN pixels in place.
    pcd = read_pcd(shared_path("mosd/test/test57.pcd"))
    assert _same(frame.points, pcd.points) and _same(frame.colors, pcd.colors)
    assert _same(read_frame(bag, index=0).points, frame.points)

    summary = read_bag_summary(bag)
    assert summary.indexed and summary.damage is None and summary.message_count == 1
    assert summary.topics() == [(TOPIC, "sensor_msgs/PointCloud2")] and summary.count(TOPIC) == 1
    with pytest.raises(InputError, match=r"--frame 1 does not exist: .* has 1 frame \(0..0\)"):
        read_frame(bag, index=1)
    with pytest.raises(InputError, match="no topic '/nope'"):
        read_frame(bag, topic="/nope")


def test_cli_plan_and_info_on_real_ros1_bag() -> None:
    bag = shared_path(REAL_BAG)
    result = _clear("plan", str(bag), "--json")
    assert result.returncode in (0, 10), result.stderr  # 10: a partial plan, a valid result
    assert "Traceback" not in result.stderr
    doc = json.loads(result.stdout)
    assert isinstance(doc, dict) and doc.get("schema", "").startswith("clear.")

    result = _clear("info", "--json", str(bag))
    assert result.returncode == 0, result.stderr
    doc = json.loads(result.stdout)
    assert doc["format"] == "rosbag1" and "mcap" not in doc
    b = doc["bag"]
    assert b["profile"] == "ros1" and b["indexed"] and b["complete"] and b["storage"] == "rosbag1"
    assert b["pointcloud_topic"] == TOPIC and b["frame_count"] == 1 and b["message_count"] == 1
    assert b["channels"] == [
        {
            "topic": TOPIC,
            "schema": "sensor_msgs/PointCloud2",
            "schema_encoding": "ros1msg",
            "message_encoding": "ros1",
            "message_count": 1,
            "point_cloud": True,
        }
    ]
    assert b["start_s"] == pytest.approx(1.3e9) and b["duration_s"] == 0.0
    assert doc["frame"]["shape"] == [480, 640] and doc["frame"]["finite_points"] == 171483

    table = _clear("info", str(bag))
    assert table.returncode == 0, table.stderr
    assert "ROS 1 bag" in table.stdout and "307 200" in table.stdout and "sensor_msgs/Point" in table.stdout


def test_truncated_real_ros1_bag(tmp_path: Path) -> None:
    data = shared_path(REAL_BAG).read_bytes()
    # Inside the bag header, inside the one chunk (the frame is lost): no frame, exit 3 for
    # the frame readers; `clear info` describes what precedes the damage, then exits 9.
    for n in (20, 5000, len(data) // 2):
        cut = tmp_path / f"cut{n}.bag"
        cut.write_bytes(data[:n])
        _one_line_error(_clear("plan", str(cut), "--json"), (EXIT_INPUT,), str(cut), "truncated", "ROS 1 bag")
        _one_line_error(
            _clear("info", "--json", str(cut)), (EXIT_PARTIAL,), str(cut), "breaks after 0 complete messages"
        )
        with pytest.raises(InputError, match="(truncated or corrupt|corrupt or truncated) ROS 1 bag"):
            read_frame(cut)
    # Just before the end: the chunk survives, the index is lost.
    cut = tmp_path / "cut_end.bag"
    cut.write_bytes(data[:-50])
    result = _clear("info", "--json", str(cut))
    _one_line_error(result, (EXIT_PARTIAL,), str(cut), "bag breaks after 1 complete message (")
    assert json.loads(result.stdout)["frame"]["points"] == 307200
    # With the index gone but the chunk whole, the frame is still read (file order).
    summary = read_bag_summary(cut)
    assert not summary.indexed and summary.damage and summary.count(TOPIC) == 1
    assert read_frame(cut).n_points == 307200
    got = []
    with pytest.raises(PartialLogError, match=f"after frame 0 of {TOPIC}"):
        for frame in iter_frames(cut):
            got.append(frame)
    assert len(got) == 1 and _same(got[0].points, read_pcd(shared_path("mosd/test/test57.pcd")).points)


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_rosbag2_written_by_rosbags_reads_back_point_for_point(tmp_path: Path, storage: str) -> None:
    frames = _frames(2)
    bag = write_rosbag2(tmp_path / f"bag_{storage}", {TOPIC: frames}, storage=storage, strings={"/chatter": 3})
    assert (bag / "metadata.yaml").is_file()
    assert sniff(bag) == "rosbag2" and sniff(bag / "metadata.yaml") == "rosbag2"
    got = list(iter_frames(bag))
    assert len(got) == 2
    for g, want in zip(got, frames):
        _assert_same_frame(g, want)
    assert got[0].shape == (480, 640) and "label" in got[0].fields
    _assert_same_frame(read_frame(bag, index=1), frames[1])
    _assert_same_frame(read_frame(bag / "metadata.yaml", index=0), frames[0])
    summary = read_bag_summary(bag)
    assert summary.storage == storage and summary.profile == "ros2" and summary.message_count == 5
    assert summary.count(TOPIC) == 2 and summary.count("/chatter") == 3
    assert summary.start_ns == 100_000_000_000 and summary.end_ns == 100_500_000_000
    with pytest.raises(InputError, match=r"--frame 2 does not exist: .* has 2 frames \(0..1\)"):
        read_frame(bag, index=2)
    with pytest.raises(InputError, match="topic /chatter has type std_msgs/msg/String, not a point cloud"):
        read_frame(bag, topic="/chatter")

    result = _clear("info", "--json", str(bag), "--frame", "1")
    assert result.returncode == 0, result.stderr
    doc = json.loads(result.stdout)
    assert doc["format"] == "rosbag2" and doc["bag"]["storage"] == storage
    assert doc["bag"]["frame_count"] == 2 and doc["frame"]["index"] == 1
    assert {c["topic"]: c["message_count"] for c in doc["bag"]["channels"]} == {TOPIC: 2, "/chatter": 3}
    assert doc["bag"]["duration_s"] == pytest.approx(0.5)
    assert doc["frame"]["finite_points"] == int(frames[1].finite_mask.sum())

    if storage == "sqlite3":  # the .db3 alone (no metadata.yaml) is a bag too
        db3 = next(bag.glob("*.db3"))
        alone = tmp_path / "alone.db3"
        shutil.copy(db3, alone)
        assert sniff(alone) == "rosbag2"
        _assert_same_frame(read_frame(alone, index=1), frames[1])


def test_ros1_written_by_rosbags_reads_back_and_seeks(tmp_path: Path) -> None:
    frames = _frames(4, rows=40)
    # Frames 1 and 2 share one log time: --frame 2 must still be frame 2, not frame 1.
    times = [100.0, 101.0, 101.0, 102.0]
    for compression in (None, "lz4", "bz2"):
        bag = write_ros1(
            tmp_path / f"four_{compression}.bag",
            {TOPIC: frames},
            strings={"/rosout": 2},
            times=times,
            compression=compression,
        )
        got = list(iter_frames(bag))
        assert len(got) == 4
        for g, want in zip(got, frames):
            _assert_same_frame(g, want)
        for i in (3, 2, 1, 0):
            _assert_same_frame(read_frame(bag, index=i), frames[i])
        summary = read_bag_summary(bag)
        assert summary.indexed and summary.count(TOPIC) == 4 and summary.count("/rosout") == 2
        assert dict(summary.topics()) == {"/rosout": "std_msgs/String", TOPIC: "sensor_msgs/PointCloud2"}


def test_topic_rules(tmp_path: Path) -> None:
    frames = _frames(1, rows=8)
    none1 = write_ros1(tmp_path / "none.bag", {}, strings={"/chatter": 2, "/rosout": 1})
    none2 = write_rosbag2(tmp_path / "none2", {}, strings={"/chatter": 2})
    # (A folder given to `plan` makes a batch; its metadata.yaml names the one bag.)
    for bag, arg, needles in [
        (none1, none1, (f"no point-cloud topic in {none1}", "/chatter (std_msgs/String)", "/rosout (std_msgs/String)")),
        (none2, none2 / "metadata.yaml", ("no point-cloud topic in ", "none2", "/chatter (std_msgs/msg/String)")),
    ]:
        _one_line_error(_clear("plan", str(arg), "--json"), (EXIT_INPUT,), *needles)
        _one_line_error(_clear("segment", str(arg)), (EXIT_INPUT,), *needles)
        with pytest.raises(InputError, match="no point-cloud topic in .*/chatter"):
            read_frame(bag)
        info = _clear("info", "--json", str(bag))  # info describes a bag without point clouds
        assert info.returncode == 0, info.stderr
        assert json.loads(info.stdout)["frame"] is None

    two = write_ros1(tmp_path / "two.bag", {"/a/points": frames, "/b/points": frames}, strings={"/chatter": 1})
    _one_line_error(
        _clear("plan", str(two), "--json"),
        (EXIT_INPUT,),
        "several point-cloud topics (/a/points, /b/points)",
        "--topic",
    )
    _assert_same_frame(read_frame(two, topic="/b/points"), frames[0])
    _one_line_error(
        _clear("info", str(two), "--topic", "/chatter"),
        (EXIT_INPUT,),
        "topic /chatter has type std_msgs/String, not a point cloud",
    )
    _one_line_error(_clear("info", str(two), "--topic", "/x"), (EXIT_INPUT,), "no topic '/x'")

    plain = tmp_path / "plain_dir"
    plain.mkdir()
    with pytest.raises(InputError, match="is a directory without metadata.yaml"):
        read_frame(plain)
    shutil.copy(next((tmp_path / "none2").glob("*.db3")), plain / "x.db3")
    with pytest.raises(InputError, match=r"it holds x\.db3: pass that file instead"):
        read_frame(plain)


def test_truncated_and_corrupt_written_bags(tmp_path: Path) -> None:
    frames = _frames(3, rows=40)
    bag = write_ros1(tmp_path / "three.bag", {TOPIC: frames})
    data = bag.read_bytes()
    # Cut inside the third frame's chunk: two complete frames, then PartialLogError.
    cut = tmp_path / "cut.bag"
    cut.write_bytes(data[: int(len(data) * 0.8)])
    got: list[Frame] = []
    with pytest.raises(PartialLogError, match=f"after frame 1 of {TOPIC}") as info:
        for frame in iter_frames(cut):
            got.append(frame)
    assert "\n" not in str(info.value) and len(got) == 2
    for g, want in zip(got, frames):
        _assert_same_frame(g, want)
    _assert_same_frame(read_frame(cut, index=1), frames[1])
    for past in (2, 5):
        with pytest.raises(PartialLogError, match=r"after frame 1 of .* \(2 complete frames read;"):
            read_frame(cut, index=past)
    result = _clear("info", "--json", str(cut))
    _one_line_error(result, (EXIT_PARTIAL,), "cut.bag", "2 complete messages")
    assert json.loads(result.stdout)["bag"]["frame_count"] == 2

    # ROS 1 bags have no CRC: zeros inside point data cannot be told, a broken record can.
    # Zeros over the third message's record header (the index intact): two frames, then
    # PartialLogError; over the chunk's header (the index unusable): no frame, InputError.
    from rosbags.rosbag1 import Reader

    with Reader(bag) as reader:
        (conn,) = reader.connections
        third = reader.indexes[conn.id][2]
        msg_pos = reader.chunks[third.chunk_pos].datapos + third.offset
        chunk_pos = third.chunk_pos
    for pos, want_frames in ((msg_pos, 2), (chunk_pos, 0)):
        corrupt = bytearray(data)
        corrupt[pos : pos + 64] = b"\x00" * 64
        bad = tmp_path / f"bad{pos}.bag"
        bad.write_bytes(bytes(corrupt))
        got = []
        with pytest.raises(ClearError) as err:
            for frame in iter_frames(bad):
                got.append(frame)
        assert "\n" not in str(err.value) and len(got) == want_frames
        if want_frames:
            assert isinstance(err.value, PartialLogError) and f"after frame 1 of {TOPIC}" in str(err.value)
            for g, want in zip(got, frames):
                _assert_same_frame(g, want)
        else:
            assert isinstance(err.value, InputError) and "ROS 1 bag" in str(err.value)
        _one_line_error(
            _clear("info", str(bad), "--frame", str(want_frames)),
            (EXIT_PARTIAL,) if want_frames else (EXIT_INPUT, EXIT_PARTIAL),
            str(bad),
        )

    # rosbag2 storage cut short: sqlite3 is unreadable; an MCAP storage file is read alone
    # up to its damage, and the error says so.
    bag2 = write_rosbag2(tmp_path / "b2", {TOPIC: frames})
    db3 = next(bag2.glob("*.db3"))
    db3.write_bytes(db3.read_bytes()[: db3.stat().st_size // 2])
    _one_line_error(_clear("info", str(bag2)), (EXIT_INPUT, EXIT_PARTIAL), str(bag2))
    five = _frames(5, rows=40)  # rosbags closes an MCAP chunk past 1 MiB: frames 0-2, then 3-4
    bag3 = write_rosbag2(tmp_path / "b3", {TOPIC: five}, storage="mcap")
    storage = next(bag3.glob("*.mcap"))
    storage.write_bytes(storage.read_bytes()[: int(storage.stat().st_size * 0.8)])
    with pytest.raises(InputError, match=f"pass {storage} itself"):
        read_frame(bag3)
    got = []
    with pytest.raises(PartialLogError, match="after frame 2"):
        for frame in iter_frames(storage):
            got.append(frame)
    assert len(got) == 3
    for g, want in zip(got, five):
        _assert_same_frame(g, want)


def test_ros1_truncation_fuzz_only_clear_errors(tmp_path: Path) -> None:
    bag = write_ros1(tmp_path / "small.bag", {TOPIC: _frames(2, rows=1)}, strings={"/chatter": 2})
    data = bag.read_bytes()
    path = tmp_path / "cut.bag"
    outcomes = set()
    for end in list(range(0, 200, 7)) + list(range(200, len(data), 97)) + [len(data) - 1]:
        path.write_bytes(data[:end])
        try:
            n = len(list(iter_frames(path)))
            outcomes.add(f"ok{n}")
        except PartialLogError:
            outcomes.add("partial")
        except InputError:
            outcomes.add("input")
    assert {"input", "partial"} <= outcomes


@pytest.mark.parametrize("kind", ["rosbag1", "sqlite3", "mcap"])
def test_static_transforms(tmp_path: Path, kind: str) -> None:
    half = np.sqrt(0.5)
    tf = ("wam_base", "camera_rgb_optical_frame", [0.1, -0.2, 0.8], [0.0, 0.0, half, half])
    frames = _frames(1, rows=4)
    if kind == "rosbag1":
        bag = write_ros1(tmp_path / "tf.bag", {TOPIC: frames}, tf=tf)
    else:
        bag = write_rosbag2(tmp_path / f"tf_{kind}", {TOPIC: frames}, storage=kind, tf=tf)
    found = read_bag_transforms(bag)
    T = found[("wam_base", "camera_rgb_optical_frame")]
    want = np.eye(4)
    want[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]  # 90 degrees about z
    want[:3, 3] = [0.1, -0.2, 0.8]
    assert np.allclose(T, want, atol=1e-12)
    assert read_bag_transforms(write_ros1(tmp_path / "notf.bag", {TOPIC: frames})) == {}
    assert len(list(iter_frames(bag))) == 1  # /tf_static does not disturb the topic rules


@pytest.mark.parametrize("kind", ["ros1", "rosbag2"])
def test_replay_places_the_robot_from_a_bags_tf_static(tmp_path: Path, kind: str) -> None:
    """`replay` reads where the robot stands from a bag's /tf_static, as from an MCAP's."""
    from clearcli.io.tf import base_camera_from_log

    tf = ("wam_link_base", "camera_rgb_optical_frame", [0.1, -0.2, 0.5], [0.0, 0.0, 0.0, 1.0])
    if kind == "ros1":
        bag = tmp_path / "session.bag"
        write_ros1(bag, {TOPIC: _frames(1, rows=4)}, tf=tf)
    else:
        bag = write_rosbag2(tmp_path / "session", {TOPIC: _frames(1, rows=4)}, tf=tf)
    T, base = base_camera_from_log(bag, "camera_rgb_optical_frame")
    assert base == "wam_link_base" and T is not None
    np.testing.assert_allclose(T[:3, 3], [0.1, -0.2, 0.5])
    np.testing.assert_allclose(T[:3, :3], np.eye(3))
    assert base_camera_from_log(bag, "no_such_frame") == (None, "")


def test_rosbag2_metadata_with_a_list_for_a_topic_name_is_one_line(tmp_path: Path) -> None:
    # before: an internal TypeError (unhashable type: 'list') from the summary's topic table
    bag = write_rosbag2(tmp_path / "bag", {TOPIC: _frames(1)}, storage="sqlite3")
    meta = bag / "metadata.yaml"
    meta.write_text(meta.read_text().replace(f"name: {TOPIC}", "name: [nope.db3]", 1))
    with pytest.raises(InputError, match=r"metadata.yaml gives a topic whose name \(\['nope.db3'\]\) .* is not text"):
        read_bag_summary(bag)
    _one_line_error(_clear("info", str(bag)), (EXIT_INPUT,), "is not text; fix the bag's metadata")
