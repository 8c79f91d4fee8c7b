"""Seconds per named step of the segmentation: the one helper `segment()` and the
refinement stages are timed by (`Segmentation.timings_s`)."""

from __future__ import annotations

import time
from collections.abc import Iterable, Iterator
from contextlib import contextmanager


class Clock:
    """``with clock("name"):`` adds the seconds spent inside to ``timings["name"]`` (a
    name timed twice adds up). ``names`` are reported in that order, 0.0 until timed."""

    def __init__(self, names: Iterable[str] = ()) -> None:
        self.start = time.perf_counter()
        self.timings: dict[str, float] = dict.fromkeys(names, 0.0)

    @contextmanager
    def __call__(self, name: str) -> Iterator[None]:
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.timings[name] = self.timings.get(name, 0.0) + time.perf_counter() - t0

    def total(self, name: str, parts: Iterable[str]) -> None:
        """``timings[name]``: the sum of the steps ``parts`` (each also reported apart)."""
        self.timings[name] = sum(self.timings.get(p, 0.0) for p in parts)

    def elapsed(self) -> float:
        """Seconds since the clock was made."""
        return time.perf_counter() - self.start
