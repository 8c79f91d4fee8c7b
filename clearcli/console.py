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
from collections.abc import Sequence
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


def _plain(text: Any, kwargs: dict[str, Any]) -> str | None:
    """What ``console.print(text, **kwargs)``, on a console not yet built whose stream is
    not a terminal, writes before its newline when it can be written without rich (the
    very bytes rich writes: tests/test_console.py compares the two), else None."""
    if type(text) is not str or len(text) > _PLAIN_MAX or not text.isascii():
        return None  # non-ASCII: rich's message on an encoding error differs
    if any(key not in ("markup", "highlight") for key in kwargs):
        return None  # highlighting only adds styles, which a pipe never shows
    if _NOT_PLAIN.search(text) or not _plain_stream():
        return None
    if kwargs.get("markup", True) is not False and "[" in text:
        # one bold span (segment's first line) is its text on a pipe; other markup: rich
        head, bold, rest = text.partition("[bold]")
        inner, close, tail = rest.partition("[/bold]")
        if not bold or not close or "\\" in text or "[" in head + inner + tail:
            return None
        return head + inner + tail
    return text


def _plain_stream() -> bool:
    """Whether nothing but isatty decides if rich takes the stream for a terminal."""
    return all(os.environ.get(name) is None for name in _RICH_ENV) and "IPython" not in sys.modules


def _plain_cell(text: Any) -> bool:
    """A table cell rich (markup on) draws as it is: ASCII, one line, no markup, emoji or
    control code, no space at either end nor two in a row (rich may wrap or trim those)."""
    return (
        type(text) is str
        and text.isascii()
        and "\n" not in text
        and "[" not in text
        and "\\" not in text
        and not _NOT_PLAIN.search(text)
        and text == text.strip()
        and "  " not in text
    )


def _plain_table(headers: Sequence[str], rows: Sequence[Sequence[str]]) -> str | None:
    """rich's ``Table(*headers)`` with ``rows`` as rich draws it on a pipe or a file
    (heavy head box, one space of padding, every column as wide as its widest cell), when
    every cell is plain (`_plain_cell`) and the table is far narrower than the console;
    else None."""
    cols = len(headers)
    if not all(map(_plain_cell, headers)) or any(len(r) != cols or not all(map(_plain_cell, r)) for r in rows):
        return None
    widths = [max(len(c) for c in column) for column in zip(headers, *rows)]
    if sum(widths) + 3 * cols + 1 > _PLAIN_MAX:
        return None

    def rule(left: str, fill: str, mid: str, right: str) -> str:
        return left + mid.join(fill * (w + 2) for w in widths) + right

    def cells(sep: str, values: Sequence[str]) -> str:
        return sep + sep.join(f" {v.ljust(w)} " for v, w in zip(values, widths)) + sep

    lines = [rule("┏", "━", "┳", "┓"), cells("┃", headers), rule("┡", "━", "╇", "┩")]
    lines += [cells("│", row) for row in rows]
    lines.append(rule("└", "─", "┴", "┘"))
    return "\n".join(lines)


def print_table(target: Console, headers: Sequence[str], rows: Sequence[Sequence[str]]) -> None:
    """``target.print(Table(*headers))`` with ``rows`` added: rich's table; drawn here
    without importing rich (~50 ms of a cold `clear segment`, issue 39) when it goes to a
    pipe or a file before the console is built, its stream takes UTF-8 (rich draws ASCII
    boxes otherwise) and `_plain_table` can draw it."""
    if isinstance(target, _OnFirstUse):
        file = target._plain_file()
        if file is not None and str(getattr(file, "encoding", None) or "utf-8").lower().startswith("utf"):
            text = _plain_table(headers, rows)
            if text is not None:
                target._write(file, text)
                return
    from rich.table import Table  # noqa: PLC0415  (~6 ms after rich.console: not for `clear --help`)

    table = Table(*headers)
    for row in rows:
        table.add_row(*row)
    target.print(table)


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
        file = self._plain_file()
        text = _plain(objects[0], kwargs) if file is not None and len(objects) == 1 else None
        if text is None:
            self._console().print(*objects, **kwargs)
        else:
            self._write(file, text)

    def _plain_file(self) -> Any:
        """The stream, when the console is not built yet and rich would take the stream
        for a pipe or a file (see `_plain` for the text), else None."""
        if object.__getattribute__(self, "_built") is not None:
            return None  # built: rich prints from now on (a Live or a Progress may hold it)
        file = sys.stderr if object.__getattribute__(self, "_stderr") else sys.stdout
        if file is None or hasattr(file, "rich_proxied_file") or _isatty(file) or not _plain_stream():
            return None  # nowhere (rich writes to nothing); rich's own redirection; a terminal
        return file

    def _write(self, file: Any, text: str) -> None:
        try:
            file.write(text + "\n")
            file.flush()
        except BrokenPipeError:
            # as the console's on_broken_pipe: quiet from now on, then the error
            self._console().on_broken_pipe()

    def __setattr__(self, name: str, value: Any) -> None:
        setattr(self._console(), name, value)

    # Python looks dunders up on the type, not through __getattr__: rich's Live and
    # Progress hold their console with `with console:` (its render lock and buffer)
    def __enter__(self) -> Console:
        return self._console().__enter__()

    def __exit__(self, *exc: Any) -> None:
        self._console().__exit__(*exc)


def is_pipe(target: Console) -> bool:
    """Whether ``target`` (`stdout` or `stderr`) is not built yet and rich would take its
    stream for a pipe or a file: nothing drawn for a terminal (a progress bar) is shown
    there, and the caller can skip importing rich for it (a batch's --json run, issue 39).
    A built console, or another one: False (ask the console)."""
    return isinstance(target, _OnFirstUse) and target._plain_file() is not None


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
