"""`info`: what a PCD, MCAP log or bag holds; exit 9 when a log breaks after some frames."""

from __future__ import annotations

from dataclasses import dataclass

from clearcli.tasks.base import NO_OUTPUTS, Outcome, Outputs, Source

SCHEMA, VERSION = "info", 1
OUTPUTS: tuple[str, ...] = ()


@dataclass(frozen=True)
class Request:
    outputs: Outputs = NO_OUTPUTS
    settings: None = None  # info reads no settings


def run(request: Request, source: Source) -> Outcome:
    from clearcli.errors import EXIT_PARTIAL
    from clearcli.io.describe import describe_file, log_part

    info = describe_file(source.path, source.topic, source.index)
    log = log_part(info)
    return Outcome(SCHEMA, VERSION, info, 0 if log is None or log["complete"] else EXIT_PARTIAL)
