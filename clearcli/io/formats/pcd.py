"""PCD files (clearcli/io/pcd.py): a header of keywords (or a comment) first."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from clearcli.io.formats.base import SingleFrame, describe_frame
from clearcli.io.sniff import looks_like_pcd

if TYPE_CHECKING:
    from clearcli.io.frames import Frame
    from clearcli.settings.images import ImageSettings


class Pcd(SingleFrame):
    name = "pcd"
    what = "a PCD file"
    suffixes = (".pcd",)

    def recognises(self, path: Path, head: bytes) -> bool:
        return looks_like_pcd(head)

    def misnamed(self, path: Path) -> str | None:
        if path.suffix.lower() == ".pcd":
            return f"{path}: not a PCD file (it does not start with a PCD header)"
        return None

    def read(self, path: Path, images: ImageSettings | None, color: Path | None) -> Frame:
        from clearcli.io.pcd import read_pcd  # noqa: PLC0415  (NumPy and io.pcd, ~95 ms: see formats/base.py)

        return read_pcd(path)

    def describe(
        self, path: Path, topic: str | None, index: int, images: ImageSettings | None, color: Path | None
    ) -> dict[str, Any]:
        from clearcli.io.pcd import pcd_header_fields  # noqa: PLC0415  (NumPy and io.pcd, ~95 ms: see formats/base.py)

        header = pcd_header_fields(path)
        frame = self.read_frame(path, topic, index, None, None)
        return {"file": str(path), "format": "pcd", "pcd": header, "frame": describe_frame(frame, index)}


FORMAT = Pcd()
