"""`info`: what a PCD, MCAP log or bag holds; exit 9 when a log breaks after some frames."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from clearcli.errors import EXIT_PARTIAL
from clearcli.io.describe import describe_file, log_part
from clearcli.settings import Settings
from clearcli.tasks.base import NO_OUTPUTS, Outcome, Outputs, Source

SCHEMA, VERSION = "info", 1
OUTPUTS: tuple[str, ...] = ()


@dataclass(frozen=True)
class Request:
    outputs: Outputs = NO_OUTPUTS
    settings: Settings | None = None  # [images] only: how depth images are read


def run(request: Request, source: Source) -> Outcome:
    images = request.settings.images if request.settings is not None else None
    color = Path(source.color) if source.color is not None else None
    info = describe_file(Path(source.path), source.topic, source.index, images, color)
    log = log_part(info)
    return Outcome(SCHEMA, VERSION, info, 0 if log is None or log["complete"] else EXIT_PARTIAL)
