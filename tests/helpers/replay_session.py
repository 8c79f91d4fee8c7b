"""Helpers that several test modules share (from the tests of replay_session)."""

from __future__ import annotations

import json
import sys
from typing import Any

import pytest
from helpers.replay import simulated_session


def _clear_inprocess(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, *args: str
) -> tuple[int, str, str]:
    """The real entry point in this process (so that monkeypatched stages apply)."""
    from clearcli import cli

    monkeypatch.setattr(sys, "argv", ["clear", *args])
    with pytest.raises(SystemExit) as exit_info:
        cli.main()
    out, err = capsys.readouterr()
    code = exit_info.value.code
    return int(code or 0), out, err


def _lines(text: str) -> list[dict[str, Any]]:
    return [json.loads(line) for line in text.splitlines() if line.strip()]


@pytest.fixture(scope="module")
def sim_log(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """A simulated session in which an object is pushed (see replay_helpers)."""
    return simulated_session(tmp_path_factory.mktemp("sim"))
