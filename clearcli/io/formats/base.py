"""What an input format is: `InputFormat`, the interface every format module offers (and
`clearcli/io/formats/__init__.py` registers), `BaseFormat` and `SingleFrame`, defaults
a format builds on, and `describe_frame`, the frame of every format's info payload.

A format module imports its reader inside the functions that use it: the registry
imports every format to tell a file apart (~15 ms, `python -X importtime -c "import
clearcli.io.formats"`), and `clear info scene.pcd` must not pay for the MCAP or rosbags
libraries, nor for clear's other readers. Those readers (io.mcap, io.rosbag, io.images,
io.pcd, io.messages) bring NumPy (~90 ms) and their own modules (io.mcap ~30 ms,
io.rosbag ~30 ms more, io.images ~10 ms, io.pcd ~6 ms, measured with NumPy loaded).
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from clearcli.errors import InputError

if TYPE_CHECKING:
    from clearcli.io.frames import Frame
    from clearcli.settings.images import ImageSettings


@runtime_checkable
class InputFormat(Protocol):
    """One input format: what it recognises, how its frames are read and described."""

    @property
    def name(self) -> str:
        """What `sniff` says it is ("pcd", "mcap", "rosbag1", "rosbag2", "image")."""
        ...

    @property
    def is_log(self) -> bool:
        """Whether it holds frames 0..N-1, named by their index (`_f<k>`): --every counts them."""
        ...

    @property
    def takes_color(self) -> bool:
        """Whether --color pairs a colour image with its frame."""
        ...

    @property
    def suffixes(self) -> tuple[str, ...]:
        """Its files' suffixes, lowercase (what a folder search takes by default; a log's
        tell an unreadable file for a log)."""
        ...

    @property
    def file_names(self) -> tuple[str, ...]:
        """Whole names its files go by (rosbag2: metadata.yaml)."""
        ...

    def recognises(self, path: Path, head: bytes) -> bool:
        """Whether the file ``path`` is one of this format's, from its first bytes
        (`clearcli.io.sniff.SNIFF_BYTES` of them, fewer in a short file; never empty)."""
        ...

    def holds_folder(self, path: Path) -> bool:
        """Whether the folder ``path`` is one input of this format (a rosbag2 bag), not a
        folder of inputs to search."""
        ...

    def searched(self, path: Path, images: ImageSettings) -> bool:
        """Whether a folder search takes the file ``path``, by its name."""
        ...

    def misnamed(self, path: Path) -> str | None:
        """The error for a file named as this format's files are that no format
        recognises (a truncated or renamed file), None to leave it to the general one."""
        ...

    def read_frame(
        self, path: Path, topic: str | None, index: int, images: ImageSettings | None, color: Path | None
    ) -> Frame:
        """Frame ``index`` (from 0); InputError for one that does not exist. ``topic``
        picks a log's frame topic; ``images`` ([images] settings) and ``color`` serve
        depth images."""
        ...

    def iter_frames(self, path: Path, topic: str | None, images: ImageSettings | None) -> Iterator[Frame]:
        """Every frame, one at a time (a log is streamed, never loaded whole)."""
        ...

    def describe(
        self, path: Path, topic: str | None, index: int, images: ImageSettings | None, color: Path | None
    ) -> dict[str, Any]:
        """The payload of `clear info` (schema documented in clearcli/commands/info.py):
        ``file``, ``format``, what the format knows and ``frame`` (`describe_frame`)."""
        ...

    def count_frames(self, path: Path, topic: str | None) -> tuple[int, Exception | None]:
        """Frames in the file, and the PartialLogError that ended a damaged log early."""
        ...

    def output_name(self, path: Path, images: ImageSettings) -> str | None:
        """The base name of a single frame's outputs when this format names it (a depth
        image: its stem without the depth suffix), None for the file's stem."""
        ...

    def reads_with(self, path: Path, images: ImageSettings, color: Path | None) -> list[Path] | None:
        """The other files a frame of ``path`` is read with (a rosbag2 folder's files, a
        depth image's colour and intrinsics) when ``path`` is named as this format's
        files are, None when it is not."""
        ...

    def transforms(self, path: Path, max_messages: int) -> dict[tuple[str, str], Any]:
        """T_parent_child (4x4) of the (parent, child) pairs on a log's /tf_static and
        /tf; {} for a format without them."""
        ...


class BaseFormat:
    """Defaults for what most formats do not have: no folder layout, found in folders by
    its suffixes, no colour, no companions, no transforms, no name of its own."""

    name: str
    is_log = False
    takes_color = False
    suffixes: tuple[str, ...] = ()
    file_names: tuple[str, ...] = ()

    def holds_folder(self, path: Path) -> bool:
        return False

    def searched(self, path: Path, images: ImageSettings) -> bool:
        return path.suffix.lower() in self.suffixes

    def misnamed(self, path: Path) -> str | None:
        return None

    def output_name(self, path: Path, images: ImageSettings) -> str | None:
        return None

    def reads_with(self, path: Path, images: ImageSettings, color: Path | None) -> list[Path] | None:
        return None

    def transforms(self, path: Path, max_messages: int) -> dict[tuple[str, str], Any]:
        return {}


class SingleFrame(BaseFormat):
    """A format whose file is one frame (a PCD, a depth image): ``read`` is the reader,
    the rest follows from it."""

    what: str  # "a PCD file": for the message about a --frame past 0

    def read(self, path: Path, images: ImageSettings | None, color: Path | None) -> Frame:
        raise NotImplementedError

    def read_frame(
        self, path: Path, topic: str | None, index: int, images: ImageSettings | None, color: Path | None
    ) -> Frame:
        if index != 0:
            raise InputError(f"{path}: --frame {index} does not exist: {self.what} holds 1 frame (0)")
        return self.read(path, images, color)

    def iter_frames(self, path: Path, topic: str | None, images: ImageSettings | None) -> Iterator[Frame]:
        yield self.read(path, images, None)

    def describe(
        self, path: Path, topic: str | None, index: int, images: ImageSettings | None, color: Path | None
    ) -> dict[str, Any]:
        frame = self.read_frame(path, topic, index, images, color)
        return {"file": str(path), "format": self.name, "frame": describe_frame(frame, index)}

    def count_frames(self, path: Path, topic: str | None) -> tuple[int, Exception | None]:
        return 1, None


def describe_frame(frame: Frame, index: int = 0) -> dict[str, Any]:
    """The `frame` object of the info schema."""
    import numpy as np  # noqa: PLC0415  (NumPy, ~90 ms: see the module)

    finite = frame.finite_mask
    n_finite = int(finite.sum())
    fields: list[dict[str, Any]] = [{"name": a, "dtype": str(frame.points.dtype), "count": 1} for a in "xyz"]
    if frame.colors is not None:
        fields.append({"name": "rgb", "dtype": "uint8", "count": 3})
    for name, values in frame.fields.items():
        values = np.asarray(values)
        fields.append({"name": name, "dtype": str(values.dtype), "count": int(np.prod(values.shape[1:], dtype=int))})
    bounds = None
    if n_finite:
        pts = frame.points[finite]
        bounds = {
            "min": [round(float(v), 6) for v in pts.min(axis=0)],
            "max": [round(float(v), 6) for v in pts.max(axis=0)],
        }
    return {
        "index": index,
        "points": frame.n_points,
        "organized": frame.is_organized,
        "shape": list(frame.shape) if frame.shape is not None else None,
        "finite_points": n_finite,
        "has_colors": frame.colors is not None,
        "fields": fields,
        "bounds_m": bounds,
        "stamp_s": float(frame.stamp_s),
        "frame_id": frame.frame_id,
    }
