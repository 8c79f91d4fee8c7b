"""From the inputs a user names (files and folders) to the frames a batch works on.

A folder is searched (recursively, sorted by name, numbers in names by value) for
`.pcd`, `.mcap` and `.bag` files and depth images named by the naming rule
(`<stem>_depth.png|.tif|.tiff|.npy`; the suffix is [images] depth_suffix): a colour image
`<stem>_color.png` is never taken for a frame, it goes with its depth image. A folder
holding `metadata.yaml` is one rosbag2 bag. A log contributes frame 0, or
``--frame N``, or every N-th frame with ``--every N``. Each frame gets the name its
outputs carry in ``--out-dir``: the input's stem (a depth image's without the depth
suffix: `uois_0003_depth.png` -> `uois_0003`), plus ``_f<index>`` for a log.

Not a task: the batch's inputs, orchestrated. What a file is, what a folder search takes
and what a frame is read with is each input format's to say (clearcli/io/walk.py,
clearcli/io/formats/); how many frames a log holds and which files a run reads,
clearcli/io/inputs.py (`count_frames`, `files_read` and `run_files` are re-exported
here, where the commands and the batch have always found them). This module makes the
batch's items of them and checks them before any work.

What cannot be expanded (a missing file, a folder with no frames, a log that cannot be
read) becomes a `BadInput`: the batch reports it in its own line and goes on.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from clearcli.errors import EXIT_INPUT, ClearError, InputError
from clearcli.io.inputs import count_frames, files_read, run_files
from clearcli.io.walk import files_in, is_input_folder, is_log, natural_key, output_name, special, taken_before
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
    images = images if images is not None else ImageSettings()

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
                items.append(BadInput(str(p), str(broken), broken.exit_code, n, f"{stem}_f{n}"))
    return items


def check_intrinsics(spec: str) -> None:
    """Read the intrinsics ``spec`` (a file or "fx fy cx cy") once, before any frame: a bad
    one is one InputError (exit 3), not one per frame."""
    # the reader pulls NumPy, ~260 ms cold, for --intrinsics alone: the commands and the
    # batch import this module to list inputs and the files a run reads, which need none
    from clearcli.io.intrinsics import read_intrinsics  # noqa: PLC0415

    read_intrinsics(spec)


def check_unique_names(items: Sequence[Item]) -> None:
    """Two frames whose outputs would share a name: a usage error before any work."""
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
