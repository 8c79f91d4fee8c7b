"""What a file is, told by its first bytes, not its name: PCD, MCAP, a ROS 1 bag, or a
rosbag2 bag (a folder holding `metadata.yaml`, that file itself, or a `.db3` file).

The signatures live here, below every reader, so that telling a PCD apart imports no log
reader and the readers can share them without importing each other.
"""

from __future__ import annotations

import errno
import stat
from pathlib import Path
from typing import BinaryIO, Literal

from clearcli.errors import InputError

_SNIFF_BYTES = 64
# File signatures.
MCAP_MAGIC = b"\x89MCAP0\r\n"
ROSBAG1_MAGIC = b"#ROSBAG"
SQLITE_MAGIC = b"SQLite format 3\x00"
ROSBAG2_METADATA = "metadata.yaml"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
TIFF_MAGICS = (b"II*\x00", b"MM\x00*")
NPY_MAGIC = b"\x93NUMPY"
# A PCD header opens with a comment or one of its keywords.
PCD_HEADER_KEYS = (b"VERSION", b"FIELDS", b"SIZE", b"TYPE", b"COUNT", b"WIDTH", b"HEIGHT", b"VIEWPOINT", b"POINTS", b"DATA")
FileKind = Literal["pcd", "mcap", "rosbag1", "rosbag2", "image"]


def looks_like_pcd(head: bytes) -> bool:
    """Whether a file's first bytes open a PCD header: a comment or a header keyword."""
    stripped = head.lstrip()
    if stripped.startswith(b"#ROSBAG"):  # a ROS 1 bag also opens with "#"
        return False
    return stripped.startswith(b"#") or any(stripped.startswith(k) for k in PCD_HEADER_KEYS)


def open_input(path: Path, what: str) -> BinaryIO:
    """``path`` opened for reading, or one InputError saying why not; ``what`` names the
    kind of file expected ("an MCAP file", "a PCD file", "a ROS 1 bag")."""
    try:
        return open(path, "rb")
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a directory, not {what}") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror})") from None


def _directory_kind(path: Path) -> FileKind:
    if (path / ROSBAG2_METADATA).is_file():
        return "rosbag2"
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


def sniff(path: Path) -> FileKind:
    """"pcd", "mcap", "rosbag1" (a ROS 1 bag), "image" (PNG, TIFF, NPY: a depth image) from
    the file's first bytes (not its name), or "rosbag2" for a rosbag2 folder, its
    metadata.yaml or a .db3 file; InputError otherwise."""
    path = Path(path)
    if path.is_dir():
        return _directory_kind(path)
    try:
        mode = path.stat().st_mode
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise InputError(f"{path}: a symbolic link loop; not a file") from None
        mode = None  # missing: said below, when opening
    if mode is not None and not stat.S_ISREG(mode):
        # a FIFO or a device would block the read, or never end it
        raise InputError(f"{path}: not a regular file (a FIFO, socket or device); expected a PCD, MCAP or bag file")
    try:
        with open(path, "rb") as fp:
            head = fp.read(_SNIFF_BYTES)
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except IsADirectoryError:
        return _directory_kind(path)
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror})") from None
    if not head:
        raise InputError(f"{path}: empty file (0 bytes); expected a PCD or MCAP file or a bag")
    if head.startswith(MCAP_MAGIC):
        return "mcap"
    if head.startswith(ROSBAG1_MAGIC):
        return "rosbag1"
    if head.startswith(SQLITE_MAGIC) or (
        path.name == ROSBAG2_METADATA and head.lstrip().startswith(b"rosbag2_bagfile_information")
    ):
        return "rosbag2"
    if head.startswith(PNG_MAGIC) or head.startswith(TIFF_MAGICS) or head.startswith(NPY_MAGIC):
        return "image"  # a depth image (clearcli/io/images.py)
    if looks_like_pcd(head):
        return "pcd"
    if path.suffix.lower() == ".pcd":
        raise InputError(f"{path}: not a PCD file (it does not start with a PCD header)")
    if path.suffix.lower() in (".png", ".tif", ".tiff", ".npy"):
        raise InputError(f"{path}: not a {path.suffix[1:].upper()} file (unrecognised first bytes); is it truncated or renamed?")
    raise InputError(
        f"{path}: not an MCAP file, a ROS bag, a PCD file or a depth image (unrecognised first bytes)"
    )
