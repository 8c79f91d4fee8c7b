"""MCAP logs (clearcli/io/mcap.py): the MCAP magic bytes first."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from clearcli.io.formats.base import BaseFormat
from clearcli.io.formats.logs import count_log_frames, describe_log
from clearcli.io.sniff import MCAP_MAGIC

if TYPE_CHECKING:
    from clearcli.io.frames import Frame
    from clearcli.settings.images import ImageSettings


class Mcap(BaseFormat):
    name = "mcap"
    is_log = True
    suffixes = (".mcap",)

    def recognises(self, path: Path, head: bytes) -> bool:
        return head.startswith(MCAP_MAGIC)

    def read_frame(
        self, path: Path, topic: str | None, index: int, images: ImageSettings | None, color: Path | None
    ) -> Frame:
        from clearcli.io.mcap import read_mcap_frame  # noqa: PLC0415  (NumPy and io.mcap, ~120 ms: see formats/base.py)

        return read_mcap_frame(path, topic, index, images)

    def iter_frames(self, path: Path, topic: str | None, images: ImageSettings | None) -> Iterator[Frame]:
        from clearcli.io.mcap import iter_mcap_frames  # noqa: PLC0415  (NumPy and io.mcap, ~120 ms: see formats/base.py)

        yield from iter_mcap_frames(path, topic, images)

    def describe(
        self, path: Path, topic: str | None, index: int, images: ImageSettings | None, color: Path | None
    ) -> dict[str, Any]:
        from clearcli.io.mcap import McapAccess, choose_topic, read_mcap_frame, read_summary  # noqa: PLC0415  (NumPy and io.mcap, ~120 ms: see formats/base.py)

        summary = read_summary(path)
        part = describe_log(
            path, summary, McapAccess(path, summary), choose_topic, read_mcap_frame, topic, index, images
        )
        return {"file": str(path), "format": "mcap", "mcap": part["log"], "frame": part["frame"]}

    def count_frames(self, path: Path, topic: str | None) -> tuple[int, Exception | None]:
        from clearcli.io.mcap import choose_topic, read_summary  # noqa: PLC0415  (NumPy and io.mcap, ~120 ms: see formats/base.py)

        return count_log_frames(read_summary(path), topic, choose_topic, lambda: self.iter_frames(path, topic, None))

    def transforms(self, path: Path, max_messages: int) -> dict[tuple[str, str], Any]:
        from clearcli.io.mcap import read_mcap_transforms  # noqa: PLC0415  (NumPy and io.mcap, ~120 ms: see formats/base.py)

        return read_mcap_transforms(path, max_messages)


FORMAT = Mcap()
