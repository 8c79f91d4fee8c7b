"""Tests of telling a file apart (clearcli/io/sniff.py, clearcli/io/formats/)."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers import shared_path
from helpers.io import _one_line_error, _same

from clearcli.io.pcd import read_pcd
from clearcli.io.read import iter_frames, read_frame


def test_ros1_bag_is_read_not_rejected() -> None:
    # ROS 1 bags are read by clearcli.io.rosbag (tests/io/test_rosbag.py has the details).
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


def test_a_fifo_or_a_link_loop_is_refused_not_read(tmp_path: Path) -> None:
    import os

    from clearcli.errors import InputError
    from clearcli.io.read import sniff

    os.mkfifo(tmp_path / "pipe.pcd")
    with pytest.raises(InputError, match="not a regular file"):
        sniff(tmp_path / "pipe.pcd")  # would block for ever if opened
    (tmp_path / "loop.pcd").symlink_to("loop.pcd")
    with pytest.raises(InputError, match="symbolic link loop"):
        sniff(tmp_path / "loop.pcd")
