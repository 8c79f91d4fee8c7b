"""`clear info`, `clear settings`, and the "not yet" placeholders."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Callable, Optional

import typer

from clearcli.errors import NotYetError

SettingsOpt = Annotated[
    Optional[Path], typer.Option("--settings", help="TOML settings file (see `clear settings`).")
]


def not_yet(name: str) -> Callable[..., Any]:
    def _cmd(args: Annotated[Optional[list[str]], typer.Argument(hidden=True)] = None) -> None:
        raise NotYetError(f"`clear {name}` is not implemented yet")

    _cmd.__doc__ = f"(not implemented yet) the {name} stage."
    return _cmd


def settings_cmd(settings: SettingsOpt = None) -> None:
    """Print the settings (defaults, or FILE merged over them) as TOML."""
    from clearcli.settings import load_settings, settings_to_toml

    typer.echo(settings_to_toml(load_settings(settings)), nl=False)
