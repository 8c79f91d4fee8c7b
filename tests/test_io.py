"""Frame input/output: PCD and MCAP reading of the shared real data, writing, bad input."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

from clearcli.errors import ClearError, InputError, PartialLogError, SceneError
from clearcli.io.frames import Frame
from clearcli.io.mcap import read_summary
from clearcli.io.mcap_write import StaticTransform, write_pointcloud2_mcap
from clearcli.io.pcd import read_pcd, write_pcd
from clearcli.io.pointfields import pack_rgb_float, unpack_rgb
from clearcli.io.read import iter_frames, read_frame, require_finite
from utils import SHARED_DATA, shared_path

MOSD_TEST = ["test44", "test46", "test47", "test55", "test57"]


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and bool(np.array_equal(a, b, equal_nan=True))


def _small_frame(n_rows: int = 4, n_cols: int = 5, nan_rows: tuple[int, ...] = (2,)) -> Frame:
    """An organized frame with hand-chosen values, NaN pixels, colours and labels."""
    n = n_rows * n_cols
    idx = np.arange(n, dtype=np.float32)
    points = np.stack([idx * 0.01, -idx * 0.02, 0.5 + idx * 0.001], axis=1).astype(np.float32)
    for r in nan_rows:
        points[r] = np.nan
    colors = np.stack([idx % 256, (idx * 7) % 256, 255 - idx % 256], axis=1).astype(np.uint8)
    labels = (np.arange(n) % 3 * 10).astype(np.uint32)
    return Frame(points=points, colors=colors, shape=(n_rows, n_cols), fields={"label": labels},
                 stamp_s=12.25, frame_id="cam", source="small")


# --- colour packing --------------------------------------------------------------------


def test_rgb_packing_hand_values() -> None:
    colors = np.array([[255, 0, 0], [0, 128, 0], [1, 2, 3]], dtype=np.uint8)
    packed = pack_rgb_float(colors)
    assert packed.dtype == np.float32
    assert packed.view(np.uint32).tolist() == [0xFF0000, 0x008000, 0x010203]
    assert unpack_rgb(packed).tolist() == colors.tolist()
    # rgba as uint32 0xAARRGGBB: alpha ignored.
    assert unpack_rgb(np.array([0x80102030], dtype=np.uint32)).tolist() == [[0x10, 0x20, 0x30]]


# --- PCD: every shared file ------------------------------------------------------------


def _all_pcds() -> list[Path]:
    base = shared_path("pcd_formats")
    files = sorted(base.glob("*.pcd")) + sorted((SHARED_DATA / "mosd").rglob("*.pcd"))
    return files


def test_every_shared_pcd_reads_or_is_rejected_cleanly() -> None:
    files = _all_pcds()
    assert len(files) >= 9 + 50
    for path in files:
        if path.name == "stereo_left.pcd":
            with pytest.raises(InputError, match="no x/y/z"):
                read_pcd(path)
            continue
        frame = read_pcd(path)
        assert frame.points.dtype == np.float32 and frame.points.shape == (frame.n_points, 3)
        if frame.shape is not None:
            assert frame.shape[0] * frame.shape[1] == frame.n_points
        assert frame.finite_mask.sum() > 0


def test_pcd_formats_values() -> None:
    bun = read_pcd(shared_path("pcd_formats/bun0.pcd"))  # ascii, normals + curvature
    assert bun.n_points == 397 and bun.shape is None and bun.colors is None
    assert set(bun.fields) == {"normal_x", "normal_y", "normal_z", "curvature"}
    colored = read_pcd(shared_path("pcd_formats/colored_cloud.pcd"))  # binary, rgb as U4
    assert colored.n_points == 1000 and colored.shape == (1000, 1) and colored.colors is not None
    assert "rgb" not in colored.fields and "curvature" in colored.fields
    mug = read_pcd(shared_path("pcd_formats/table_scene_mug_rgb_float.pcd"))  # rgb as F4
    assert mug.shape == (480, 640) and mug.colors is not None
    assert int(mug.finite_mask.sum()) == 209280
    room = read_pcd(shared_path("pcd_formats/capture0001_xyz_only_room.pcd"))
    assert room.colors is None and room.fields == {} and room.shape == (480, 640)
    keys = read_pcd(shared_path("pcd_formats/office1_keypoints.pcd"))
    assert keys.n_points == 1318 and keys.fields["intensity"].dtype == np.float32


def test_rgb_float_colours_match_open3d() -> None:
    import open3d as o3d

    path = shared_path("pcd_formats/table_scene_mug_rgb_float.pcd")
    ours = read_pcd(path)
    theirs = o3d.io.read_point_cloud(str(path), remove_nan_points=False)
    assert _same(np.asarray(theirs.points).astype(np.float32), ours.points)
    assert np.array_equal(np.round(np.asarray(theirs.colors) * 255).astype(np.uint8), ours.colors)


def test_test57_three_encodings_identical() -> None:
    ascii_ = read_pcd(shared_path("pcd_formats/mosd_test57_ascii.pcd"))
    binary = read_pcd(shared_path("pcd_formats/mosd_test57_binary.pcd"))
    compressed = read_pcd(shared_path("mosd/test/test57.pcd"))
    for other in (ascii_, binary):
        assert other.shape == compressed.shape == (480, 640)
        assert _same(other.points, compressed.points)
        assert np.array_equal(other.colors, compressed.colors)
        assert np.array_equal(other.fields["label"], compressed.fields["label"])
    assert int(compressed.finite_mask.sum()) == 171483


def test_mosd_frames_organized_with_labels_and_nan_in_place() -> None:
    for name in MOSD_TEST:
        frame = read_pcd(shared_path(f"mosd/test/{name}.pcd"))
        assert frame.shape == (480, 640) and frame.n_points == 640 * 480
        labels = frame.fields["label"]
        assert labels.dtype == np.uint32 and labels.shape == (640 * 480,)
        finite = frame.finite_mask
        # Invalid pixels stay where they are and carry label 0; some objects (>= 10) exist.
        assert 0 < finite.sum() < frame.n_points
        assert np.all(labels[~finite] == 0)
        assert len(np.unique(labels[labels >= 10] // 10)) >= 5
    # test57: complex clutter, 14-16 objects by the README.
    t57 = read_pcd(shared_path("mosd/test/test57.pcd")).fields["label"]
    assert 14 <= len(np.unique(t57[t57 >= 10] // 10)) <= 16


# --- PCD: writing ----------------------------------------------------------------------


def test_write_pcd_round_trip_organized(tmp_path: Path) -> None:
    frame = _small_frame()
    out = tmp_path / "small.pcd"
    write_pcd(out, frame)
    back = read_pcd(out)
    assert back.shape == (4, 5)
    assert _same(back.points, frame.points)
    assert np.array_equal(back.colors, frame.colors)
    assert np.array_equal(back.fields["label"], frame.fields["label"])
    assert b"DATA binary_compressed" in out.read_bytes()[:400]
    assert not [p for p in tmp_path.iterdir() if p.name != "small.pcd"]  # no temp file left


def test_write_pcd_labels_argument_and_unorganized(tmp_path: Path) -> None:
    base = _small_frame()
    frame = Frame(points=base.points, colors=None, shape=None)
    labels = np.full(frame.n_points, 7, dtype=np.int64)
    out = tmp_path / "u.pcd"
    write_pcd(out, frame, labels=labels)
    back = read_pcd(out)
    assert back.shape is None and back.colors is None
    assert back.fields["label"].dtype == np.uint32 and set(back.fields["label"].tolist()) == {7}
    header = out.read_bytes()[:300].decode("ascii", "replace")
    assert "FIELDS x y z label" in header and "WIDTH 20" in header and "HEIGHT 1" in header


def test_write_pcd_mosd_round_trip_and_open3d(tmp_path: Path) -> None:
    import open3d as o3d

    frame = read_pcd(shared_path("mosd/test/test57.pcd"))
    out = tmp_path / "t57.pcd"
    write_pcd(out, frame)
    back = read_pcd(out)
    assert _same(back.points, frame.points) and np.array_equal(back.colors, frame.colors)
    assert np.array_equal(back.fields["label"], frame.fields["label"])
    cloud = o3d.io.read_point_cloud(str(out), remove_nan_points=False)
    assert len(cloud.points) == 307200 and cloud.has_colors()
    assert _same(np.asarray(cloud.points).astype(np.float32), frame.points)
    finite = frame.finite_mask
    assert np.array_equal(np.round(np.asarray(cloud.colors)[finite] * 255).astype(np.uint8), frame.colors[finite])


# --- PCD: bad input --------------------------------------------------------------------

_HEADER = (
    "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n"
    "TYPE F F F\nCOUNT 1 1 1\nWIDTH {w}\nHEIGHT {h}\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {d}\n"
)


def _header(w: int = 3, h: int = 1, n: int | None = None, d: str = "binary") -> bytes:
    return _HEADER.format(w=w, h=h, n=w * h if n is None else n, d=d).encode()


def _xyz(n: int) -> bytes:
    return np.arange(3 * n, dtype="<f4").tobytes()


def _one_line_error(path: Path, match: str, kind: type[ClearError] = InputError) -> str:
    with pytest.raises(kind, match=match) as info:
        read_frame(path)
    message = str(info.value)
    assert "\n" not in message and str(path) in message
    return message


def test_bad_pcd_inputs(tmp_path: Path) -> None:
    cases: dict[str, tuple[bytes, str]] = {
        "empty.pcd": (b"", "empty file"),
        "garbage.pcd": (b"\x00\x01\x02binary junk", "not a PCD file"),
        "text.pcd": (b"hello world\n", "not a PCD file"),
        "comment_only.pcd": (b"# .PCD v0.7\n", "no DATA line"),
        "header_cut.pcd": (_header()[:60], "no DATA line"),
        "points_lie.pcd": (_header(n=5) + _xyz(5), r"POINTS 5 but WIDTH\*HEIGHT = 3\*1 = 3"),
        "organized_lie.pcd": (_header(w=2, h=2, n=3) + _xyz(3), "POINTS 3 but WIDTH"),
        "binary_short.pcd": (_header(w=4) + _xyz(3), "truncated PCD"),
        "binary_cut_mid_point.pcd": (_header(w=3) + _xyz(3)[:-5], "truncated PCD"),
        "compressed_no_sizes.pcd": (_header(d="binary_compressed") + b"\x01\x02", "size header is missing"),
        "compressed_cut.pcd": (
            _header(d="binary_compressed") + struct.pack("<II", 30, 36) + b"\x00" * 10,
            "truncated PCD",
        ),
        "compressed_wrong_size.pcd": (
            _header(d="binary_compressed") + struct.pack("<II", 4, 99) + b"\x00" * 4,
            "unpacks to 99 bytes",
        ),
        "compressed_corrupt.pcd": (
            _header(d="binary_compressed") + struct.pack("<II", 8, 36) + b"\xff" * 8,
            "corrupt PCD",
        ),
        "ascii_short.pcd": (_header(d="ascii") + b"1 2 3\n4 5 6\n", "2 rows"),
        "ascii_bad_token.pcd": (_header(d="ascii") + b"1 2 3\n4 x 6\n7 8 9\n", "bad ASCII point data"),
        "fields_mismatch.pcd": (
            _header().replace(b"SIZE 4 4 4", b"SIZE 4 4"), "3 FIELDS but 2 SIZE"
        ),
        "bad_type.pcd": (_header().replace(b"TYPE F F F", b"TYPE F F Q"), "bad PCD header"),
        "bad_width.pcd": (_header().replace(b"WIDTH 3", b"WIDTH three"), "bad PCD header"),
        "no_xyz.pcd": (_header().replace(b"FIELDS x y z", b"FIELDS a b c") + _xyz(3), "no x/y/z"),
        "ros1.bag.pcd": (b"#ROSBAG V2.0\n\x00\x00", "truncated or corrupt ROS 1 bag"),
    }
    for name, (content, match) in cases.items():
        path = tmp_path / name
        path.write_bytes(content)
        _one_line_error(path, match)
    _one_line_error(tmp_path / "missing.pcd", "file not found")
    with pytest.raises(InputError, match="directory"):
        read_frame(tmp_path)
    with pytest.raises(InputError, match="frame 1 does not exist"):
        read_frame(shared_path("pcd_formats/bun0.pcd"), index=1)


def test_stereo_left_has_no_xyz() -> None:
    path = shared_path("pcd_formats/stereo_left.pcd")
    message = _one_line_error(path, "no x/y/z fields")
    assert "rgba" in message


def test_all_nan_reads_but_require_finite_refuses(tmp_path: Path) -> None:
    path = tmp_path / "nan.pcd"
    path.write_bytes(_header(w=2, h=2) + np.full(12, np.nan, dtype="<f4").tobytes())
    frame = read_frame(path)
    assert frame.shape == (2, 2) and frame.finite_mask.sum() == 0
    with pytest.raises(SceneError, match="0 finite points of 4"):
        require_finite(frame)
    ok = read_frame(shared_path("mosd/test/test57.pcd"))
    assert require_finite(ok, min_points=1000) is ok


def test_pcd_count_field_and_padding(tmp_path: Path) -> None:
    """COUNT 3 fields become (N, 3); PCL's `_` padding is dropped; compressed layout is per field."""
    import lzf

    n = 3
    xyz = np.arange(3 * n, dtype="<f4").reshape(n, 3)
    normal = (np.arange(3 * n, dtype="<f4") + 100).reshape(n, 3)
    pad = np.zeros(n, dtype="<f4")
    blocks = b"".join(np.ascontiguousarray(a).tobytes() for a in (xyz[:, 0], xyz[:, 1], xyz[:, 2], normal, pad))
    packed = lzf.compress(blocks)
    header = (
        "VERSION 0.7\nFIELDS x y z normal _\nSIZE 4 4 4 4 4\nTYPE F F F F F\nCOUNT 1 1 1 3 1\n"
        f"WIDTH {n}\nHEIGHT 1\nPOINTS {n}\nDATA binary_compressed\n"
    ).encode()
    path = tmp_path / "normals.pcd"
    path.write_bytes(header + struct.pack("<II", len(packed), len(blocks)) + packed)
    frame = read_frame(path)
    assert np.array_equal(frame.points, xyz)
    assert list(frame.fields) == ["normal"] and np.array_equal(frame.fields["normal"], normal)


def test_pcd_truncation_fuzz_only_clear_errors(tmp_path: Path) -> None:
    """Every prefix of a small PCD (and a few byte flips) gives a frame or a ClearError."""
    frame = _small_frame(3, 4, nan_rows=())
    good = tmp_path / "good.pcd"
    write_pcd(good, frame)
    data = good.read_bytes()
    path = tmp_path / "cut.pcd"
    for end in range(0, len(data) - 1, 3):
        path.write_bytes(data[:end])
        with pytest.raises(ClearError):
            read_frame(path)
    rng = np.random.default_rng(0)
    for _ in range(60):
        flipped = bytearray(data)
        flipped[int(rng.integers(len(data)))] = int(rng.integers(256))
        path.write_bytes(bytes(flipped))
        try:
            back = read_frame(path)
        except ClearError:
            continue
        # a flip the reader accepts changed a value, never how many points there are
        assert back.n_points == frame.n_points


# --- MCAP: shared logs -----------------------------------------------------------------


def test_ros2_pointcloud2_frames_equal_mosd_pcds() -> None:
    log = shared_path("mcap/mosd_tabletop_ros2_pointcloud2.mcap")
    frames = list(iter_frames(log))
    assert len(frames) == 3
    for i, (frame, name) in enumerate(zip(frames, ["test/test57", "test/test55", "learn/learn21"])):
        pcd = read_pcd(shared_path(f"mosd/{name}.pcd"))
        assert frame.shape == (480, 640)
        assert _same(frame.points, pcd.points)
        assert np.array_equal(frame.colors, pcd.colors)
        assert frame.frame_id == "camera_rgb_optical_frame"
        assert frame.stamp_s == pytest.approx(1300000000.0 + 0.5 * i)
    third = read_frame(log, index=2)
    assert _same(third.points, frames[2].points) and "#2" in third.source


def test_foxglove_protobuf_and_json() -> None:
    proto = list(iter_frames(shared_path("mcap/mosd_tabletop_foxglove_protobuf.mcap")))
    assert len(proto) == 2
    for frame, name in zip(proto, ["test57", "test55"]):
        pcd = read_pcd(shared_path(f"mosd/test/{name}.pcd"))
        finite = pcd.finite_mask
        assert frame.shape is None
        assert np.array_equal(frame.points, pcd.points[finite])  # the finite points, in order
        assert np.array_equal(frame.colors, pcd.colors[finite])
    js = list(iter_frames(shared_path("mcap/mosd_tabletop_foxglove_json.mcap")))
    assert len(js) == 1 and js[0].n_points == 42895 and js[0].colors is not None
    assert js[0].stamp_s == pytest.approx(1300000000.0)
    t57 = read_pcd(shared_path("mosd/test/test57.pcd"))
    known = {tuple(p) for p in t57.points[t57.finite_mask][:, :].tolist()}
    assert all(tuple(p) in known for p in js[0].points[:500].tolist())


def test_ouster_ros1() -> None:
    log = shared_path("mcap/ouster_ros1_pointcloud2.mcap")
    frames = list(iter_frames(log))
    assert len(frames) == 2
    for frame in frames:
        assert frame.shape == (64, 2048) and frame.frame_id == "os1_lidar"
        assert {"intensity", "ring", "range", "reflectivity"} <= set(frame.fields)
        assert frame.fields["ring"].dtype == np.uint8
    # Ouster's `range` is in millimetres: it must agree with |xyz| of finite, non-zero returns.
    f = frames[0]
    rng_m = f.fields["range"].astype(np.float64) / 1000.0
    dist = np.linalg.norm(f.points.astype(np.float64), axis=1)
    ok = rng_m > 1.0
    assert ok.sum() > 10000
    assert np.median(np.abs(dist[ok] - rng_m[ok])) < 0.05
    assert frames[1].stamp_s - frames[0].stamp_s == pytest.approx(0.1, abs=0.01)


def test_logs_without_point_clouds_list_their_topics() -> None:
    logs = sorted(shared_path("mcap/rosbag2").glob("*.mcap"))
    assert len(logs) == 8
    for log in logs:
        summary = read_summary(log)
        with pytest.raises(InputError) as info:
            read_frame(log)
        message = str(info.value)
        assert message.startswith(f"no point-cloud topic in {log}; topics: ")
        for topic, schema in summary.topics():
            assert f"{topic} ({schema})" in message
    talker = shared_path("mcap/rosbag2/talker.mcap")
    with pytest.raises(InputError, match=r"/topic \(std_msgs/msg/String\)"):
        read_frame(talker)


def test_ros1_bag_is_read_not_rejected() -> None:
    # ROS 1 bags are read by clearcli.io.rosbag (tests/test_rosbag.py has the details).
    bag = shared_path("mcap/mosd_tabletop_ros1.bag")
    frames = list(iter_frames(bag))
    assert len(frames) == 1
    assert _same(frames[0].points, read_pcd(shared_path("mosd/test/test57.pcd")).points)


def test_magic_decides_not_the_extension(tmp_path: Path) -> None:
    log = shared_path("mcap/mosd_tabletop_foxglove_json.mcap")
    renamed = tmp_path / "looks_like.pcd"
    renamed.write_bytes(log.read_bytes())
    assert read_frame(renamed).n_points == 42895
    pcd = tmp_path / "cloud.mcap"
    pcd.write_bytes(shared_path("pcd_formats/bun0.pcd").read_bytes())
    assert read_frame(pcd).n_points == 397
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"\x89MCAQ garbage" * 10)
    _one_line_error(junk, "not an MCAP file")


def test_frame_out_of_range_and_topics() -> None:
    log = shared_path("mcap/mosd_tabletop_ros2_pointcloud2.mcap")
    with pytest.raises(InputError, match=r"--frame 3 does not exist: .* has 3 frames \(0..2\)"):
        read_frame(log, index=3)
    with pytest.raises(InputError, match="no topic '/nope'"):
        read_frame(log, topic="/nope")
    ouster = shared_path("mcap/ouster_ros1_pointcloud2.mcap")
    with pytest.raises(InputError, match="sensor_msgs/Imu, not a point cloud"):
        read_frame(ouster, topic="/os1_cloud_node/imu")
    assert read_frame(ouster, topic="/os1_cloud_node/points", index=1).shape == (64, 2048)


def test_truncated_and_corrupt_logs(tmp_path: Path) -> None:
    data = shared_path("mcap/mosd_tabletop_ros2_pointcloud2.mcap").read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * 0.7)])  # three chunks, one frame each: two survive
    got: list[Frame] = []
    with pytest.raises(PartialLogError, match="after frame 1 of /camera/depth_registered/points") as info:
        for frame in iter_frames(cut):
            got.append(frame)
    assert "\n" not in str(info.value)
    assert len(got) == 2
    assert _same(got[1].points, read_pcd(shared_path("mosd/test/test55.pcd")).points)
    assert read_frame(cut, index=1).n_points == 307200
    with pytest.raises(PartialLogError):
        read_frame(cut, index=2)
    early = tmp_path / "early.mcap"
    early.write_bytes(data[:5000])
    _one_line_error(early, "truncated or corrupt")
    corrupt = bytearray(data)
    corrupt[len(data) // 2 : len(data) // 2 + 4000] = b"\x00" * 4000
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(corrupt))
    got = []
    with pytest.raises(PartialLogError, match="after frame 0"):
        for frame in iter_frames(bad):
            got.append(frame)
    assert len(got) == 1


# --- MCAP: writing ---------------------------------------------------------------------


def test_write_pointcloud2_round_trip(tmp_path: Path) -> None:
    a = _small_frame()
    b = Frame(points=a.points[::-1].copy(), colors=None, shape=None, stamp_s=13.5)
    out = tmp_path / "out.mcap"
    labels = [np.arange(a.n_points, dtype=np.uint32) * 10, None]
    T = np.eye(4)
    T[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]  # 90 degrees about z
    T[:3, 3] = [0.1, -0.2, 0.75]
    n = write_pointcloud2_mcap(out, [a, b], labels=labels,
                               tf_static=[StaticTransform("table", "cam", T, stamp_s=12.0)])
    assert n == 2
    summary = read_summary(out)
    assert summary.profile == "ros2"
    assert {(c.topic, c.schema_name, c.message_count) for c in summary.channels} == {
        ("/tf_static", "tf2_msgs/msg/TFMessage", 1),
        ("/camera/depth_registered/points", "sensor_msgs/msg/PointCloud2", 2),
    }
    x, y = list(iter_frames(out))
    assert x.shape == (4, 5) and _same(x.points, a.points) and np.array_equal(x.colors, a.colors)
    assert np.array_equal(x.fields["label"], labels[0]) and x.frame_id == "cam" and x.stamp_s == 12.25
    assert y.shape is None and y.colors is None and _same(y.points, b.points)
    assert y.frame_id == "camera_rgb_optical_frame" and y.stamp_s == 13.5 and y.fields == {}

    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    with open(out, "rb") as fp:
        reader = make_reader(fp, decoder_factories=[DecoderFactory()])
        (_, _, _, msg), = list(reader.iter_decoded_messages(topics=["/tf_static"]))
    tf = msg.transforms[0]
    assert (tf.header.frame_id, tf.child_frame_id) == ("table", "cam")
    r = tf.transform.rotation
    assert (r.x, r.y, r.z, r.w) == pytest.approx((0, 0, np.sqrt(0.5), np.sqrt(0.5)))
    assert (tf.transform.translation.x, tf.transform.translation.z) == pytest.approx((0.1, 0.75))


def test_write_pointcloud2_mosd_equals_source(tmp_path: Path) -> None:
    frame = read_pcd(shared_path("mosd/test/test57.pcd"))
    out = tmp_path / "t57.mcap"
    write_pointcloud2_mcap(out, [frame])
    back = read_frame(out)
    assert back.shape == (480, 640) and _same(back.points, frame.points)
    assert np.array_equal(back.fields["label"], frame.fields["label"])


def _big_frame(seed: int) -> Frame:
    """An organized frame of ~1 MB of random points (incompressible): three of them fill
    more than one of the writer's chunks."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(-1, 1, (300 * 280, 3)).astype(np.float32)
    return Frame(points=points, colors=None, shape=(300, 280), fields={}, stamp_s=float(seed), frame_id="cam", source="big")


def test_mcap_truncation_fuzz_reads_every_whole_frame_or_errs(tmp_path: Path) -> None:
    """A log cut anywhere gives the frames wholly before the cut, each equal to what was
    written, and says it is damaged (PartialLogError) when it lost any; with no whole frame
    it is an InputError. Never silently fewer frames, never zero frames without an error."""
    frames = [_big_frame(k) for k in range(3)]
    good = tmp_path / "good.mcap"
    write_pointcloud2_mcap(good, frames)
    data = good.read_bytes()
    path = tmp_path / "cut.mcap"
    counts = []
    for end in np.linspace(0, len(data), 160).astype(int):
        path.write_bytes(data[: int(end)])
        got: list[Frame] = []
        error: ClearError | None = None
        try:
            for f in iter_frames(path):
                got.append(f)
        except ClearError as exc:
            error = exc
        for f, want in zip(got, frames):  # every frame read is whole and in order
            assert np.array_equal(f.points, want.points) and f.stamp_s == want.stamp_s
        if len(got) < len(frames):
            assert error is not None, f"cut at {end}: {len(got)} frames and no error"
            assert isinstance(error, PartialLogError if got else InputError), (end, type(error))
        counts.append(len(got))
    assert counts == sorted(counts)  # a longer prefix never reads fewer frames
    # the frames of a chunk are read as soon as the chunk is whole: cuts between chunks
    # give the first frames (the writer's chunks hold one or two of these frames)
    assert counts[0] == 0 and counts[-1] == 3 and {1, 2} & set(counts)


def test_pointcloud2_blob_big_endian_with_row_padding() -> None:
    """Rows padded beyond width*point_step, big-endian fields, a COUNT-2 field, an rgb float."""
    from clearcli.io.pointfields import FieldSpec, frame_from_records, records_from_blob

    height, width, step, pad = 2, 3, 20, 4
    specs = [FieldSpec("x", 0, "f4"), FieldSpec("y", 4, "f4"), FieldSpec("z", 8, "f4"),
             FieldSpec("rgb", 12, "f4"), FieldSpec("uv", 16, "u2", 2)]
    dtype = np.dtype({"names": ["x", "y", "z", "rgb", "uv"],
                      "formats": [">f4", ">f4", ">f4", ">u4", (">u2", (2,))],
                      "offsets": [0, 4, 8, 12, 16], "itemsize": step})
    rows = []
    for r in range(height):
        rec = np.zeros(width, dtype=dtype)
        rec["x"] = np.arange(width) + 10 * r
        rec["y"] = -1.5
        rec["z"] = 2.0 + r
        rec["rgb"] = 0x00A0B0C0 + r
        rec["uv"] = [[c, r] for c in range(width)]
        rows.append(rec.tobytes() + b"\xee" * pad)
    records = records_from_blob(b"".join(rows)[:-pad], specs, step, width, height, width * step + pad, True)
    frame = frame_from_records(records, (height, width))
    assert frame.points[:, 0].tolist() == [0, 1, 2, 10, 11, 12]
    assert frame.points[:, 2].tolist() == [2, 2, 2, 3, 3, 3]
    assert frame.colors[0].tolist() == [0xA0, 0xB0, 0xC0] and frame.colors[3].tolist() == [0xA0, 0xB0, 0xC1]
    assert frame.fields["uv"].shape == (6, 2) and frame.fields["uv"][4].tolist() == [1, 1]
    assert frame.fields["uv"].dtype.isnative
    with pytest.raises(ValueError, match="layout needs"):
        records_from_blob(b"\x00" * 50, specs, step, width, height, width * step, True)
