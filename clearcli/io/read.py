"""One way in: a path (PCD, MCAP, a bag or a depth image, told apart by content) -> frames.

PCD and MCAP files and ROS 1 bags (`#ROSBAG`) are told apart by their first bytes, not
their names; a folder holding `metadata.yaml` (or that file itself, or a `.db3` SQLite
file) is a rosbag2 bag. Each format reads its own frames (clearcli/io/formats/: what it
recognises, how it reads them). Logs and bags are streamed, never loaded whole.

Every frame-reading subcommand calls `read_frame(path, topic, index)`; `iter_frames` walks
a whole file. Only ClearError subclasses leave these functions for anything a file can
hold: InputError (exit 3) for unreadable input, PartialLogError (exit 9) when a log breaks
after complete frames.

Reading a frame whose points are all NaN is not an error (``clear info`` reports it); a
stage that needs points calls `require_finite(frame)`, which raises SceneError (exit 4).
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from clearcli.errors import SceneError
from clearcli.io.formats import check_color, format_of, sniff
from clearcli.io.frames import Frame

if TYPE_CHECKING:
    from clearcli.settings.images import ImageSettings

__all__ = ["iter_frames", "read_frame", "require_finite", "sniff"]


def read_frame(
    path: Path,
    topic: str | None = None,
    index: int = 0,
    images: ImageSettings | None = None,
    color: Path | None = None,
) -> Frame:
    """Frame `index` (from 0) of the file at `path`; a PCD or a depth image holds exactly
    one frame.

    `topic` picks the point-cloud topic of a log or bag holding several; ignored for PCD.
    `images` ([images] settings) and `color` (its colour image) serve depth images.
    """
    path = Path(path)
    fmt = format_of(path)
    check_color(fmt, path, color)
    return fmt.read_frame(path, topic, index, images, color)


def iter_frames(path: Path, topic: str | None = None, images: ImageSettings | None = None) -> Iterator[Frame]:
    """Every frame of the file, one at a time (a log or bag is streamed, never loaded whole)."""
    path = Path(path)
    yield from format_of(path).iter_frames(path, topic, images)


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
