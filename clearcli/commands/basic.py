"""`clear settings`: the resolved settings tree as TOML."""

from __future__ import annotations

from typing import Annotated

import typer

from clearcli.commands import options as bo


def settings_cmd(
    settings: bo.SettingsFile = None,
    sets: bo.Set = None,
    ranges: Annotated[bool, typer.Option("--ranges", help="Say each key's accepted values in a comment.")] = False,
) -> None:
    """Print every setting as TOML: the defaults, or FILE and each --set merged over them
    (the resolved tree a command would use). Every value is checked first: a bad one is
    one line naming the key, the value and the accepted range (exit 3)."""
    from clearcli.settings import settings_to_toml

    typer.echo(settings_to_toml(bo.resolve_settings(settings, sets), ranges=ranges), nl=False)
