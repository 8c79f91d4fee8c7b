"""Logs cut anywhere keep every whole frame: depth-image logs (RGB-D) by the same rule and
code path as point-cloud logs (clearcli/io/mcap.py `_scan`, `choose_topic`, `_guarded`;
clearcli/io/rosbag.py for ROS 1 bags). A frame is whole when its message lies wholly
before the cut; then the command goes through every whole frame and exits 9 (3 when none
is whole)."""

from __future__ import annotations

import json
import struct
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from helpers import run_clear, shared_path
from PIL import Image

from clearcli.errors import EXIT_INPUT, EXIT_PARTIAL, EXIT_SCENE, ClearError, InputError, PartialLogError
from clearcli.io.read import iter_frames, read_frame

RGBD_LOG = "rgbd/uois_realsense_ros2.mcap"  # 9 frames: one zstd chunk each (4 messages)
POINTS_LOG = "mcap/mosd_tabletop_ros2_pointcloud2.mcap"  # 3 frames: one chunk each
DEPTH_TOPIC = "/camera/camera/aligned_depth_to_color/image_raw"
# The stages are not what these tests are about, and a replay of real frames takes seconds
# each: with no table in reach, every frame read is reported at once (status no_table, or
# exit 4 for one frame), which shows that it was read whole.
NO_TABLE = ("--set", "segment.table_max_distance_m=0.05")


def _layout(path: Path) -> tuple[list[tuple[int, int]], int]:
    """([(chunk start, chunk end)] in file order, summary start) of an intact MCAP log, each
    chunk checked to hold exactly one frame of the log's frame topic."""
    from mcap.reader import make_reader

    data = path.read_bytes()
    # the footer: opcode 0x02, length, summary_start, summary_offset_start, crc; then the magic
    footer = len(data) - 8 - (1 + 8 + 8 + 8 + 4)
    assert data[footer] == 0x02
    (summary_start,) = struct.unpack_from("<Q", data, footer + 9)
    with open(path, "rb") as fp:
        summary = make_reader(fp).get_summary()
    assert summary is not None
    frame_channels = {
        cid for cid, ch in summary.channels.items() if ch.topic in (DEPTH_TOPIC, "/camera/depth_registered/points")
    }
    chunks = sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)
    for c in chunks:
        assert len(set(c.message_index_offsets) & frame_channels) == 1
    return [(c.chunk_start_offset, c.chunk_start_offset + c.chunk_length) for c in chunks], summary_start


def _cuts(path: Path) -> dict[str, tuple[int, int]]:
    """{where: (bytes kept, frames wholly before the cut)}."""
    chunks, summary_start = _layout(path)
    size = path.stat().st_size
    whole = lambda n: sum(1 for _, end in chunks if end <= n)  # noqa: E731
    k = len(chunks) // 2
    cuts = {
        "in the data": chunks[k][0] + (chunks[k][1] - chunks[k][0]) // 3,  # inside chunk k
        "at a message boundary": chunks[k - 1][1],  # right after chunk k-1, before its indexes
        "in the summary only": summary_start + (size - summary_start) // 2,
    }
    return {where: (n, whole(n)) for where, n in cuts.items()}


def _replay(path: Path, *args: str) -> tuple[int, list[dict[str, Any]], str]:
    result = run_clear("replay", path, "--json", *args, timeout=900)
    lines = [json.loads(line) for line in result.stdout.splitlines() if line.strip()]
    return result.returncode, lines, result.stderr


def _assert_whole_frames_then_9(path: Path, whole: int, total: int, *args: str) -> None:
    code, lines, err = _replay(path, *args)
    frames = [d for d in lines if d["type"] == "frame"]
    errors = [line for line in err.splitlines() if line.startswith("clear: error:")]
    assert "Traceback" not in err
    if whole == 0:
        assert code == EXIT_INPUT and len(errors) == 1, err
        return
    assert code == EXIT_PARTIAL, (code, err)
    assert len(errors) == 1 and f"{whole} complete frame" in errors[0], err
    assert [d["index"] for d in frames] == list(range(whole)), (len(frames), whole, total)
    summary = lines[-1]
    assert summary["type"] == "summary" and summary["frames_read"] == whole and summary["stopped"]


@pytest.mark.parametrize("log", [RGBD_LOG, POINTS_LOG])
@pytest.mark.parametrize("where", ["in the data", "at a message boundary", "in the summary only"])
def test_a_cut_log_replays_every_whole_frame_then_exit_9(tmp_path: Path, log: str, where: str) -> None:
    """The RGB-D recording and the point-cloud log, cut at the same places: the same rule.
    A cut in the summary alone leaves every frame whole: all are replayed, then exit 9
    (the log is damaged all the same), as the point-cloud log always did."""
    src = shared_path(log)
    n, whole = _cuts(src)[where]
    total = len(_layout(src)[0])
    assert 0 < whole <= total and (whole == total) == (where == "in the summary only")
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(src.read_bytes()[:n])
    # the report's case replays its frames fully; the others only read them
    _assert_whole_frames_then_9(cut, whole, total, *(() if (log, where) == (RGBD_LOG, "in the data") else NO_TABLE))


def test_a_cut_rgbd_log_reads_described_and_plans_like_a_cut_point_cloud_log(tmp_path: Path) -> None:
    src = shared_path(RGBD_LOG)
    n, whole = _cuts(src)["in the data"]
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(src.read_bytes()[:n])
    intact = list(iter_frames(src))
    got = []
    with pytest.raises(PartialLogError, match=f"after frame {whole - 1} of {DEPTH_TOPIC}"):
        for frame in iter_frames(cut):
            got.append(frame)
    assert len(got) == whole
    for frame, want in zip(got, intact):  # every frame read is the intact log's, point for point
        np.testing.assert_array_equal(frame.points, want.points)
    np.testing.assert_array_equal(read_frame(cut, index=whole - 1).points, intact[whole - 1].points)
    with pytest.raises(PartialLogError):
        read_frame(cut, index=whole)  # past the damage: exit 9, not "no such frame"
    # `clear info` describes it (the depth topic is its frame topic), then exits 9
    result = run_clear("info", "--json", cut)
    assert result.returncode == EXIT_PARTIAL, result.stderr
    info = json.loads(result.stdout)
    assert info["mcap"]["complete"] is False and info["mcap"]["pointcloud_topic"] == DEPTH_TOPIC
    assert info["mcap"]["frame_count"] == whole and info["frame"]["shape"] == [480, 640]
    # `clear plan --frame N`: a whole frame is read (and found without a table in reach:
    # exit 4); past the damage, exit 9
    planned = run_clear("plan", cut, "--frame", whole - 1, "--json", *NO_TABLE)
    assert planned.returncode == EXIT_SCENE, planned.stderr
    past = run_clear("plan", cut, "--frame", whole, "--json", *NO_TABLE)
    assert past.returncode == EXIT_PARTIAL, past.stderr
    assert len([x for x in past.stderr.splitlines() if x.startswith("clear: error:")]) == 1


def test_a_log_cut_before_any_frame_topic_says_frame_topic(tmp_path: Path) -> None:
    data = shared_path(RGBD_LOG).read_bytes()
    cut = tmp_path / "early.mcap"
    cut.write_bytes(data[:40])  # the header alone: no channel yet
    with pytest.raises(InputError, match="before any frame topic"):
        read_frame(cut)


# --- ROS 1 bags ------------------------------------------------------------------------


def _rgbd_bag(path: Path, n: int) -> tuple[Path, list[int]]:
    """A ROS 1 bag of the first n uois frames (depth, colour, camera info), and the byte
    where each depth message ends (found by its pixels, the message's last field)."""
    from helpers.rgbd_logs import write_rgbd_bag

    uois = shared_path("rgbd/uois")
    depth = [np.asarray(Image.open(uois / f"uois_{k:04d}_depth.png")) for k in range(n)]
    color = [np.asarray(Image.open(uois / f"uois_{k:04d}_color.png")) for k in range(n)]
    write_rgbd_bag(path, depth, color, ros1=True)
    data = path.read_bytes()
    ends = []
    for d in depth:
        start = data.find(np.ascontiguousarray(d).tobytes())
        assert start > 0
        ends.append(start + d.nbytes)
    return path, ends


def _count_then_error(path: Path) -> tuple[int, ClearError | None]:
    n = 0
    try:
        for _ in iter_frames(path):
            n += 1
    except ClearError as exc:
        return n, exc
    return n, None


def test_a_cut_ros1_rgbd_bag_keeps_every_whole_frame_like_a_cut_point_cloud_bag(tmp_path: Path) -> None:
    bag, ends = _rgbd_bag(tmp_path / "rgbd.bag", 4)
    data = bag.read_bytes()
    cut = tmp_path / "cut.bag"
    cuts = {
        "in depth message 2": ends[2] - 1000,
        "at the end of depth message 1": ends[1],
        "in the index only": len(data) - 50,
    }
    for where, n in cuts.items():
        cut.write_bytes(data[:n])
        whole = sum(1 for end in ends if end <= n)
        got, error = _count_then_error(cut)
        assert got == whole, (where, got, whole)
        assert isinstance(error, PartialLogError), (where, error)
        assert f"{whole} complete frame" in str(error) and "\n" not in str(error)
    # the point-cloud bag cut in its index: the same, exit 9 after its frame
    points = shared_path("mcap/mosd_tabletop_ros1.bag").read_bytes()
    cut.write_bytes(points[:-50])
    got, error = _count_then_error(cut)
    assert got == 1 and isinstance(error, PartialLogError)


def test_cli_on_a_cut_ros1_rgbd_bag(tmp_path: Path) -> None:
    bag, ends = _rgbd_bag(tmp_path / "rgbd.bag", 3)
    cut = tmp_path / "cut.bag"
    cut.write_bytes(bag.read_bytes()[: ends[1] + 10])
    result = run_clear("info", "--json", cut)
    assert result.returncode == EXIT_PARTIAL, result.stderr
    info = json.loads(result.stdout)
    assert info["bag"]["complete"] is False and info["frame"]["shape"] == [480, 640]
    seg = run_clear("segment", cut, "--frame", 1, "--json", *NO_TABLE)
    assert seg.returncode == EXIT_SCENE, seg.stderr  # read whole: no table within 5 cm, as asked
    past = run_clear("segment", cut, "--frame", 2, "--json", *NO_TABLE)
    assert past.returncode == EXIT_PARTIAL, past.stderr
