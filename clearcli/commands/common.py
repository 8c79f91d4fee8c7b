"""What every subcommand shares: reading a frame, settings, output files, JSON, consoles.

Only light imports here (typer, rich): `clear --help` must stay fast.
"""

from __future__ import annotations

import contextlib
import json
import os
import sys
import tempfile
from pathlib import Path
from typing import Any, Iterator

from rich.console import Console

from clearcli.errors import OutputError


def _default_mode() -> int:
    """The mode a plain open() would give: mkstemp's 0600 would surprise users."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask

JSON_SCHEMA_VERSION = 1

# Results go to stdout; logs, tables meant for people and progress go to stderr when
# stdout carries machine output.
stdout = Console(soft_wrap=True)
stderr = Console(stderr=True, soft_wrap=True)


def print_json(kind: str, payload: dict[str, Any], version: int = JSON_SCHEMA_VERSION) -> None:
    """One JSON document on stdout with the versioned envelope every command shares.
    Versions are per schema: a schema's version rises when a key is removed, renamed or
    changes meaning."""
    doc = {"schema": f"clear.{kind}", "version": version, **payload}
    sys.stdout.write(json.dumps(doc, separators=(",", ":"), allow_nan=False) + "\n")
    sys.stdout.flush()


def check_output_path(path: Path, force: bool, inputs: tuple[Path, ...] = ()) -> None:
    """Refuse to clobber: an input, or an existing file without --force."""
    path = Path(path)
    for inp in inputs:
        with contextlib.suppress(OSError):
            if path.resolve() == Path(inp).resolve():
                raise OutputError(f"{path}: refusing to overwrite the input file; choose another path")
    if path.exists() and not force:
        raise OutputError(f"{path}: exists; pass --force to overwrite it")
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise OutputError(f"{path}: directory {parent} does not exist")


@contextlib.contextmanager
def atomic_output(path: Path, mode: str = "wb") -> Iterator[Any]:
    """Write to a temporary file beside ``path`` and move it into place only when whole."""
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=parent)
    except OSError as exc:
        raise OutputError(f"{path}: cannot write ({exc.strerror})") from None
    try:
        with os.fdopen(fd, mode) as handle:
            yield handle
        os.chmod(tmp, _default_mode())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


@contextlib.contextmanager
def atomic_path(path: Path) -> Iterator[Path]:
    """Like `atomic_output`, for writers that want a path (open3d, matplotlib)."""
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=parent)
    except OSError as exc:
        raise OutputError(f"{path}: cannot write ({exc.strerror})") from None
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, _default_mode())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
