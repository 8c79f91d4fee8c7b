"""The two consoles every command prints through: results to stdout, logs, progress and
tables meant for people (when stdout carries machine output) to stderr.

Each is built, and rich imported, at its first use: every command module imports them,
and `clear --help` (which imports every command module and prints through click) would
otherwise pay rich's ~30 ms import for nothing. A line of plain text printed to a pipe or
a file, before anything else needed the console, is written as rich would write it
without importing rich (`_plain`): `clear plan`'s text prints only such lines, and
rich.console was ~40-50 ms of its cold start (issue 39).
"""

from __future__ import annotations

import errno
import os
import re
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


# What rich's Console.print (rich 13-15) changes in a plain string when its stream is not a
# terminal: markup ("[bold]"; with markup off, none), emoji codes (":smile:"), the control
# codes its Text strips (BEL, BS, VT, FF, CR), tabs (expanded), and lines longer than the
# console's width (100 000 columns here; wide characters count two). A string with none
# of those is written as it is, then the end of line. Anything else goes to rich.
_NOT_PLAIN = re.compile(r"[\x07\x08\x0b\x0c\r\t]|:\S*:")
_PLAIN_MAX = 50_000  # characters: under half the width even if every one were wide
# What makes rich treat a pipe as a terminal (or pick its own output) whatever isatty says.
_RICH_ENV = ("FORCE_COLOR", "TTY_COMPATIBLE", "JUPYTER_COLUMNS", "JUPYTER_LINES")


def _plain(text: Any, kwargs: dict[str, Any]) -> bool:
    """Whether ``console.print(text, **kwargs)`` on a console not yet built may write
    ``text`` and a newline itself: the very bytes rich would write (tests/test_console.py
    compares the two), without importing rich."""
    if type(text) is not str or len(text) > _PLAIN_MAX or not text.isascii():
        return False  # non-ASCII: rich's message on an encoding error differs
    if any(key not in ("markup", "highlight") for key in kwargs):
        return False  # highlighting only adds styles, which a pipe never shows
    if kwargs.get("markup", True) is not False and "[" in text:
        return False
    if _NOT_PLAIN.search(text) or any(os.environ.get(name) is not None for name in _RICH_ENV):
        return False
    if "IPython" in sys.modules:  # rich writes to a notebook its own way
        return False
    return True


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

    def print(self, *objects: Any, **kwargs: Any) -> None:
        """rich's Console.print; a plain line to a pipe or a file before the console is
        built is written here (`_plain`), as rich writes it: the text, a newline, a flush."""
        stderr = object.__getattribute__(self, "_stderr")
        file = sys.stderr if stderr else sys.stdout
        if (
            object.__getattribute__(self, "_built") is None
            and len(objects) == 1
            and _plain(objects[0], kwargs)
            and file is not None  # rich writes nowhere then
            and not hasattr(file, "rich_proxied_file")  # rich's own redirection (a Live's)
            and not _isatty(file)
        ):
            try:
                file.write(objects[0] + "\n")
                file.flush()
            except BrokenPipeError:
                # as the console's on_broken_pipe: quiet from now on, then the error
                self._console().on_broken_pipe()
            return
        self._console().print(*objects, **kwargs)

    def __setattr__(self, name: str, value: Any) -> None:
        setattr(self._console(), name, value)

    # Python looks dunders up on the type, not through __getattr__: rich's Live and
    # Progress hold their console with `with console:` (its render lock and buffer)
    def __enter__(self) -> Console:
        return self._console().__enter__()

    def __exit__(self, *exc: Any) -> None:
        self._console().__exit__(*exc)


def _isatty(file: Any) -> bool:
    """rich's test (Console.is_terminal, after the environment's overrides): a stream
    without isatty, or one that fails it, is not a terminal."""
    isatty = getattr(file, "isatty", None)
    try:
        return bool(isatty()) if isatty is not None else False
    except ValueError:
        return False


# Results go to stdout; logs, tables meant for people and progress go to stderr when
# stdout carries machine output.
stdout: Console = cast("Console", _OnFirstUse(stderr=False))
stderr: Console = cast("Console", _OnFirstUse(stderr=True))
