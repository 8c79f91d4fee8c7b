"""Output files written whole or not at all, and never over what the user had.

Every writer of `clear` goes through these: a temporary file beside the target, moved into
place only when complete (`os.replace` is atomic on one file system), removed on any
error or interruption. `clearcli.commands.common` re-exports them for the subcommands.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from clearcli.errors import InputError, OutputError

# Temporary files are named ".<target name>.<random>.part" (atomic_output) or
# ".<target name>.<random><suffix>" (atomic_path) beside their target, <random> being
# mkstemp's 8 characters: `temporary_target` reads the target back from the name alone.
PART_SUFFIX = ".part"
# errno values of a write that failed for reasons of the place, not of clear: exit 8.
WRITE_ERRNOS = frozenset(
    getattr(errno, n)
    for n in ("ENOSPC", "EDQUOT", "EROFS", "EACCES", "EPERM", "ENAMETOOLONG", "EIO", "ENOENT", "EFBIG")
    if hasattr(errno, n)
)
# DOTALL and \Z: a file name may hold a newline, and its temporary is ours all the same
_TEMPORARY = re.compile(r"\.(?P<target>.+)\.[a-z0-9_]{8}(?:\.part|\.[A-Za-z0-9]+)\Z", re.DOTALL)


def temporary_target(name: str) -> str | None:
    """The file a temporary of ours named ``name`` was to become (None when ``name`` is
    not one): a batch removes exactly its own frames' temporaries, never by pattern."""
    m = _TEMPORARY.match(name)
    return m.group("target") if m else None


def exists(path: str | Path) -> bool:
    """``Path.exists`` that says False, not raises, for a name the system cannot look up
    (past 255 bytes, through a file): text that may be a path or something else."""
    try:
        return Path(path).exists()
    except (OSError, ValueError):
        return False


def require_regular(path: str | Path, what: str) -> None:
    """InputError unless ``path`` is a regular file (links followed): a FIFO or a device
    given as an input is refused, never opened (opening a FIFO waits for a writer)."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror or exc})") from None
    if stat.S_ISDIR(mode):
        raise InputError(f"{path}: is a folder; give {what}")
    if not stat.S_ISREG(mode):
        raise InputError(f"{path}: not a regular file (a FIFO or a device); give {what}")


def _default_mode() -> int:
    """The mode a plain open() would give: mkstemp's 0600 would surprise users."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


# A link through one of these is an open file of a process (`/dev/stdout` ->
# `/proc/self/fd/1` -> wherever the shell sent it): written into, never replaced, or the
# shell's redirection would point at a file removed from under it.
_FD_LINK = re.compile(r"\A/(?:dev|proc/[^/]+)/fd/\d+\Z|\A/dev/std(?:out|err)\Z")


def _through_fd(path: Path) -> bool:
    """Whether ``path`` or a link on the way to its target names a process's open file."""
    hop = os.path.abspath(path)
    for _ in range(40):  # the kernel's own limit of links followed
        if _FD_LINK.match(hop):
            return True
        try:
            nxt = os.readlink(hop)
        except OSError:
            return False
        hop = os.path.abspath(os.path.join(os.path.dirname(hop), nxt))
    return False


def stream_kind(path: Path) -> str | None:
    """What kind of non-regular file ``path`` (links followed) is, when output to it is
    written into rather than replaced: "a character device" (/dev/null, a terminal),
    "a FIFO", or "an open file of a process" (/dev/stdout, /dev/fd/N). None for a
    regular file, a missing one or a folder; a block device or a socket is refused by
    `check_output_path`."""
    if _through_fd(Path(path)):
        return "an open file of a process"
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return None
    if stat.S_ISCHR(mode):
        return "a character device"
    if stat.S_ISFIFO(mode):
        return "a FIFO"
    return None


def check_output_path(path: Path, force: bool, inputs: tuple[Path, ...] = (), streams: bool = True) -> None:
    """Refuse to clobber: an input (by its real path), an existing file without
    --force, a folder, a block device or socket. An existing character device, FIFO or
    open file (/dev/null, /dev/stdout, a pipe) is written into, never replaced: no
    --force needed, nothing the user had is lost (``streams`` False: refused instead,
    as in a batch's --out-dir, whose outputs are files)."""
    path = Path(path)
    try:
        _check_output_path(path, force, inputs, streams)
    except OSError as exc:  # a name too long, a path through a file: the place, not clear
        raise OutputError(f"{path}: cannot write ({exc.strerror or exc})", errno_=exc.errno) from None


def _check_output_path(path: Path, force: bool, inputs: tuple[Path, ...], streams: bool) -> None:
    for inp in inputs:
        with contextlib.suppress(OSError):
            if path.resolve() == Path(inp).resolve() or os.path.samefile(path, inp):
                also = "" if str(inp) == str(path) else f" (as {inp})"
                raise OutputError(
                    f"{path}: is an input of this run, a file it reads{also}; refusing to overwrite it (even "
                    "with --force); choose another path"
                )
    if path.is_dir():
        raise OutputError(f"{path}: is a folder; name a file to write")
    kind = stream_kind(path)
    if kind is not None:
        if not streams:
            raise OutputError(f"{path}: is {kind}, not a file; remove it or choose another --out-dir")
        return
    if path.exists() and not path.is_file():
        raise OutputError(f"{path}: is not a regular file (a block device or socket); name a file to write")
    if path.exists() and not force:
        raise OutputError(f"{path}: exists; pass --force to overwrite it")
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise OutputError(f"{path}: directory {parent} does not exist")


def _write_into(path: Path, tmp: str) -> None:
    """Copy the finished temporary ``tmp`` into the stream ``path`` (a device, a FIFO,
    an open file), opened for appending, never created, truncated or replaced. A FIFO
    nobody reads is refused at once rather than waited on for ever."""
    flags = os.O_WRONLY | os.O_APPEND | getattr(os, "O_NOCTTY", 0)
    try:
        fd = os.open(path, flags | os.O_NONBLOCK)
    except OSError as exc:
        if exc.errno == errno.ENXIO:
            raise OutputError(f"{path}: a FIFO that nobody reads; start its reader first", errno_=exc.errno) from None
        raise
    try:
        os.set_blocking(fd, True)
        with open(tmp, "rb") as src:
            while chunk := src.read(1 << 20):
                view = memoryview(chunk)
                while view:
                    view = view[os.write(fd, view) :]
    finally:
        os.close(fd)


@contextlib.contextmanager
def _temporary_beside(path: Path, prefix: str, suffix: str) -> Iterator[tuple[int, str]]:
    """(fd, name) of a new temporary beside ``path``, moved onto it when the block ends
    normally and removed when it does not (an error, Ctrl-C, SIGTERM's SystemExit). A
    stream (`stream_kind`) is written into once its output is whole, never replaced."""
    stream = stream_kind(path) is not None
    if not stream and path.is_symlink():
        path = path.resolve()  # a link to a file: the file is written, the link kept
    # a stream's output is made whole in the temporary folder first, then copied in
    parent = Path(tempfile.gettempdir()) if stream else (path.parent if str(path.parent) else Path("."))
    try:
        fd, tmp = tempfile.mkstemp(prefix=prefix, suffix=suffix, dir=parent)
    except OSError as exc:
        raise OutputError(f"{path}: cannot write ({exc.strerror or exc})", errno_=exc.errno) from None
    try:
        yield fd, tmp
        if stream:
            _write_into(path, tmp)
            os.unlink(tmp)
        else:
            os.chmod(tmp, _default_mode())
            os.replace(tmp, path)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        if isinstance(exc, OSError) and exc.errno in WRITE_ERRNOS:
            # a full disk, a read-only or vanished folder: bad output, not a bug
            raise OutputError(f"{path}: cannot write ({exc.strerror or exc})", errno_=exc.errno) from None
        raise


@contextlib.contextmanager
def atomic_output(path: Path, mode: str = "wb") -> Iterator[Any]:
    """Write to a temporary file beside ``path`` and move it into place only when whole."""
    path = Path(path)
    with _temporary_beside(path, f".{path.name}.", PART_SUFFIX) as (fd, _tmp):
        with os.fdopen(fd, mode) as handle:
            yield handle


@contextlib.contextmanager
def atomic_path(path: Path) -> Iterator[Path]:
    """Like `atomic_output`, for writers that want a path (pypcd4, matplotlib: they
    choose the format by the suffix, so the temporary keeps it)."""
    path = Path(path)
    with _temporary_beside(path, f".{path.name}.", path.suffix) as (fd, tmp):
        os.close(fd)
        yield Path(tmp)
