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
import tempfile
from pathlib import Path
from typing import Any, Iterator

from clearcli.errors import OutputError

# Temporary files are named ".<target name>.<random>.part" (atomic_output) or
# ".<target name>.<random><suffix>" (atomic_path) beside their target, <random> being
# mkstemp's 8 characters: `temporary_target` reads the target back from the name alone.
PART_SUFFIX = ".part"
# errno values of a write that failed for reasons of the place, not of clear: exit 8.
WRITE_ERRNOS = frozenset(
    getattr(errno, n) for n in ("ENOSPC", "EDQUOT", "EROFS", "EACCES", "EPERM", "ENAMETOOLONG", "EIO", "ENOENT", "EFBIG")
    if hasattr(errno, n)
)
# DOTALL and \Z: a file name may hold a newline, and its temporary is ours all the same
_TEMPORARY = re.compile(r"\.(?P<target>.+)\.[a-z0-9_]{8}(?:\.part|\.[A-Za-z0-9]+)\Z", re.DOTALL)


def temporary_target(name: str) -> str | None:
    """The file a temporary of ours named ``name`` was to become (None when ``name`` is
    not one): a batch removes exactly its own frames' temporaries, never by pattern."""
    m = _TEMPORARY.match(name)
    return m.group("target") if m else None


def _default_mode() -> int:
    """The mode a plain open() would give: mkstemp's 0600 would surprise users."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def check_output_path(path: Path, force: bool, inputs: tuple[Path, ...] = ()) -> None:
    """Refuse to clobber: an input, or an existing file without --force."""
    path = Path(path)
    for inp in inputs:
        with contextlib.suppress(OSError):
            if path.resolve() == Path(inp).resolve():
                raise OutputError(f"{path}: refusing to overwrite the input file; choose another path")
    if path.is_dir():
        raise OutputError(f"{path}: is a folder; name a file to write")
    if path.exists() and not force:
        raise OutputError(f"{path}: exists; pass --force to overwrite it")
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise OutputError(f"{path}: directory {parent} does not exist")


@contextlib.contextmanager
def _temporary_beside(path: Path, prefix: str, suffix: str) -> Iterator[tuple[int, str]]:
    """(fd, name) of a new temporary beside ``path``, moved onto it when the block ends
    normally and removed when it does not (an error, Ctrl-C, SIGTERM's SystemExit)."""
    parent = path.parent if str(path.parent) else Path(".")
    try:
        fd, tmp = tempfile.mkstemp(prefix=prefix, suffix=suffix, dir=parent)
    except OSError as exc:
        raise OutputError(f"{path}: cannot write ({exc.strerror or exc})", errno_=exc.errno) from None
    try:
        yield fd, tmp
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
