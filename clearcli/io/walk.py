"""Inputs as files: what a folder search takes, which inputs are logs, what a frame's
name is and which files a frame is read with, each as its format says
(clearcli/io/formats/). The task layer (clearcli/tasks/sources.py) makes a batch's
frames of these.

A folder is searched recursively, sorted by name (numbers in names by value), for the
files some format takes by name (`.pcd`, `.mcap`, `.bag`, depth images by the naming
rule); a folder a format holds whole (a rosbag2 bag) is one entry, hidden entries are
passed over, and only regular files and folders are taken.
"""

from __future__ import annotations

import errno
import re
import stat
from pathlib import Path
from typing import TYPE_CHECKING

from clearcli.io import formats
from clearcli.io.sniff import SNIFF_BYTES

if TYPE_CHECKING:
    from clearcli.settings.images import ImageSettings


def natural_key(path: Path) -> tuple[int | str, ...]:
    """learn2 before learn10: digit runs compare as numbers. (isdecimal: the runs \\d
    finds, which int() reads; isdigit also took a "²" between them, which int() refuses.)"""
    return tuple(int(t) if t.isdecimal() else t for t in re.split(r"(\d+)", path.name))


def special(path: Path) -> str | None:
    """Why ``path`` is neither a regular file nor a folder (a FIFO a recorder left, a
    socket, a device, a link loop), or None when it is one of those."""
    try:
        mode = path.stat().st_mode
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "a symbolic link loop"
        if path.is_symlink():
            return "a symbolic link to nothing"
        return None  # missing: reported as such by the caller
    if stat.S_ISREG(mode) or stat.S_ISDIR(mode):
        return None
    kind = {
        stat.S_ISFIFO: "a FIFO (named pipe)",
        stat.S_ISSOCK: "a socket",
        stat.S_ISCHR: "a character device",
        stat.S_ISBLK: "a block device",
    }
    return next((name for test, name in kind.items() if test(mode)), "not a regular file")


def is_input_folder(path: Path) -> bool:
    """A folder that is one input (a rosbag2 bag), not a folder of inputs."""
    return path.is_dir() and formats.folder_format(path) is not None


def files_in(
    folder: Path, seen: set[tuple[int, int]], skipped: list[tuple[str, str]], images: ImageSettings
) -> list[Path]:
    """Frame files below ``folder``, sorted; a folder a format holds whole (a rosbag2
    bag) is one entry, hidden entries (a batch's own temporaries, editors' backups) are
    passed over. Only regular files and folders are taken; each real folder is searched
    once (``seen``: its device and inode), so a link back up the tree is reported, not
    walked again. What is passed over is added to ``skipped`` as (path, why)."""
    found: list[Path] = []
    try:
        st = folder.stat()
    except OSError:
        return found
    if (st.st_dev, st.st_ino) in seen:
        skipped.append((str(folder), "a link to a folder already searched"))
        return found
    seen.add((st.st_dev, st.st_ino))
    for p in sorted(folder.iterdir(), key=natural_key):
        if p.name.startswith("."):
            continue
        why = special(p)
        if why is not None:
            skipped.append((str(p), why))
        elif p.is_dir():
            found.extend([p] if formats.folder_format(p) is not None else files_in(p, seen, skipped, images))
        elif any(fmt.searched(p, images) for fmt in formats.FORMATS):
            found.append(p)
    return found


def is_log(path: Path) -> bool:
    """A log (frames named with their index): told by content, as `formats.sniff` does,
    by its name when it cannot be read; never an error."""
    if path.is_dir():
        fmt = formats.folder_format(path)
        return fmt is None or fmt.is_log
    if any(fmt.is_log and path.name in fmt.file_names for fmt in formats.FORMATS):
        return True
    try:
        with open(path, "rb") as fp:
            head = fp.read(SNIFF_BYTES)
    except OSError:
        return any(fmt.is_log and path.suffix.lower() in fmt.suffixes for fmt in formats.FORMATS)
    fmt = formats.recognised(path, head) if head else None
    return fmt is not None and fmt.is_log


def output_name(path: Path, images: ImageSettings) -> str:
    """The base name of the outputs of a single frame's file: its stem, or the name its
    format gives it (a depth image's stem without the depth suffix)."""
    for fmt in formats.FORMATS:
        name = fmt.output_name(path, images)
        if name is not None:
            return name
    return path.stem


def frame_files(source: str | Path, images: ImageSettings, color: str | Path | None = None) -> tuple[Path, ...]:
    """The files a frame of ``source`` is read from: the file itself and those its format
    reads with it (a rosbag2 folder's files; a depth image's colour image, --color or the
    one the naming rule pairs, and its intrinsics file), or the colour image --color
    names. Files that do not exist are left out."""
    path = Path(source)
    found: list[Path] = [path]
    for fmt in formats.FORMATS:
        more = fmt.reads_with(path, images, Path(color) if color else None)
        if more is not None:
            found.extend(more)
            break
    else:
        if color:
            found.append(Path(color))
    return tuple(p for p in dict.fromkeys(found) if p.exists())


def taken_before(path: Path, taken: dict[tuple[int, int], str]) -> str | None:
    """The name under which the real file (or rosbag2 folder) ``path`` was taken
    before, else None, and ``path`` is taken now."""
    try:
        st = path.stat()
    except OSError:
        return None
    key = (st.st_dev, st.st_ino)
    if key in taken:
        return taken[key]
    taken[key] = str(path)
    return None
