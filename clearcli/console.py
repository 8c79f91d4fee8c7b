"""The two consoles every command prints through: results to stdout, logs, progress and
tables meant for people (when stdout carries machine output) to stderr."""

from __future__ import annotations

import errno
import sys
from typing import Any

from rich.console import Console


class _Console(Console):
    def on_broken_pipe(self) -> None:
        """Stdout closed by its reader (`| head`): stop quietly, the same way wherever it
        happens (rich would exit 1 by itself; the CLI reports 141)."""
        self.quiet = True
        raise BrokenPipeError(errno.EPIPE, "stdout closed")


def _console(file: Any, stderr: bool = False) -> Console:
    """A console that prints tables whole when its stream is not a terminal (a pipe, a
    file): rich would otherwise cut cells to 80 columns with "…"."""
    is_tty = hasattr(file, "isatty") and file.isatty()
    return _Console(stderr=stderr, soft_wrap=True, width=None if is_tty else 100_000)


# Results go to stdout; logs, tables meant for people and progress go to stderr when
# stdout carries machine output.
stdout: Console = _console(sys.stdout)
stderr: Console = _console(sys.stderr, stderr=True)
