"""The two consoles every command prints through: results to stdout, logs, progress and
tables meant for people (when stdout carries machine output) to stderr.

Each is built, and rich imported, at its first use: every command module imports them,
and `clear --help` (which imports every command module and prints through click) would
otherwise pay rich's ~30 ms import for nothing.
"""

from __future__ import annotations

import errno
import sys
from typing import TYPE_CHECKING, Any, cast

if TYPE_CHECKING:
    from rich.console import Console


def _console(file: Any, stderr: bool = False) -> Console:
    """A console that prints tables whole when its stream is not a terminal (a pipe, a
    file): rich would otherwise cut cells to 80 columns with "…"."""
    from rich.console import Console  # noqa: PLC0415  (~30 ms: at first use, not at --help)

    class _Console(Console):
        def on_broken_pipe(self) -> None:
            """Stdout closed by its reader (`| head`): stop quietly, the same way wherever it
            happens (rich would exit 1 by itself; the CLI reports 141)."""
            self.quiet = True
            raise BrokenPipeError(errno.EPIPE, "stdout closed")

    is_tty = hasattr(file, "isatty") and file.isatty()
    return _Console(stderr=stderr, soft_wrap=True, width=None if is_tty else 100_000)


class _OnFirstUse:
    """Stands for the console of one stream, built at the first attribute read or set:
    every attribute goes to it, so it is used exactly as the console itself."""

    __slots__ = ("_built", "_stderr")

    def __init__(self, stderr: bool) -> None:
        object.__setattr__(self, "_stderr", stderr)
        object.__setattr__(self, "_built", None)

    def _console(self) -> Console:
        built = object.__getattribute__(self, "_built")
        if built is None:
            stderr = object.__getattribute__(self, "_stderr")
            built = _console(sys.stderr if stderr else sys.stdout, stderr=stderr)
            object.__setattr__(self, "_built", built)
        return cast("Console", built)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._console(), name)

    def __setattr__(self, name: str, value: Any) -> None:
        setattr(self._console(), name, value)

    # Python looks dunders up on the type, not through __getattr__: rich's Live and
    # Progress hold their console with `with console:` (its render lock and buffer)
    def __enter__(self) -> Console:
        return self._console().__enter__()

    def __exit__(self, *exc: Any) -> None:
        self._console().__exit__(*exc)


# Results go to stdout; logs, tables meant for people and progress go to stderr when
# stdout carries machine output.
stdout: Console = cast("Console", _OnFirstUse(stderr=False))
stderr: Console = cast("Console", _OnFirstUse(stderr=True))
