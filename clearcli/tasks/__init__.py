"""The task layer: one module per frame command, below the CLI and the batch.

Each module has a frozen ``Request`` (the resolved `Settings` inside, plus the command's
own options), ``run(request, source) -> Outcome``, its ``SCHEMA``, ``VERSION`` and the
``OUTPUTS`` kinds it can write. `clearcli/commands/` parses flags into a request and
prints the outcome; `clearcli/batch/` runs the same ``run`` per frame in workers.
"""

from __future__ import annotations

from importlib import import_module
from types import ModuleType

TASKS: dict[str, str] = {
    "info": "clearcli.tasks.info",
    "segment": "clearcli.tasks.segment",
    "predicates": "clearcli.tasks.predicates",
    "plan": "clearcli.tasks.plan",
    "evaluate": "clearcli.tasks.evaluate",
}


def load(command: str) -> ModuleType:
    """The task module of ``command`` (imported on first use: start-up stays cheap)."""
    return import_module(TASKS[command])
