"""clearcli/io/mcap_images.py: depth image topics of MCAP logs read as the frames a point cloud gives."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers import shared_path
from helpers.rgbd_logs import write_rgbd_mcap
from PIL import Image

from clearcli.errors import InputError, PartialLogError
from clearcli.io.pcd import read_pcd
from clearcli.io.read import iter_frames, read_frame


def _uois(k: int) -> tuple[np.ndarray, np.ndarray, object]:
    depth = np.asarray(Image.open(shared_path(f"rgbd/uois/uois_{k:04d}_depth.png")))
    color = np.asarray(Image.open(shared_path(f"rgbd/uois/uois_{k:04d}_color.png")))
    return depth, color, read_pcd(shared_path(f"scenes/uois_realsense/uois_image_{k:04d}.pcd"))


def test_the_realsense_recording_gives_the_pcds_frames_with_colour() -> None:
    log = shared_path("rgbd/uois_realsense_ros2.mcap")
    frames = list(iter_frames(log))
    assert len(frames) == 9
    for k, frame in enumerate(frames):
        want = read_pcd(shared_path(f"scenes/uois_realsense/uois_image_{k:04d}.pcd"))
        np.testing.assert_array_equal(frame.points, want.points)
        np.testing.assert_array_equal(frame.colors, want.colors)
        assert frame.shape == (480, 640) and frame.frame_id == "camera_color_optical_frame"
    assert read_frame(log, None, 4).stamp_s == frames[4].stamp_s


def test_float_metres_and_bgr_colour_from_a_written_log(tmp_path: Path) -> None:
    depth, color, want = _uois(3)
    metres = depth.astype(np.float32) / np.float32(1000)
    log = write_rgbd_mcap(
        tmp_path / "f.mcap",
        [
            {"depth": metres, "depth_encoding": "32FC1", "color": color[:, :, ::-1], "color_encoding": "bgr8"},
        ],
    )
    frame = read_frame(log)
    np.testing.assert_array_equal(frame.points, want.points)
    np.testing.assert_array_equal(frame.colors, want.colors)


def test_an_unregistered_colour_stream_is_left_out_not_painted_on(tmp_path: Path) -> None:
    depth, color, want = _uois(3)
    log = write_rgbd_mcap(
        tmp_path / "u.mcap",
        [
            {
                "depth": depth,
                "frame_id": "camera_depth_optical_frame",
                "color": color,
                "color_frame_id": "camera_color_optical_frame",
            },
        ],
    )
    frame = read_frame(log)
    assert frame.colors is None
    np.testing.assert_array_equal(frame.points, want.points)


@pytest.mark.parametrize(
    "case, words",
    [
        ("no_camera_info", "no camera info for the depth images"),
        ("colour_on_the_depth_topic", "encoding is 'rgb8', not depth"),
        ("damaged", "damaged image"),
        ("intrinsics_size", "are for 1280 x 720"),
    ],
)
def test_bad_image_logs_are_one_input_error(tmp_path: Path, case: str, words: str) -> None:
    depth, color, _ = _uois(3)
    frame: dict = {"depth": depth}
    if case == "colour_on_the_depth_topic":
        frame = {"depth": color, "depth_encoding": "rgb8"}
    if case == "damaged":
        from helpers.rgbd_logs import image_msg

        msg = image_msg(depth, "16UC1", 1_700_000_000_000_000_000, "camera_color_optical_frame")
        msg["data"] = msg["data"][: len(msg["data"]) // 2]  # the width halved in the data, not in the header
        frame["depth_msg"] = msg
    log = tmp_path / "bad.mcap"
    if case == "intrinsics_size":  # a camera info for another resolution
        _write_with_info_size(log, depth, 1280, 720)
    else:
        write_rgbd_mcap(log, [frame], info=case != "no_camera_info")
    with pytest.raises(InputError, match=words):
        read_frame(log)


def _write_with_info_size(path: Path, depth: np.ndarray, w: int, h: int) -> None:
    from helpers.rgbd_logs import CAMERA_INFO_MSGDEF, IMAGE_MSGDEF, image_msg, info_msg
    from mcap_ros2.writer import Writer

    t = 1_700_000_000_000_000_000
    with open(path, "wb") as fp:
        writer = Writer(fp)
        image = writer.register_msgdef("sensor_msgs/msg/Image", IMAGE_MSGDEF)
        camera = writer.register_msgdef("sensor_msgs/msg/CameraInfo", CAMERA_INFO_MSGDEF)
        writer.write_message("/cam/depth/camera_info", camera, info_msg(w, h, t, "f"), log_time=t, publish_time=t)
        writer.write_message(
            "/cam/depth/image_raw", image, image_msg(depth, "16UC1", t, "f"), log_time=t + 1, publish_time=t + 1
        )
        writer.finish()


def test_a_damaged_image_after_whole_frames_ends_the_log_with_exit_9(tmp_path: Path) -> None:
    from helpers.rgbd_logs import image_msg

    depth, _, _ = _uois(3)
    bad = image_msg(depth, "16UC1", 1_700_000_002_000_000_000, "camera_color_optical_frame")
    bad["data"] = bad["data"][:-640]
    log = write_rgbd_mcap(tmp_path / "p.mcap", [{"depth": depth}, {"depth": depth}, {"depth": depth, "depth_msg": bad}])
    got = []
    with pytest.raises(PartialLogError, match="2 complete frames"):
        for frame in iter_frames(log):
            got.append(frame)
    assert len(got) == 2


@pytest.mark.parametrize("kind", ["ros1", "rosbag2-sqlite3", "rosbag2-mcap"])
def test_bags_with_depth_and_colour_images_read_as_the_pcd(tmp_path: Path, kind: str) -> None:
    from helpers.rgbd_logs import write_rgbd_bag

    depth, color, want = _uois(3)
    path = tmp_path / ("b.bag" if kind == "ros1" else "b2")
    write_rgbd_bag(path, [depth, depth], [color, color], ros1=kind == "ros1", storage=kind.rsplit("-", 1)[-1])
    frames = list(iter_frames(path))
    assert len(frames) == 2
    for frame in frames + [read_frame(path, None, 1)]:
        np.testing.assert_array_equal(frame.points, want.points)
        np.testing.assert_array_equal(frame.colors, want.colors)


def test_a_realsense_sdk_recording_reads_depth_with_its_units_and_leaves_unregistered_colour_out(
    tmp_path: Path,
) -> None:
    from helpers.rgbd_logs import write_realsense_sdk_bag

    depth, color, want = _uois(3)
    # depth stored in units of 0.1 mm, as the sensor's Depth Units option records it
    log = write_realsense_sdk_bag(tmp_path / "rs.bag", [depth * 10], [color], depth_units=0.0001)
    frame = read_frame(log)
    np.testing.assert_allclose(frame.points, want.points, rtol=1e-6, atol=1e-7, equal_nan=True)
    assert frame.colors is None  # another sensor, no registration recorded for it: left out, not painted on


def test_foxglove_raw_images_with_a_calibration(tmp_path: Path) -> None:
    from helpers.rgbd_logs import write_foxglove_json_mcap

    depth, color, want = _uois(3)
    log = write_foxglove_json_mcap(tmp_path / "fox.mcap", depth.astype(np.float32) / np.float32(1000), color)
    frame = read_frame(log)
    np.testing.assert_array_equal(frame.points, want.points)
    np.testing.assert_array_equal(frame.colors, want.colors)


def test_ros1_messages_in_an_mcap_log(tmp_path: Path) -> None:
    from helpers.rgbd_logs import write_ros1_mcap

    depth, color, want = _uois(3)
    frame = read_frame(write_ros1_mcap(tmp_path / "r1.mcap", depth, color))
    np.testing.assert_array_equal(frame.points, want.points)
    np.testing.assert_array_equal(frame.colors, want.colors)


def test_compressed_depth_is_refused_by_name(tmp_path: Path) -> None:
    from mcap.writer import Writer

    log = tmp_path / "c.mcap"
    with open(log, "wb") as fp:
        writer = Writer(fp)
        writer.start(profile="", library="tests")
        schema = writer.register_schema("sensor_msgs/msg/CompressedImage", "jsonschema", b"{}")
        ch = writer.register_channel("/camera/depth/image_raw/compressedDepth", "json", schema)
        writer.add_message(ch, log_time=1, publish_time=1, data=b'{"format": "16UC1; compressedDepth png"}')
        writer.finish()
    with pytest.raises(InputError, match="compressed.*record the raw topic"):
        read_frame(log)


class _Topics:
    """A log summary holding only its topics (what `camera_info_topic` reads)."""

    def __init__(self, topics: dict[str, str]) -> None:
        self._topics = topics
        self.path = Path("log.mcap")

    def topics(self) -> list[tuple[str, str]]:
        return list(self._topics.items())


@pytest.mark.parametrize(
    ("depth_topic", "found"),
    [
        ("/camera/depth/image_raw", "/camera/depth/camera_info"),  # the sibling
        ("/camera/depth/sub/image", "/camera/depth/camera_info"),  # the one in the namespace above
        ('"camera/depth/image_raw', None),  # a damaged name (fuzz seed 60, case 1107): no leading "/"
        ("camera/depth/image_raw", None),  # nor any other name without one
        ("image_raw", None),  # no namespace at all
    ],
)
def test_camera_info_is_found_up_the_namespaces_and_the_search_ends(depth_topic: str, found: str | None) -> None:
    """The search goes up one namespace at a time and ends at the top, whatever the name:
    one without a leading "/" once looped for ever (`rsplit` gave the name back)."""
    from clearcli.io.mcap_images import camera_info_topic

    summary = _Topics({depth_topic: "sensor_msgs/msg/Image", "/camera/depth/camera_info": "sensor_msgs/msg/CameraInfo"})
    if found is None:
        with pytest.raises(InputError, match="no camera info"):
            camera_info_topic(summary, depth_topic)  # type: ignore[arg-type]  # a summary by the names it reads
    else:
        assert camera_info_topic(summary, depth_topic) == found  # type: ignore[arg-type]
