"""Tests of clearcli/console.py: the consoles built on first use."""

from __future__ import annotations

import io
import sys

import pytest

from clearcli import console


@pytest.fixture(autouse=True)
def _as_in_a_command(monkeypatch: pytest.MonkeyPatch) -> None:
    """The environment of a `clear` process: none of the variables that make rich take a
    pipe for a terminal, and no IPython loaded (the full suite imports it through another
    test's libraries; `_plain` then leaves everything to rich, as it should in Jupyter)."""
    for name in console._RICH_ENV:
        monkeypatch.delenv(name, raising=False)
    monkeypatch.delitem(sys.modules, "IPython", raising=False)


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
    "[bold]/data/frame.pcd[/bold]: table normal (0.006, -0.800, -0.600), camera 0.613 m above it",
    "[bold]a[/bold] [bold]b[/bold]",
    "[bold]a (unclosed)",
    "[bold]a\\[b][/bold]",
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
    assert (built is None) == (console._plain(text, dict(kwargs)) is not None)
    assert built is None or isinstance(built, Console)


def test_plan_text_is_printed_without_rich(monkeypatch: pytest.MonkeyPatch) -> None:
    """The lines `clear plan` prints are plain: its cold start does not import rich."""
    for text in _TEXTS[:6]:
        assert console._plain(text, {"markup": False, "highlight": False}) == text
    assert console._plain("[bold]o1[/bold] stays", {}) == "o1 stays"  # segment's bold span
    assert console._plain("[o1] stays", {}) is None  # other markup: rich
    for text in (":smile:", "a\ttab", "cr\r", "café", "x" * 60_000):
        assert console._plain(text, {"markup": False, "highlight": False}) is None
    assert console._plain("a", {"end": ""}) is None  # any other option: rich
    monkeypatch.setenv("FORCE_COLOR", "1")  # rich would treat the pipe as a terminal
    assert console._plain("plain", {"markup": False}) is None


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


def _rich_table(headers: list[str], rows: list[list[str]]) -> str:
    from rich.table import Table

    out, saved = io.StringIO(), sys.stdout
    table = Table(*headers)
    for row in rows:
        table.add_row(*row)
    try:
        sys.stdout = out  # the console writes to sys.stdout as it is at the time
        console._console(out).print(table)
    finally:
        sys.stdout = saved
    return out.getvalue()


def test_a_plain_table_is_drawn_as_rich_draws_it() -> None:
    """Issue 39: `clear segment`'s table, to a pipe, without rich: random tables of plain
    cells (and cells rich would change, which go to rich) give rich's bytes."""
    import random

    rnd = random.Random(1)
    alphabet = "abcxyz0123456789 .+-()/_,;=<>!?%#@&*'|~^`{}$"
    odd = ["[b]x[/b]", ":smile:", "\t", "\u00e9", "  y", " ", "\n2", "\\"]
    drawn = 0
    for _ in range(400):
        cols, n_rows = rnd.randint(1, 6), rnd.randint(0, 5)

        def cell() -> str:
            text = "".join(rnd.choice(alphabet) for _ in range(rnd.choice([0, 1, 3, 8, 20])))
            return text + rnd.choice(odd) if rnd.random() < 0.1 else text

        headers = [cell() or "h" for _ in range(cols)]
        rows = [[cell() for _ in range(cols)] for _ in range(n_rows)]
        ours = console._plain_table(headers, rows)
        if ours is not None:
            assert ours + "\n" == _rich_table(headers, rows), (headers, rows)
            drawn += 1
    assert drawn > 100  # most were drawn here, not left to rich


def test_print_table_goes_to_a_pipe_without_rich_and_to_a_terminal_with_it(monkeypatch: pytest.MonkeyPatch) -> None:
    headers = ["id", "label", "points", "centroid (m)", "box extents (m)"]
    rows = [["0", "10", "20193", "-0.056 +0.086 +0.633", "0.158 x 0.065 x 0.248"]]
    want = _rich_table(headers, rows)
    pipe = io.StringIO()
    monkeypatch.setattr(sys, "stdout", pipe)
    proxy = console._OnFirstUse(stderr=False)
    console.print_table(proxy, headers, rows)  # type: ignore[arg-type]
    assert object.__getattribute__(proxy, "_built") is None
    assert pipe.getvalue() == want

    class Tty(io.StringIO):
        def isatty(self) -> bool:
            return True

    monkeypatch.setattr(sys, "stdout", Tty())
    proxy = console._OnFirstUse(stderr=False)
    console.print_table(proxy, headers, rows)  # type: ignore[arg-type]
    assert object.__getattribute__(proxy, "_built") is not None  # rich drew it
