"""From the inputs a user names (files and folders) to the frames a batch works on.

A folder is searched (recursively, sorted by name, numbers in names by value) for
`.pcd`, `.mcap` and `.bag` files and depth images named by the naming rule
(`<stem>_depth.png|.tif|.tiff|.npy`; the suffix is [images] depth_suffix): a colour image
`<stem>_color.png` is never taken for a frame, it goes with its depth image. A folder
holding `metadata.yaml` is one rosbag2 bag. A log contributes frame 0, or
``--frame N``, or every N-th frame with ``--every N``. Each frame gets the name its
outputs carry in ``--out-dir``: the input's stem (a depth image's without the depth
suffix: `uois_0003_depth.png` -> `uois_0003`), plus ``_f<index>`` for a log.

What a file is, what a folder search takes and what a frame is read with is each
input format's to say (clearcli/io/walk.py, clearcli/io/formats/); this module makes the
batch's items of them.

What cannot be expanded (a missing file, a folder with no frames, a log that cannot be
read) becomes a `BadInput`: the batch reports it in its own line and goes on.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from clearcli.io.walk import natural_key

if TYPE_CHECKING:
    from clearcli.settings.images import ImageSettings

__all__ = [
    "BadInput",
    "FrameRef",
    "Item",
    "Skipped",
    "check_intrinsics",
    "check_unique_names",
    "count_frames",
    "expand",
    "files_read",
    "natural_key",
    "run_files",
]


@dataclass(frozen=True)
class FrameRef:
    """One frame of one input."""

    source: str  # the file (or rosbag2 folder)
    index: int  # frame index within it (0 for a PCD)
    is_log: bool  # a log (MCAP, bag): names carry the frame index
    name: str  # base name of its outputs in --out-dir


@dataclass(frozen=True)
class BadInput:
    """An input that yields no frame, with the error a single call would give."""

    source: str
    message: str
    exit_code: int
    index: int = 0
    name: str = ""


@dataclass(frozen=True)
class Skipped:
    """An entry of a searched folder that is no frame and was not read (a FIFO, a
    socket, a device, a link loop, a folder reached twice): reported, not a failure."""

    source: str
    reason: str


Item = FrameRef | BadInput | Skipped


def count_frames(path: Path, topic: str | None) -> tuple[int, Exception | None]:
    """Point-cloud frames in a log, and the PartialLogError that ended it early, if any.
    An intact log or bag is counted from its summary (index); a damaged one is read
    through to its break (its format's `count_frames`)."""
    from clearcli.io.formats import format_of

    return format_of(Path(path)).count_frames(Path(path), topic)


def expand(
    inputs: Sequence[Path],
    *,
    frame: int | None = None,
    every: int | None = None,
    topic: str | None = None,
    images: ImageSettings | None = None,
) -> list[Item]:
    """The frames of ``inputs`` in order (folders expanded), and the inputs that fail.
    ``images``: the naming rule of depth images ([images]; defaults when None)."""
    from clearcli.errors import EXIT_INPUT, ClearError
    from clearcli.io.images import or_defaults
    from clearcli.io.walk import files_in, is_input_folder, is_log, output_name, special, taken_before

    images = or_defaults(images)

    items: list[Item] = []
    # Real folders searched and real files taken, over all the inputs: a folder reached
    # again (a link back to itself, or named twice through links) is searched once, and
    # a file a folder search reaches again is one frame, not two lines whose outputs
    # would clash. A file named twice on the command line is done twice: asked for.
    seen: set[tuple[int, int]] = set()
    taken: dict[tuple[int, int], str] = {}
    for raw in inputs:
        path = Path(raw)
        why = special(path)
        if why is not None:
            items.append(Skipped(str(path), why))
            continue
        if path.is_dir() and not is_input_folder(path):
            skipped: list[tuple[str, str]] = []
            files = files_in(path, seen, skipped, images)
            items.extend(Skipped(source, reason) for source, reason in skipped)
            if not files and not skipped:
                items.append(
                    BadInput(
                        str(path),
                        f"{path}: folder holds no .pcd, .mcap or .bag file and no depth image named "
                        f"<stem>{images.depth_suffix}.png (.tif, .npy)",
                        EXIT_INPUT,
                    )
                )
            paths = files
        elif not path.exists():
            items.append(BadInput(str(path), f"{path}: file not found", EXIT_INPUT))
            continue
        else:
            paths = [path]
        searched = path.is_dir() and not is_input_folder(path)
        for p in paths:
            again = taken_before(p, taken)
            if again is not None and searched:
                items.append(Skipped(str(p), f"the same file as {again}, reached again"))
                continue
            stem = p.name if p.is_dir() else p.stem
            if not is_log(p):
                items.append(FrameRef(str(p), 0, False, output_name(p, images)))
                continue
            if every is None:
                k = frame or 0
                items.append(FrameRef(str(p), k, True, f"{stem}_f{k}"))
                continue
            try:
                n, broken = count_frames(p, topic)
            except ClearError as exc:
                items.append(BadInput(str(p), str(exc), exc.exit_code))
                continue
            start = frame or 0
            if start >= n and broken is None:
                # a selection that selects nothing is a mistake, not an empty result
                items.append(
                    BadInput(
                        str(p),
                        f"{p}: --frame {start} with --every {every} selects no frame: the log has {n} "
                        f"frame(s) on its point-cloud topic (0-{n - 1})"
                        if n
                        else f"{p}: the log has no point-cloud frame",
                        EXIT_INPUT,
                        start,
                        f"{stem}_f{start}",
                    )
                )
                continue
            items.extend(FrameRef(str(p), k, True, f"{stem}_f{k}") for k in range(start, n, every))
            if broken is not None:  # every complete frame is in; the break is reported
                items.append(BadInput(str(p), str(broken), broken.exit_code, n, f"{stem}_f{n}"))  # type: ignore[attr-defined]
    return items


def check_intrinsics(spec: str) -> None:
    """Read the intrinsics ``spec`` (a file or "fx fy cx cy") once, before any frame: a bad
    one is one InputError (exit 3), not one per frame."""
    from clearcli.io.intrinsics import read_intrinsics

    read_intrinsics(spec)


def check_unique_names(items: Sequence[Item]) -> None:
    """Two frames whose outputs would share a name: a usage error before any work."""
    from clearcli.errors import InputError

    seen: dict[str, str] = {}
    for it in items:
        if isinstance(it, FrameRef):
            other = seen.get(it.name)
            if other is not None and other != it.source:
                raise InputError(
                    f"{it.source} and {other} would both write outputs named {it.name!r} in --out-dir; "
                    "run them in separate batches or rename one"
                )
            seen[it.name] = it.source


def files_read(
    source: str | Path,
    settings: Any = None,
    color: str | Path | None = None,
    also: Sequence[str | Path | None] = (),
) -> tuple[Path, ...]:
    """Every file a run on ``source`` reads, so that no output may name one (even with
    --force): the frame's file (a rosbag2 folder's files), the colour image --color or
    the naming rule pairs with a depth image, the intrinsics file ([images] intrinsics,
    or the ones found beside the image), the robot's URDF ([robot] urdf) and the meshes
    it names, and ``also`` (the --settings file, a groups file). Files that do not
    exist are left out: they cannot be overwritten, and their absence is another error."""
    from clearcli.io.images import or_defaults
    from clearcli.io.walk import frame_files

    images = or_defaults(getattr(settings, "images", None))
    return frame_files(source, images, color) + run_files(settings, also)


def run_files(settings: Any = None, also: Sequence[str | Path | None] = ()) -> tuple[Path, ...]:
    """The files a run reads whatever its frames: the robot's URDF ([robot] urdf) and
    the meshes it names, and ``also`` (the --settings file, a groups file)."""
    found: list[Path] = []
    urdf = getattr(getattr(settings, "robot", None), "urdf", "")
    if urdf:
        found.extend(_urdf_files(Path(urdf)))
    found.extend(Path(p) for p in also if p)
    return tuple(p for p in dict.fromkeys(found) if p.exists())


def _urdf_files(urdf: Path) -> list[Path]:
    """A URDF and the mesh files it names by a path (relative to it, absolute or
    file://; package:// needs a ROS workspace and is not followed)."""
    import re

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
