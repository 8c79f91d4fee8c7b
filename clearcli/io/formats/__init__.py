"""The input formats: one module each (what it recognises, how it reads and describes
its frames: `base.InputFormat`), registered in `FORMATS`. Everything that asks what a
file is goes through here: `io.read` (read a frame, iterate frames), `io.describe`
(`clear info`), `io.walk` (a folder search, a batch's frames), `io.tf` (a log's
transforms).

A new format is a module here and its line in `FORMATS`; nothing else changes.
A file is told apart by its first bytes, never its name: the formats are asked in the
order of `FORMATS`, the first that recognises it reads it.
"""

from __future__ import annotations

from pathlib import Path

from clearcli.errors import InputError
from clearcli.io.formats import image, mcap, pcd, rosbag
from clearcli.io.formats.base import InputFormat
from clearcli.io.sniff import ROSBAG2_METADATA, read_head

FORMATS: list[InputFormat] = [
    mcap.FORMAT,
    rosbag.ROS1,
    rosbag.ROS2,
    image.FORMAT,
    pcd.FORMAT,
]


def recognised(path: Path, head: bytes) -> InputFormat | None:
    """The first format that recognises the file ``path`` by its first bytes ``head``."""
    return next((fmt for fmt in FORMATS if fmt.recognises(path, head)), None)


def folder_format(path: Path) -> InputFormat | None:
    """The format whose one input the folder ``path`` is (a rosbag2 bag), None for a
    folder of inputs."""
    return next((fmt for fmt in FORMATS if fmt.holds_folder(path)), None)


def format_of(path: Path) -> InputFormat:
    """The format of the file or folder at ``path``, from its first bytes (not its name);
    InputError when none recognises it, or it cannot be read."""
    path = Path(path)
    if path.is_dir():
        return _folder(path)
    head = read_head(path)
    if head is None:  # a folder after all
        return _folder(path)
    fmt = recognised(path, head)
    if fmt is not None:
        return fmt
    for fmt in FORMATS:
        message = fmt.misnamed(path)
        if message is not None:
            raise InputError(message)
    raise InputError(f"{path}: not an MCAP file, a ROS bag, a PCD file or a depth image (unrecognised first bytes)")


def sniff(path: Path) -> str:
    """What the file (or folder) at ``path`` is: its format's name ("pcd", "mcap",
    "rosbag1", "rosbag2", "image": a depth image); InputError otherwise."""
    return format_of(path).name


def check_color(fmt: InputFormat, path: Path, color: Path | None) -> None:
    """InputError for a colour image given with a file whose format takes none."""
    if color is not None and not fmt.takes_color:
        raise InputError(f"--color {color}: only a depth image takes a colour image; {path} is a {fmt.name} file")


def _folder(path: Path) -> InputFormat:
    fmt = folder_format(path)
    if fmt is not None:
        return fmt
    try:
        storage = sorted(p.name for p in path.iterdir() if p.suffix in (".db3", ".mcap"))
    except OSError:
        storage = []
    hint = (
        f"; it holds {', '.join(storage[:3])}{' ...' if len(storage) > 3 else ''}: pass that file instead"
        if storage
        else ""
    )
    raise InputError(
        f"{path}: is a directory without {ROSBAG2_METADATA} (not a rosbag2 bag); "
        f"expected a .pcd, .mcap or .bag file or a rosbag2 folder{hint}"
    )
