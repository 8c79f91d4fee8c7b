"""ROS bags (clearcli/io/rosbag.py): ROS 1 bags (`#ROSBAG` first) and rosbag2 bags (a
folder holding metadata.yaml, that file itself, or its SQLite `.db3` storage file); one
reader, two formats."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from clearcli.io.formats.base import BaseFormat
from clearcli.io.formats.logs import count_log_frames, describe_log
from clearcli.io.sniff import ROSBAG1_MAGIC, ROSBAG2_METADATA, SQLITE_MAGIC

if TYPE_CHECKING:
    from clearcli.io.frames import Frame
    from clearcli.settings.images import ImageSettings


class _Bag(BaseFormat):
    is_log = True

    def read_frame(
        self, path: Path, topic: str | None, index: int, images: ImageSettings | None, color: Path | None
    ) -> Frame:
        from clearcli.io.rosbag import read_bag_frame  # noqa: PLC0415  (NumPy, io.mcap and io.rosbag, ~150 ms: see formats/base.py)

        return read_bag_frame(path, topic, index, images)

    def iter_frames(self, path: Path, topic: str | None, images: ImageSettings | None) -> Iterator[Frame]:
        from clearcli.io.rosbag import iter_bag_frames  # noqa: PLC0415  (NumPy, io.mcap and io.rosbag, ~150 ms: see formats/base.py)

        yield from iter_bag_frames(path, topic, images)

    def describe(
        self, path: Path, topic: str | None, index: int, images: ImageSettings | None, color: Path | None
    ) -> dict[str, Any]:
        from clearcli.io.bag_messages import BagDecoders  # noqa: PLC0415  (NumPy, io.mcap and io.rosbag, ~150 ms: see formats/base.py)
        from clearcli.io.rosbag import BagAccess, choose_bag_topic, read_bag_frame, read_bag_summary  # noqa: PLC0415  (NumPy, io.mcap and io.rosbag, ~150 ms: see formats/base.py)

        summary = read_bag_summary(path)
        access = BagAccess(summary, BagDecoders(ros1=summary.format == "rosbag1"))
        part = describe_log(path, summary, access, choose_bag_topic, read_bag_frame, topic, index, images)
        part["log"]["storage"] = summary.storage
        return {"file": str(path), "format": self.name, "bag": part["log"], "frame": part["frame"]}

    def count_frames(self, path: Path, topic: str | None) -> tuple[int, Exception | None]:
        from clearcli.io.rosbag import choose_bag_topic, read_bag_summary  # noqa: PLC0415  (NumPy, io.mcap and io.rosbag, ~150 ms: see formats/base.py)

        return count_log_frames(
            read_bag_summary(path), topic, choose_bag_topic, lambda: self.iter_frames(path, topic, None)
        )

    def transforms(self, path: Path, max_messages: int) -> dict[tuple[str, str], Any]:
        from clearcli.io.rosbag import read_bag_transforms  # noqa: PLC0415  (NumPy, io.mcap and io.rosbag, ~150 ms: see formats/base.py)

        return read_bag_transforms(path, max_messages)


class Ros1Bag(_Bag):
    name = "rosbag1"
    suffixes = (".bag",)

    def recognises(self, path: Path, head: bytes) -> bool:
        return head.startswith(ROSBAG1_MAGIC)


class Rosbag2(_Bag):
    name = "rosbag2"
    suffixes = (".db3",)
    file_names = (ROSBAG2_METADATA,)

    def recognises(self, path: Path, head: bytes) -> bool:
        return head.startswith(SQLITE_MAGIC) or (
            path.name == ROSBAG2_METADATA and head.lstrip().startswith(b"rosbag2_bagfile_information")
        )

    def holds_folder(self, path: Path) -> bool:
        return (path / ROSBAG2_METADATA).is_file()

    def searched(self, path: Path, images: ImageSettings) -> bool:
        return False  # its storage files are found as its folder

    def reads_with(self, path: Path, images: ImageSettings, color: Path | None) -> list[Path] | None:
        if not (path.is_dir() and self.holds_folder(path)):
            return None
        return [p for p in path.iterdir() if p.is_file()]


ROS1 = Ros1Bag()
ROS2 = Rosbag2()
