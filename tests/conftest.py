import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

# every JSON document clear writes in a test is validated against its schema (and counted)
from helpers.schemas import _documents_match_their_schemas, pytest_terminal_summary  # noqa: E402, F401


@pytest.fixture(autouse=True)
def _signal_handlers_restored():  # type: ignore[no-untyped-def]
    """`clearcli.cli.main` is a process's entry point and owns SIGINT/SIGTERM: when the
    command is over it makes them end the process at once (clearcli/interrupts.py
    `finish`). Tests that run it in this process must not leave that to the tests
    after them (a later test's Ctrl-C would end pytest itself)."""
    import signal

    saved = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    yield
    for s, handler in saved.items():
        if handler is not None:
            signal.signal(s, handler)
