"""The two consoles every command prints through: results to stdout, logs, progress and
tables meant for people (when stdout carries machine output) to stderr."""

from __future__ import annotations

import sys
from typing import Any

from rich.console import Console


def _console(file: Any, stderr: bool = False) -> Console:
    """A console that prints tables whole when its stream is not a terminal (a pipe, a
    file): rich would otherwise cut cells to 80 columns with "…"."""
    stream = file or (sys.stderr if stderr else sys.stdout)
    is_tty = hasattr(stream, "isatty") and stream.isatty()
    return Console(stderr=stderr, soft_wrap=True, width=None if is_tty else 100_000)


class _Lazy:
    """The console is made on first use, for the stream as it is then (tests swap
    sys.stdout)."""

    def __init__(self, stderr: bool) -> None:
        self._stderr = stderr
        self._made: tuple[Any, Console] | None = None

    def __getattr__(self, name: str) -> Any:
        stream = sys.stderr if self._stderr else sys.stdout
        if self._made is None or self._made[0] is not stream:
            self._made = (stream, _console(stream, self._stderr))
        return getattr(self._made[1], name)


# Results go to stdout; logs, tables meant for people and progress go to stderr when
# stdout carries machine output.
stdout: Any = _Lazy(stderr=False)
stderr: Any = _Lazy(stderr=True)
