"""What every subcommand shares: consoles, printing a document, output paths.

Only light imports here (typer, rich): `clear --help` must stay fast.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from clearcli.console import stderr, stdout  # noqa: F401  (re-exported)
from clearcli.files import atomic_output, atomic_path, check_output_path  # noqa: F401  (re-exported)


def print_json(schema: str, version: int, payload: Mapping[str, Any], settings: Any, command: str) -> None:
    """One JSON document on stdout in the shared envelope, with its provenance."""
    from clearcli.provenance import envelope, print_document, stamp

    print_document(envelope(schema, version, payload, stamp(settings, command)))
