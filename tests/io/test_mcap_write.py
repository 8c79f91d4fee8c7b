"""Tests of clearcli/io/mcap_write.py."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers import shared_path
from helpers.io import _same, _small_frame

from clearcli.io.frames import Frame
from clearcli.io.mcap import read_summary
from clearcli.io.mcap_write import StaticTransform, write_pointcloud2_mcap
from clearcli.io.pcd import read_pcd
from clearcli.io.read import iter_frames, read_frame


def test_write_pointcloud2_round_trip(tmp_path: Path) -> None:
    a = _small_frame()
    b = Frame(points=a.points[::-1].copy(), colors=None, shape=None, stamp_s=13.5)
    out = tmp_path / "out.mcap"
    labels = [np.arange(a.n_points, dtype=np.uint32) * 10, None]
    T = np.eye(4)
    T[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]  # 90 degrees about z
    T[:3, 3] = [0.1, -0.2, 0.75]
    n = write_pointcloud2_mcap(out, [a, b], labels=labels, tf_static=[StaticTransform("table", "cam", T, stamp_s=12.0)])
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
        ((_, _, _, msg),) = list(reader.iter_decoded_messages(topics=["/tf_static"]))
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
