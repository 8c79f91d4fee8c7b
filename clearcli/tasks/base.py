"""Not a task: what every task shares: where a frame comes from (`Source`), what a task
gives back (`Outcome`), where its outputs go (`Outputs`, `OUTPUT_FILES`).

A task is one command's work on one frame: ``run(request, source) -> Outcome``. The
request is frozen and plain (picklable: a batch sends it to worker processes and Ray
workers), with the resolved `Settings` inside, built and checked once by the caller. A
single call and a batch worker call the same ``run``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

# The file each output kind is written to in a batch's --out-dir.
OUTPUT_FILES: dict[str, str] = {
    "labels": "{name}.labels.pcd",
    "problem": "{name}.problem.pddl",
    "domain": "{name}.domain.pddl",
    "plan": "{name}.plan",
    "png": "{name}.png",
}


@dataclass(frozen=True)
class Source:
    """One frame: a file (PCD, MCAP, bag, depth image), the frame's index on its topic,
    the name its outputs take in a batch, and a depth image's colour image when named
    (--color; else the naming rule pairs one)."""

    path: str | Path  # as named (the commands and the batch pass it as text)
    index: int = 0
    topic: str | None = None
    name: str = ""
    color: str | None = None


@dataclass(frozen=True)
class Outcome:
    """One frame's result: its document (schema, version, payload), the exit code a
    single call gives for it, and the files written."""

    schema: str
    version: int
    payload: Mapping[str, Any]
    exit_code: int = 0
    written: tuple[Path, ...] = ()
    # what the work made beyond the document (the frame, the segmentation, the state), for
    # the Python API's arrays (clearcli/api.py); only when the request asks (``keep``), so
    # a batch never sends it between processes
    kept: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Outputs:
    """Where a frame's outputs go, by kind (None: not written)."""

    paths: tuple[tuple[str, Path], ...] = ()

    @staticmethod
    def of(**given: Path | None) -> Outputs:
        return Outputs(tuple((k, Path(v)) for k, v in given.items() if v is not None))

    def get(self, kind: str) -> Path | None:
        for k, p in self.paths:
            if k == kind:
                return p
        return None

    def all(self) -> tuple[Path, ...]:
        return tuple(p for _, p in self.paths)


NO_OUTPUTS = Outputs()
