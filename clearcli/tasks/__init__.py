"""The task layer: the commands' work, below the CLI and the batch.

A frame task (info, segment, predicates, plan, evaluate: `TASKS`) is one module with a
frozen ``Request`` (the resolved `Settings` inside, plus the command's own options),
``run(request, source) -> Outcome``, its ``SCHEMA``, ``VERSION`` and the ``OUTPUTS``
kinds it can write. `clearcli/commands/` parses flags into a request and prints the
outcome; `clearcli/batch/` runs the same ``run`` per frame in workers.

A session task (replay, simulate) has a frozen ``Request`` and its own ``run``: a whole
log, never batched. The other modules are no task, each says what it is: `base` (what
the tasks share), `sources` (a batch's frames), `domain` and `robots` (commands that
read no frame), `versions` (the schema versions the commands' help names).
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
