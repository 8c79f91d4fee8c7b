"""Shell completion (clearcli/cli.py: Typer's, on Click's): a completion request
registers every subcommand and completes its options."""

from __future__ import annotations

import os

from helpers import run_clear


def _complete(words: str, cword: int) -> list[str]:
    env = dict(os.environ, COMP_WORDS=words, COMP_CWORD=str(cword), _CLEAR_COMPLETE="complete_bash")
    res = run_clear(timeout=60, env=env)
    assert res.returncode == 0, res.stderr
    return res.stdout.split()


def test_subcommands_complete() -> None:
    assert _complete("clear pl", 1) == ["plan"]
    assert {"segment", "settings", "schema", "simulate"} <= set(_complete("clear s", 1))


def test_a_subcommands_options_complete() -> None:
    assert _complete("clear plan --gr", 2) == ["--grasps"]
    assert "--json" in _complete("clear segment --j", 2)


def test_the_script_for_a_shell_is_printed() -> None:
    res = run_clear("--show-completion", "bash", timeout=60)
    assert res.returncode == 0 and "_CLEAR_COMPLETE=complete_bash" in res.stdout, res.stderr
