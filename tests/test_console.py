"""Tests of clearcli/console.py: the consoles built on first use."""

from __future__ import annotations

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
