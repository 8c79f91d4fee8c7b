"""Options converted without pydantic (clearcli/commands/coercion.py) give what typer's own
conversion gives: the same value of the same type, or the same error, on every parameter
of every command."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import typer.main
from helpers import run_clear
from helpers.batch import hooked_env
from typer import _click
from typer._coercion import build_runtime_param

from clearcli.cli import make_app
from clearcli.commands.coercion import plain_converter

SAMPLES: list[Any] = [
    None, "", "0", "-0", "1", "-1", "7", "007", "+5", " 5", "1_000", "2.5", "-0.25", "0.10", "1e3", "inf", "nan",
    "abc", "x.pcd", "/tmp", "-", ".", "a\x00b", 0, 3, -2, 2.5, True, False, ["1", "a"], ("x.pcd", "y.pcd"),
    Path("z.pcd"), 10**30, "123456789012345678901234",
]  # fmt: skip


def _params() -> list[tuple[str, _click.Command, Any]]:
    out: list[tuple[str, _click.Command, Any]] = []

    def walk(command: _click.Command, name: str) -> None:
        out.extend((f"{name} {p.name}", command, p) for p in command.params if hasattr(p, "type_descriptor"))
        for sub_name, sub in getattr(command, "commands", {}).items():
            walk(sub, f"{name} {sub_name}")

    walk(typer.main.get_command(make_app()), "clear")
    return out


def _outcome(converter: Any, value: Any, param: Any, ctx: Any) -> tuple[Any, ...]:
    try:
        result = converter.coerce(value, param=param, ctx=ctx)
    except Exception as exc:
        return ("error", type(exc).__name__, str(exc))
    return ("value", type(result).__name__, repr(result))  # repr: nan equals nan


def test_every_parameter_converts_as_typer_does() -> None:
    params = _params()
    plain_kinds = 0
    for label, command, param in params:
        plain = plain_converter(param)
        if plain is None:
            continue
        plain_kinds += 1
        typers = build_runtime_param(param.type_descriptor)
        ctx = _click.Context(command, info_name="clear")
        for value in SAMPLES:
            expected = _outcome(typers, value, param, ctx)
            got = _outcome(plain, value, param, ctx)
            assert got == expected, f"{label} <- {value!r}"
    assert plain_kinds >= 80, "fewer plain parameters than the commands have: nothing much was checked"


def test_plain_values_are_converted_without_typers_converter() -> None:
    converted = {}
    for label, command, param in _params():
        plain = plain_converter(param)
        annotation = param.type_descriptor.annotation
        sample = {int: "3", float: "0.5", str: "abc", bool: True, Path: "x.pcd"}.get(annotation)
        if plain is None or sample is None:
            continue
        ctx = _click.Context(command, info_name="clear")
        converted[label] = plain.coerce(sample, param=param, ctx=ctx)
        assert plain._typer is None, f"{label}: typer's converter was built for {sample!r}"
    assert converted["clear plan frame_index"] == 3 and converted["clear segment settings_file"] == Path("x.pcd")


_HOOK = """
import atexit, json, os, sys
atexit.register(lambda: json.dump({"pydantic": "pydantic" in sys.modules}, open(os.environ["CLEAR_TEST_REPORT"], "w")))
"""


@pytest.mark.parametrize("args", [("schema", "plan"), ("settings",), ("--version",)])
def test_commands_without_a_pcd_do_not_import_pydantic(tmp_path: Path, args: tuple[str, ...]) -> None:
    report = tmp_path / "report.json"
    env = hooked_env(tmp_path, _HOOK)
    env["CLEAR_TEST_REPORT"] = str(report)
    res = run_clear(*args, timeout=120, env=env)
    assert res.returncode == 0 and res.stdout, res.stderr
    assert json.loads(report.read_text()) == {"pydantic": False}


def test_a_bad_value_gets_typers_message() -> None:
    res = run_clear("plan", "x.pcd", "--frame", "-1", timeout=120)
    assert res.returncode == 2
    assert "Invalid value for '--frame': Input should be greater than or equal to 0" in res.stderr
