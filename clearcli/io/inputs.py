"""The inputs of a run as files: how many frames a log holds, every file a run reads
(which no output may name), and what a log says of itself before its frames are read.

What a file is and how it is read is each input format's to say (clearcli/io/formats/);
what a folder search takes and what a frame is named, clearcli/io/walk.py. The task
layer (clearcli/tasks/sources.py: a batch's frames, clearcli/tasks/replay.py: a replayed
log) asks this module about files and makes its own items of the answers.

Telling files apart loads no reader (tests/io/test_io_layout.py): this module imports
the registry and the folder rules only; a log's summary is read by its format's reader,
imported when a replay asks for it.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from clearcli.errors import PartialLogError
from clearcli.io import formats
from clearcli.io.formats import mcap as mcap_format
from clearcli.io.formats import rosbag as rosbag_formats
from clearcli.io.formats.base import InputFormat
from clearcli.io.walk import frame_files
from clearcli.settings.images import ImageSettings

if TYPE_CHECKING:
    from clearcli.settings import Settings


def count_frames(path: Path, topic: str | None) -> tuple[int, PartialLogError | None]:
    """Point-cloud frames in a log, and the PartialLogError that ended it early, if any.
    An intact log or bag is counted from its summary (index); a damaged one is read
    through to its break (its format's `count_frames`)."""
    n, broken = formats.format_of(Path(path)).count_frames(Path(path), topic)
    assert broken is None or isinstance(broken, PartialLogError)  # what `InputFormat.count_frames` gives
    return n, broken


def files_read(
    source: str | Path,
    settings: Settings | None = None,
    color: str | Path | None = None,
    also: Sequence[str | Path | None] = (),
) -> tuple[Path, ...]:
    """Every file a run on ``source`` reads, so that no output may name one (even with
    --force): the frame's file (a rosbag2 folder's files), the colour image --color or
    the naming rule pairs with a depth image, the intrinsics file ([images] intrinsics,
    or the ones found beside the image), the robot's URDF ([robot] urdf) and the meshes
    it names, and ``also`` (the --settings file, a groups file). Files that do not
    exist are left out: they cannot be overwritten, and their absence is another error."""
    images = settings.images if settings is not None else ImageSettings()
    return frame_files(source, images, color) + run_files(settings, also)


def run_files(settings: Settings | None = None, also: Sequence[str | Path | None] = ()) -> tuple[Path, ...]:
    """The files a run reads whatever its frames: the robot's URDF ([robot] urdf) and
    the meshes it names, and ``also`` (the --settings file, a groups file)."""
    found: list[Path] = []
    urdf = settings.robot.urdf if settings is not None else ""
    if urdf:
        found.extend(urdf_files(Path(urdf)))
    found.extend(Path(p) for p in also if p)
    return tuple(p for p in dict.fromkeys(found) if p.exists())


def urdf_files(urdf: Path) -> list[Path]:
    """A URDF and the mesh files it names by a path (relative to it, absolute or
    file://; package:// needs a ROS workspace and is not followed)."""
    try:
        text = urdf.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return [urdf]
    meshes = []
    for name in re.findall(r'filename\s*=\s*["\']([^"\']+)["\']', text):
        if name.startswith("package://"):
            continue
        name = name[len("file://") :] if name.startswith("file://") else name
        meshes.append(urdf.parent / name)
    return [urdf, *meshes]


# --- a log before its frames: what a replay learns of it -----------------------------


@dataclass(frozen=True)
class LogIndex:
    """What an input says of itself before its frames are read, as a replay uses it."""

    topic: str | None  # the frame topic: the one its summary's rules choose, else as given
    start_s: float | None  # when the log starts (None: at its first frame)
    total: int | None  # frames on the topic by its summary (None: none counted, or unknown)
    transforms: bool  # whether its /tf_static and /tf may place the robot
    copied: bool  # whether an annotated log copies its frames' messages (else: JSON clouds)


def log_index(path: Path, topic: str | None) -> LogIndex:
    """What the input at ``path`` says before its frames are read; InputError for a file
    no format recognises. An MCAP log: its chosen frame topic, start time and frame
    count from its summary, its transforms, its messages copied into an annotated log
    (an MCAP too). A ROS bag: its frame count from its summary; the topic stays as
    given, the first frame starts it, its transforms are not looked at and an annotated
    log writes its frames as JSON point clouds. A one-frame file: one frame."""
    fmt = formats.format_of(Path(path))
    indexed = _INDEXED.get(fmt)
    if indexed is None:
        return LogIndex(topic, None, 1, transforms=False, copied=False)
    return indexed(Path(path), topic)


def _mcap_index(path: Path, topic: str | None) -> LogIndex:
    # the MCAP reader, ~110 ms: listing a batch's inputs (tasks/sources.py imports this
    # module) loads no reader (tests/io/test_io_layout.py)
    from clearcli.io.mcap import choose_topic, read_summary  # noqa: PLC0415

    summary = read_summary(path)
    chosen = choose_topic(summary, topic)
    start_s = summary.start_ns / 1e9 if summary.start_ns is not None else None
    return LogIndex(chosen, start_s, summary.count(chosen) or None, transforms=True, copied=True)


def _bag_index(path: Path, topic: str | None) -> LogIndex:
    # the bag reader, ~90 ms: as for the MCAP one above
    from clearcli.io.rosbag import choose_bag_topic, read_bag_summary  # noqa: PLC0415

    bag = read_bag_summary(path)
    return LogIndex(topic, None, bag.count(choose_bag_topic(bag, topic)) or None, transforms=False, copied=False)


# The formats whose summary a replay reads first (the others hold one frame).
_INDEXED: dict[InputFormat, Callable[[Path, str | None], LogIndex]] = {
    mcap_format.FORMAT: _mcap_index,
    rosbag_formats.ROS1: _bag_index,
    rosbag_formats.ROS2: _bag_index,
}
