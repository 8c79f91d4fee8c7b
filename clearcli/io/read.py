"""One way in: a path (PCD or MCAP) -> frames."""

from __future__ import annotations

from pathlib import Path
from typing import Iterator

from clearcli.errors import InputError
from clearcli.io.frames import Frame


def read_frame(path: Path, topic: str | None = None, index: int = 0) -> Frame:
    """Frame ``index`` of the file at ``path`` (a PCD holds exactly one)."""
    path = Path(path)
    if path.suffix.lower() == ".pcd":
        if index != 0:
            raise InputError(f"{path}: a PCD file holds one frame; --frame {index} does not exist")
        from clearcli.io.pcd import read_pcd

        return read_pcd(path)
    raise InputError(f"{path}: unsupported file type (expected .pcd or .mcap)")


def iter_frames(path: Path, topic: str | None = None) -> Iterator[Frame]:
    yield read_frame(path, topic)
