"""Not a task: the schema names and versions of the tasks' documents that the commands'
help texts name, in a module that imports only clearcli/planning/versions.py (which
imports nothing). `clear --help` imports every command module, and `clear plan`'s help
names its document's version: read here, that costs ~1 ms; read from
clearcli/tasks/plan.py it would load the whole pipeline (~1 s) for a help text.
"""

from __future__ import annotations

from clearcli.planning.versions import PLAN_SCHEMA as PLAN_SCHEMA
from clearcli.planning.versions import PLAN_VERSION as PLAN_VERSION
