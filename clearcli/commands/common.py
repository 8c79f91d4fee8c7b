"""What every subcommand shares: reading a frame, settings, output files, JSON, consoles.

Only light imports here (typer, rich): `clear --help` must stay fast.
"""

from __future__ import annotations

import json
import sys
from typing import Any

from rich.console import Console

from clearcli.io.files import atomic_output, atomic_path, check_output_path  # noqa: F401  (re-exported)

JSON_SCHEMA_VERSION = 1

# Results go to stdout; logs, tables meant for people and progress go to stderr when
# stdout carries machine output.
stdout = Console(soft_wrap=True)
stderr = Console(stderr=True, soft_wrap=True)


def print_json(kind: str, payload: dict[str, Any], version: int = JSON_SCHEMA_VERSION) -> None:
    """One JSON document on stdout with the versioned envelope every command shares.
    Versions are per schema: a schema's version rises when a key is removed, renamed or
    changes meaning."""
    doc = {"schema": f"clear.{kind}", "version": version, **payload}
    sys.stdout.write(json.dumps(doc, separators=(",", ":"), allow_nan=False) + "\n")
    sys.stdout.flush()


