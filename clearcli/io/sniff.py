"""What a file is told by: its first bytes (not its name), and the signatures of the
built-in formats (PCD, MCAP, ROS 1 bag, rosbag2's SQLite storage and metadata.yaml, the
depth images' PNG, TIFF and NPY).

The signatures live here, below every reader and every format (clearcli/io/formats/),
so that telling a PCD apart imports no log reader and the readers can share them without
importing each other. Which format a path is: `clearcli.io.formats.sniff`.
"""

from __future__ import annotations

import errno
import stat
from pathlib import Path
from typing import BinaryIO

from clearcli.errors import InputError

SNIFF_BYTES = 64  # what a format is told by
# File signatures.
MCAP_MAGIC = b"\x89MCAP0\r\n"
ROSBAG1_MAGIC = b"#ROSBAG"
SQLITE_MAGIC = b"SQLite format 3\x00"
ROSBAG2_METADATA = "metadata.yaml"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
TIFF_MAGICS = (b"II*\x00", b"MM\x00*")
NPY_MAGIC = b"\x93NUMPY"
# A PCD header opens with a comment or one of its keywords.
PCD_HEADER_KEYS = (
    b"VERSION",
    b"FIELDS",
    b"SIZE",
    b"TYPE",
    b"COUNT",
    b"WIDTH",
    b"HEIGHT",
    b"VIEWPOINT",
    b"POINTS",
    b"DATA",
)


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


def read_head(path: Path) -> bytes | None:
    """The first bytes of the regular file at ``path``, what a format is told by; None when
    it is a folder after all (it became one since it was looked at). InputError for what
    cannot be read: a FIFO, socket or device (reading would block, or never end), a link
    loop, a missing, unreadable or empty file."""
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
            head = fp.read(SNIFF_BYTES)
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except IsADirectoryError:
        return None
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror})") from None
    if not head:
        raise InputError(f"{path}: empty file (0 bytes); expected a PCD or MCAP file or a bag")
    return head
