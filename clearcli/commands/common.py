"""What every subcommand shares: consoles, printing a document, output paths.

Only light imports here (typer, rich): `clear --help` must stay fast.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from clearcli.console import print_table, stderr, stdout
from clearcli.files import atomic_output, atomic_path, check_output_path

__all__ = ["atomic_output", "atomic_path", "check_output_path", "print_json", "print_table", "stderr", "stdout"]


def print_json(schema: str, version: int, payload: Mapping[str, Any], settings: Any, command: str) -> None:
    """One JSON document on stdout in the shared envelope, with its provenance."""
    # provenance loads the settings tree (~50 ms), which `clear --help` never needs
    from clearcli.provenance import envelope, print_document, stamp  # noqa: PLC0415  (~50 ms: --json only)

    print_document(envelope(schema, version, payload, stamp(settings, command)))
