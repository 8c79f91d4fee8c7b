"""`clear settings`: the resolved settings tree as TOML."""

from __future__ import annotations

from typing import Annotated

import typer

from clearcli import settings as clear_settings
from clearcli.commands import options as bo
from clearcli.commands.common import print_json


def settings_cmd(
    settings: bo.SettingsFile = None,
    sets: bo.Set = None,
    ranges: Annotated[bool, typer.Option("--ranges", help="Say each key's accepted values in a comment.")] = False,
) -> None:
    """Print every setting as TOML: the defaults, or FILE and each --set merged over them
    (the resolved tree a command would use). Every value is checked first: a bad one is
    one line naming the key, the value and the accepted range (exit 3)."""
    typer.echo(clear_settings.settings_to_toml(bo.resolve_settings(settings, sets), ranges=ranges), nl=False)


def robots_cmd(
    name: Annotated[str | None, typer.Argument(help="A profile: print its facts.", metavar="[NAME]")] = None,
    json_out: Annotated[
        bool, typer.Option("--json", help="Machine-readable output (schema clear.robots, version 1).")
    ] = False,
) -> None:
    """List the robot profiles (--robot NAME, [robot] name), or print one's facts: its
    description, frames, reach, gripper, joints and the [robot]/[gripper] defaults it
    supplies."""
    from clearcli.tasks import robots as task  # noqa: PLC0415  (the task, ~7 ms: not for `clear --help`)

    payload = task.robots_payload(name)
    if json_out:
        print_json(task.SCHEMA, task.VERSION, payload, bo.resolve_settings(None, None), "robots")
        return
    if name is None:
        width = max(len(p["name"]) for p in payload["profiles"])
        for p in payload["profiles"]:
            typer.echo(f"{p['name']:{width}s}  {p['summary']}" + ("  (default)" if p["default"] else ""))
        return
    facts = payload["profile"]
    for key in (
        "name",
        "summary",
        "urdf",
        "base_frame",
        "flange_frame",
        "tcp_frame",
        "reach_m",
        "shoulder_base_m",
        "base_above_footprint_m",
        "gripper",
        "tools",
    ):
        typer.echo(f"{key:24s} {facts[key]}")
    typer.echo("joints (rad)")
    for j in facts["joints"]:
        typer.echo(f"  {j['name']:24s} {j['lower_rad']:+.4f} .. {j['upper_rad']:+.4f}")
    for section, values in facts["defaults"].items():
        typer.echo(f"[{section}] defaults")
        for k, v in values.items():
            typer.echo(f"  {k} = {v}")
