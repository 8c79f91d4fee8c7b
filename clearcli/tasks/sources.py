"""From the inputs a user names (files and folders) to the frames a batch works on.

A folder is searched (recursively, sorted by name, numbers in names by value) for
`.pcd`, `.mcap` and `.bag` files and depth images named by the naming rule
(`<stem>_depth.png|.tif|.tiff|.npy`; the suffix is [images] depth_suffix): a colour image
`<stem>_color.png` is never taken for a frame, it goes with its depth image. A folder
holding `metadata.yaml` is one rosbag2 bag. A log contributes frame 0, or
``--frame N``, or every N-th frame with ``--every N``. Each frame gets the name its
outputs carry in ``--out-dir``: the input's stem (a depth image's without the depth
suffix: `uois_0003_depth.png` -> `uois_0003`), plus ``_f<index>`` for a log.

What cannot be expanded (a missing file, a folder with no frames, a log that cannot be
read) becomes a `BadInput`: the batch reports it in its own line and goes on.
"""

from __future__ import annotations

import errno
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence, Union

if TYPE_CHECKING:
    from clearcli.settings.images import ImageSettings

FRAME_SUFFIXES = (".pcd", ".mcap", ".bag")


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


Item = Union[FrameRef, BadInput, Skipped]


def natural_key(path: Path) -> tuple:
    """learn2 before learn10: digit runs compare as numbers."""
    import re

    return tuple(int(t) if t.isdigit() else t for t in re.split(r"(\d+)", path.name))


def _is_rosbag2(path: Path) -> bool:
    return path.is_dir() and (path / "metadata.yaml").is_file()


def _special(path: Path) -> str | None:
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
    kind = {stat.S_ISFIFO: "a FIFO (named pipe)", stat.S_ISSOCK: "a socket", stat.S_ISCHR: "a character device",
            stat.S_ISBLK: "a block device"}
    return next((name for test, name in kind.items() if test(mode)), "not a regular file")


def _is_depth_image(path: Path, depth_suffix: str) -> bool:
    """A depth image by the naming rule (a folder search takes only these)."""
    from clearcli.io.images import IMAGE_SUFFIXES

    return path.suffix.lower() in IMAGE_SUFFIXES and path.stem.endswith(depth_suffix)


def _files_in(folder: Path, seen: set[tuple[int, int]], skipped: list["Skipped"], depth_suffix: str = "_depth") -> list[Path]:
    """Frame files below ``folder``, sorted; a rosbag2 folder is one entry, hidden
    entries (a batch's own temporaries, editors' backups) are passed over. Only regular
    files and folders are taken; each real folder is searched once (``seen``: its device
    and inode), so a link back up the tree is reported, not walked again."""
    found: list[Path] = []
    try:
        st = folder.stat()
    except OSError:
        return found
    if (st.st_dev, st.st_ino) in seen:
        skipped.append(Skipped(str(folder), "a link to a folder already searched"))
        return found
    seen.add((st.st_dev, st.st_ino))
    for p in sorted(folder.iterdir(), key=natural_key):
        if p.name.startswith("."):
            continue
        why = _special(p)
        if why is not None:
            skipped.append(Skipped(str(p), why))
        elif p.is_dir():
            found.extend([p] if _is_rosbag2(p) else _files_in(p, seen, skipped, depth_suffix))
        elif p.suffix.lower() in FRAME_SUFFIXES or _is_depth_image(p, depth_suffix):
            found.append(p)
    return found


def _is_log(path: Path) -> bool:
    """A log (frames named with their index): MCAP, ROS 1 bag, rosbag2 (folder, .db3,
    metadata.yaml); told by content, as `io.read.sniff` does."""
    from clearcli.io.sniff import MCAP_MAGIC, ROSBAG1_MAGIC, ROSBAG2_METADATA, SQLITE_MAGIC

    if path.is_dir() or path.name == ROSBAG2_METADATA:
        return True
    try:
        with open(path, "rb") as fp:
            head = fp.read(16)
    except OSError:
        return path.suffix.lower() in (".mcap", ".bag", ".db3")
    return head.startswith((MCAP_MAGIC, ROSBAG1_MAGIC, SQLITE_MAGIC))


def count_frames(path: Path, topic: str | None) -> tuple[int, Exception | None]:
    """Point-cloud frames in a log, and the PartialLogError that ended it early, if any.
    An intact log or bag is counted from its summary (index); a damaged one is read
    through to its break."""
    from clearcli.errors import PartialLogError
    from clearcli.io.mcap import choose_topic
    from clearcli.io.read import iter_frames, sniff

    if sniff(path) == "mcap":
        from clearcli.io.mcap import read_summary as summary_of
    else:
        from clearcli.io.rosbag import read_bag_summary as summary_of
    summary = summary_of(path)
    if summary.damage is None:
        return summary.count(choose_topic(summary, topic)), None
    n = 0
    try:
        for _ in iter_frames(path, topic):
            n += 1
    except PartialLogError as exc:
        return n, exc
    return n, None


def expand(
    inputs: Sequence[Path],
    *,
    frame: int | None = None,
    every: int | None = None,
    topic: str | None = None,
    images: "ImageSettings | None" = None,
) -> list[Item]:
    """The frames of ``inputs`` in order (folders expanded), and the inputs that fail.
    ``images``: the naming rule of depth images ([images]; defaults when None)."""
    from clearcli.errors import EXIT_INPUT, ClearError
    from clearcli.io.images import or_defaults, frame_name

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
        why = _special(path)
        if why is not None:
            items.append(Skipped(str(path), why))
            continue
        if path.is_dir() and not _is_rosbag2(path):
            skipped: list[Skipped] = []
            files = _files_in(path, seen, skipped, images.depth_suffix)
            items.extend(skipped)
            if not files and not skipped:
                items.append(BadInput(
                    str(path), f"{path}: folder holds no .pcd, .mcap or .bag file and no depth image named "
                    f"<stem>{images.depth_suffix}.png (.tif, .npy)", EXIT_INPUT,
                ))
            paths = files
        elif not path.exists():
            items.append(BadInput(str(path), f"{path}: file not found", EXIT_INPUT))
            continue
        else:
            paths = [path]
        searched = path.is_dir() and not _is_rosbag2(path)
        for p in paths:
            again = _taken_before(p, taken)
            if again is not None and searched:
                items.append(Skipped(str(p), f"the same file as {again}, reached again"))
                continue
            stem = p.name if p.is_dir() else p.stem
            if not _is_log(p):
                name = frame_name(p, images) if _is_depth_image(p, images.depth_suffix) else stem
                items.append(FrameRef(str(p), 0, False, name))
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
                items.append(BadInput(
                    str(p), f"{p}: --frame {start} with --every {every} selects no frame: the log has {n} "
                    f"frame(s) on its point-cloud topic (0-{n - 1})" if n else f"{p}: the log has no point-cloud frame",
                    EXIT_INPUT, start, f"{stem}_f{start}",
                ))
                continue
            items.extend(FrameRef(str(p), k, True, f"{stem}_f{k}") for k in range(start, n, every))
            if broken is not None:  # every complete frame is in; the break is reported
                items.append(BadInput(str(p), str(broken), broken.exit_code, n, f"{stem}_f{n}"))  # type: ignore[attr-defined]
    return items


def _taken_before(path: Path, taken: dict[tuple[int, int], str]) -> str | None:
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
    from clearcli.io.images import INTRINSICS_NAMES, color_pair, or_defaults

    path = Path(source)
    images = or_defaults(getattr(settings, "images", None))
    found: list[Path] = [path]
    if _is_rosbag2(path):
        found.extend(p for p in path.iterdir() if p.is_file())
    elif _is_depth_image(path, images.depth_suffix) or path.suffix.lower() in (".png", ".tif", ".tiff", ".npy"):
        paired = Path(color) if color else color_pair(path, images)
        if paired is not None:
            found.append(paired)
        if images.intrinsics and Path(images.intrinsics).is_file():
            found.append(Path(images.intrinsics))
        elif not images.intrinsics:
            found.extend(path.parent / n for n in INTRINSICS_NAMES)
    elif color:
        found.append(Path(color))
    return tuple(p for p in dict.fromkeys(found) if p.exists()) + run_files(settings, also)


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
        name = name[len("file://"):] if name.startswith("file://") else name
        meshes.append(urdf.parent / name)
    return [urdf, *meshes]
