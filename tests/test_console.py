"""Tests of clearcli/console.py: the consoles built on first use."""

from __future__ import annotations

import io
import sys

import pytest

from clearcli import console


def test_a_lazy_console_is_a_context_manager_as_rich_uses_it(capsys) -> None:  # type: ignore[no-untyped-def]
    # rich's Live and Progress hold their console with `with console:`; Python looks
    # that up on the type, past the proxy's __getattr__
    proxy = console._OnFirstUse(stderr=True)
    with proxy as inner:
        inner.print("inside")
    assert "inside" in capsys.readouterr().err


def test_a_progress_on_the_lazy_console_starts_and_stops() -> None:
    from rich.progress import Progress

    with Progress(console=console.stderr, transient=True) as progress:
        progress.add_task("x", total=1)


# Strings as the commands print them, and the cases rich changes (markup, emoji codes,
# control codes, tabs, ANSI sequences, trailing spaces, blank lines, non-ASCII). (A line
# longer than _PLAIN_MAX goes to rich too, checked below without it: rich's highlighter
# takes minutes on one.)
_TEXTS = [
    "  1. (grasp o0)",
    "complete: removes all 2 objects",
    "cost 2, optimal (proven), every action IK-checked, search astar(lmcut())",
    "first action (grasp o0), joint solution (rad) per pose:",
    "  [-0.343, +0.616, +0.545, +2.427, -1.109, +0.350, -1.786]",
    "left o3 (unreachable): every pose of (grasp o3) has no IK solution",
    "[bold]o1[/bold] stays",
    "[o1] stays",
    "ratio 1:2:3 and :smile: and :thumbs_up: and ::",
    "a\ttab",
    "bell\x07 backspace\x08 vt\x0b ff\x0c cr\r end",
    "\x1b[31mred\x1b[0m",
    "trailing spaces   ",
    "",
    "\n",
    "two\n\nlines\n",
    "café ×2",
    "\\[escaped]",
]


@pytest.mark.parametrize("text", _TEXTS)
@pytest.mark.parametrize("kwargs", [{"markup": False, "highlight": False}, {"markup": False}, {}, {"highlight": False}])
def test_a_plain_line_to_a_pipe_is_what_rich_writes(text: str, kwargs: dict[str, object]) -> None:
    """Issue 39: a line printed before the console is built, to a stream that is not a
    terminal, is written without rich when that gives the same bytes."""
    from rich.console import Console

    ours, theirs = io.StringIO(), io.StringIO()
    saved = sys.stdout
    try:
        sys.stdout = theirs
        console._console(theirs).print(text, **kwargs)  # type: ignore[arg-type]
        sys.stdout = ours
        proxy = console._OnFirstUse(stderr=False)
        proxy.print(text, **kwargs)
    finally:
        sys.stdout = saved
    assert ours.getvalue() == theirs.getvalue()
    # the plain strings went without a console; the others through rich's
    built = object.__getattribute__(proxy, "_built")
    assert (built is None) == console._plain(text, dict(kwargs))
    assert built is None or isinstance(built, Console)


def test_plan_text_is_printed_without_rich(monkeypatch: pytest.MonkeyPatch) -> None:
    """The lines `clear plan` prints are plain: its cold start does not import rich."""
    for text in _TEXTS[:6]:
        assert console._plain(text, {"markup": False, "highlight": False})
    assert not console._plain("[bold]o1[/bold] stays", {})  # markup on
    for text in (":smile:", "a\ttab", "cr\r", "café", "x" * 60_000):
        assert not console._plain(text, {"markup": False, "highlight": False})
    assert not console._plain("a", {"end": ""})  # any other option: rich
    monkeypatch.setenv("FORCE_COLOR", "1")  # rich would treat the pipe as a terminal
    assert not console._plain("plain", {"markup": False})


def test_a_terminal_gets_rich(monkeypatch: pytest.MonkeyPatch) -> None:
    class Tty(io.StringIO):
        def isatty(self) -> bool:
            return True

    monkeypatch.setattr(sys, "stdout", Tty())
    proxy = console._OnFirstUse(stderr=False)
    proxy.print("plain", markup=False, highlight=False)
    assert object.__getattribute__(proxy, "_built") is not None
    assert sys.stdout.getvalue() == "plain\n"


def test_a_closed_pipe_is_raised_as_the_console_raises_it(monkeypatch: pytest.MonkeyPatch) -> None:
    class Closed(io.StringIO):
        def write(self, s: str) -> int:
            raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr(sys, "stdout", Closed())
    proxy = console._OnFirstUse(stderr=False)
    with pytest.raises(BrokenPipeError, match="stdout closed"):
        proxy.print("plain", markup=False)
    assert object.__getattribute__(proxy, "_built").quiet  # later prints are dropped
