"""Tests of clearcli/io/describe.py."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import shared_path

from clearcli.io.describe import describe_file
from clearcli.io.pcd import read_pcd


def test_info_pcd_values() -> None:
    path = shared_path("mosd/test/test57.pcd")
    info = describe_file(path)
    assert info["format"] == "pcd"
    assert info["pcd"]["encoding"] == "binary_compressed"
    assert [f["name"] for f in info["pcd"]["fields"]] == ["label", "x", "y", "z", "rgba"]
    frame = info["frame"]
    assert frame["points"] == 307200 and frame["shape"] == [480, 640] and frame["organized"]
    assert frame["finite_points"] == 171483 and frame["has_colors"]
    assert [f["name"] for f in frame["fields"]] == ["x", "y", "z", "rgb", "label"]
    pts = read_pcd(path).points
    finite = np.isfinite(pts).all(axis=1)
    assert frame["bounds_m"]["min"] == pytest.approx(pts[finite].min(axis=0).tolist(), abs=1e-6)
    assert frame["bounds_m"]["max"] == pytest.approx(pts[finite].max(axis=0).tolist(), abs=1e-6)
    # The camera is about 0.6 m above the table, looking down: depths between 0.5 and 1.5 m.
    assert 0.5 < frame["bounds_m"]["min"][2] < frame["bounds_m"]["max"][2] < 1.5


def test_info_mcap_values() -> None:
    info = describe_file(shared_path("mcap/ouster_ros1_pointcloud2.mcap"))
    m = info["mcap"]
    assert m["profile"] == "ros1" and m["indexed"] and m["complete"]
    assert m["message_count"] == 273
    assert m["pointcloud_topic"] == "/os1_cloud_node/points" and m["frame_count"] == 2
    assert m["duration_s"] == pytest.approx(0.183, abs=0.001)
    rosout = [c for c in m["channels"] if c["topic"] == "/rosout"]
    assert len(rosout) == 2 and sum(c["message_count"] for c in rosout) == 12
    assert info["frame"]["shape"] == [64, 2048] and info["frame"]["frame_id"] == "os1_lidar"

    ros2 = describe_file(shared_path("mcap/mosd_tabletop_ros2_pointcloud2.mcap"), index=2)
    assert ros2["mcap"]["frame_count"] == 3 and ros2["frame"]["index"] == 2
    assert ros2["frame"]["finite_points"] == int(read_pcd(shared_path("mosd/learn/learn21.pcd")).finite_mask.sum())

    counts = {
        "mcap/mosd_tabletop_foxglove_protobuf.mcap": 2,
        "mcap/mosd_tabletop_foxglove_json.mcap": 1,
    }
    for rel, n in counts.items():
        d = describe_file(shared_path(rel))
        assert d["mcap"]["frame_count"] == n and d["frame"]["shape"] is None

    none = describe_file(shared_path("mcap/rosbag2/talker.mcap"))
    assert none["mcap"]["pointcloud_topic"] is None and none["frame"] is None
    assert {c["topic"] for c in none["mcap"]["channels"]} == {"/rosout", "/parameter_events", "/topic"}
