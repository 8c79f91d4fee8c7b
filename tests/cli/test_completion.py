"""Shell completion (clearcli/cli.py: Typer's, on Click's): a completion request
registers every subcommand and completes its options."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def _complete(words: str, cword: int) -> list[str]:
    env = dict(os.environ, COMP_WORDS=words, COMP_CWORD=str(cword), _CLEAR_COMPLETE="complete_bash")
    res = subprocess.run(
        [sys.executable, "-c", "import sys; sys.argv[0] = 'clear'; from clearcli.cli import main; main()"],
        env=env,
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert res.returncode == 0, res.stderr
    return res.stdout.split()


def test_subcommands_complete() -> None:
    assert _complete("clear pl", 1) == ["plan"]
    assert {"segment", "settings", "schema", "simulate"} <= set(_complete("clear s", 1))


def test_a_subcommands_options_complete() -> None:
    assert _complete("clear plan --gr", 2) == ["--grasps"]
    assert "--json" in _complete("clear segment --j", 2)


def test_the_script_for_a_shell_is_printed() -> None:
    res = subprocess.run(
        [sys.executable, "-c", "import sys; sys.argv[0] = 'clear'; from clearcli.cli import main; main()"]
        + ["--show-completion", "bash"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert res.returncode == 0 and "_CLEAR_COMPLETE=complete_bash" in res.stdout, res.stderr
