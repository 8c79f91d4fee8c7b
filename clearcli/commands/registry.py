"""The subcommands, in the order `clear --help` lists them.

Each entry: (name, function, typer.command kwargs). A subcommand's module imports only
typer/rich at top level.
"""

from __future__ import annotations

from typing import Any, Callable

import typer

from clearcli.commands import basic

COMMANDS: list[tuple[str, Callable[..., Any], dict[str, Any]]] = [
    ("info", basic.info_cmd, {}),
    ("segment", basic.not_yet("segment"), {}),
    ("predicates", basic.not_yet("predicates"), {}),
    ("plan", basic.not_yet("plan"), {}),
    ("replay", basic.not_yet("replay"), {}),
    ("settings", basic.settings_cmd, {}),
]

GROUPS: list[tuple[str, typer.Typer]] = []
