"""What every subcommand shares: consoles, printing a document, output paths.

Only light imports here (typer, rich): `clear --help` must stay fast.
"""

from __future__ import annotations

import sys
from typing import Any, Mapping

from rich.console import Console

from clearcli.io.files import atomic_output, atomic_path, check_output_path  # noqa: F401  (re-exported)


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


def print_json(schema: str, version: int, payload: Mapping[str, Any], settings: Any, command: str) -> None:
    """One JSON document on stdout in the shared envelope, with its provenance."""
    from clearcli.provenance import envelope, print_document, stamp

    print_document(envelope(schema, version, payload, stamp(settings, command)))
