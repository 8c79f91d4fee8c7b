"""The subcommands, in the order `clear --help` lists them.

Each entry: (name, function, typer.command kwargs). A subcommand's module imports only
typer/rich at top level.
"""

from __future__ import annotations

from typing import Any, Callable

import typer

from clearcli.commands import basic, info, replay, plan, predicates, simulate
from clearcli.commands import evaluate, segment

COMMANDS: list[tuple[str, Callable[..., Any], dict[str, Any]]] = [
    ("info", info.info_cmd, {}),
    ("segment", segment.segment_cmd, {}),
    ("predicates", predicates.predicates_cmd, {}),
    ("domain", predicates.domain_cmd, {}),
    ("plan", plan.plan_cmd, {}),
    ("replay", replay.replay_cmd, {}),
    ("simulate", simulate.simulate_cmd, {}),
    ("settings", basic.settings_cmd, {}),
]

GROUPS: list[tuple[str, typer.Typer]] = [
    ("evaluate", evaluate.evaluate_app),
]
