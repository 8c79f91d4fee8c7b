"""Tests of clearcli/io/mcap.py."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers import shared_path
from helpers.io import _one_line_error, _same

from clearcli.errors import ClearError, InputError, PartialLogError
from clearcli.io.frames import Frame
from clearcli.io.mcap import read_summary
from clearcli.io.mcap_write import write_pointcloud2_mcap
from clearcli.io.pcd import read_pcd
from clearcli.io.read import iter_frames, read_frame


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


def _big_frame(seed: int) -> Frame:
    """An organized frame of ~1 MB of random points (incompressible): three of them fill
    more than one of the writer's chunks."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(-1, 1, (300 * 280, 3)).astype(np.float32)
    return Frame(
        points=points, colors=None, shape=(300, 280), fields={}, stamp_s=float(seed), frame_id="cam", source="big"
    )


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
