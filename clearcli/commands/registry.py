"""The subcommands, in the order `clear --help` lists them.

Each entry names its function as "module:attribute", imported only when the command is
registered: `clear plan ...` imports and registers `plan` alone (clearcli/cli.py), while
`clear --help` and anything not naming a known command register them all. So a
subcommand's module imports at its top only what costs `--help` next to nothing, and its
task inside its function (clearcli/commands/__init__.py).

COMMANDS: (name, "module:function", typer.command kwargs).
GROUPS: (name, "module:typer.Typer").
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

COMMANDS: list[tuple[str, str, dict[str, Any]]] = [
    ("info", "clearcli.commands.info:info_cmd", {}),
    ("segment", "clearcli.commands.segment:segment_cmd", {}),
    ("predicates", "clearcli.commands.predicates:predicates_cmd", {}),
    ("domain", "clearcli.commands.predicates:domain_cmd", {}),
    ("plan", "clearcli.commands.plan:plan_cmd", {}),
    ("replay", "clearcli.commands.replay:replay_cmd", {}),
    ("simulate", "clearcli.commands.simulate:simulate_cmd", {}),
    ("settings", "clearcli.commands.basic:settings_cmd", {}),
    ("robots", "clearcli.commands.basic:robots_cmd", {}),
    ("schema", "clearcli.commands.schema:schema_cmd", {}),
]

GROUPS: list[tuple[str, str]] = [
    ("evaluate", "clearcli.commands.evaluate:evaluate_app"),
]

NAMES: frozenset[str] = frozenset([name for name, _, _ in COMMANDS] + [name for name, _ in GROUPS])


def load(target: str) -> Any:
    """The object a "module:attribute" entry names."""
    module, _, attr = target.partition(":")
    return getattr(import_module(module), attr)
