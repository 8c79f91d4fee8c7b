"""One way in: a path (PCD, MCAP, a bag or a depth image, told apart by content) -> frames.

PCD and MCAP files and ROS 1 bags (`#ROSBAG`) are told apart by their first bytes, not
their names; a folder holding `metadata.yaml` (or that file itself, or a `.db3` SQLite
file) is a rosbag2 bag. Logs and bags are streamed, never loaded whole.

Every frame-reading subcommand calls `read_frame(path, topic, index)`; `iter_frames` walks
a whole file. Only ClearError subclasses leave these functions for anything a file can
hold: InputError (exit 3) for unreadable input, PartialLogError (exit 9) when a log breaks
after complete frames.

Reading a frame whose points are all NaN is not an error (``clear info`` reports it); a
stage that needs points calls `require_finite(frame)`, which raises SceneError (exit 4).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Iterator

from clearcli.errors import InputError, SceneError
from clearcli.io.frames import Frame
from clearcli.io.sniff import sniff

if TYPE_CHECKING:
    from clearcli.settings.images import ImageSettings


def read_frame(
    path: Path,
    topic: str | None = None,
    index: int = 0,
    images: "ImageSettings | None" = None,
    color: Path | None = None,
) -> Frame:
    """Frame `index` (from 0) of the file at `path`; a PCD or a depth image holds exactly
    one frame.

    `topic` picks the point-cloud topic of a log or bag holding several; ignored for PCD.
    `images` ([images] settings) and `color` (its colour image) serve depth images.
    """
    path = Path(path)
    kind = sniff(path)
    if color is not None and kind != "image":
        raise InputError(f"--color {color}: only a depth image takes a colour image; {path} is a {kind} file")
    if kind == "image":
        if index != 0:
            raise InputError(f"{path}: --frame {index} does not exist: a depth image holds 1 frame (0)")
        from clearcli.io.images import read_image_frame

        return read_image_frame(path, images, color)
    if kind == "pcd":
        if index != 0:
            raise InputError(f"{path}: --frame {index} does not exist: a PCD file holds 1 frame (0)")
        from clearcli.io.pcd import read_pcd

        return read_pcd(path)
    if kind in ("rosbag1", "rosbag2"):
        from clearcli.io.rosbag import read_bag_frame

        return read_bag_frame(path, topic, index, images)
    from clearcli.io.mcap import read_mcap_frame

    return read_mcap_frame(path, topic, index, images)


def iter_frames(path: Path, topic: str | None = None, images: "ImageSettings | None" = None) -> Iterator[Frame]:
    """Every frame of the file, one at a time (a log or bag is streamed, never loaded whole)."""
    path = Path(path)
    kind = sniff(path)
    if kind == "image":
        from clearcli.io.images import read_image_frame

        yield read_image_frame(path, images)
        return
    if kind == "pcd":
        from clearcli.io.pcd import read_pcd

        yield read_pcd(path)
        return
    if kind in ("rosbag1", "rosbag2"):
        from clearcli.io.rosbag import iter_bag_frames

        yield from iter_bag_frames(path, topic, images)
        return
    from clearcli.io.mcap import iter_mcap_frames

    yield from iter_mcap_frames(path, topic, images)


def require_finite(frame: Frame, min_points: int = 1) -> Frame:
    """The frame itself when it holds at least `min_points` finite points; else SceneError.

    For stages that need geometry; reading and `clear info` accept all-NaN frames.
    """
    n_finite = int(frame.finite_mask.sum()) if frame.n_points else 0
    if n_finite < min_points:
        where = frame.source or "the frame"
        raise SceneError(
            f"{where}: only {n_finite} finite points of {frame.n_points} (need {min_points}); "
            "every pixel is invalid (NaN), so there is no scene to work on"
            if n_finite == 0
            else f"{where}: only {n_finite} finite points of {frame.n_points} (need {min_points})"
        )
    return frame
