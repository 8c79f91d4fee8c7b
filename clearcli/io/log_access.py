"""The log interface: what a reader that pairs messages of several topics (a depth image
with its camera info and its colour: clearcli/io/mcap_images.py) asks of a log, whatever
its format. MCAP logs (`clearcli.io.mcap.McapAccess`) and ROS bags
(`clearcli.io.rosbag.BagAccess`) offer it; the readers that use it import this module,
never each other.
"""

from __future__ import annotations

from collections.abc import Generator
from pathlib import Path
from typing import Any, Protocol

# (schema or type name, decoded message, log time ns)
Decoded = tuple[str, Any, int]


class LogSummary(Protocol):
    """What a log holds, as far as a paired reader needs it (`McapSummary`, `BagSummary`)."""

    @property
    def path(self) -> Path: ...

    @property
    def damage(self) -> str | None: ...

    def topics(self) -> list[tuple[str, str]]:
        """(topic, schema name) once per topic."""
        ...

    def image_topics(self) -> list[str]: ...

    def count(self, topic: str) -> int: ...


class LogAccess(Protocol):
    """A log's decoded messages by topic."""

    @property
    def path(self) -> Path: ...

    @property
    def summary(self) -> LogSummary: ...

    @property
    def can_seek(self) -> bool:
        """Whether `window` may be used (the log is indexed)."""
        ...

    def decoded(self, topic: str) -> Generator[Decoded, None, None]:
        """(schema name, message, log time ns) of every message of ``topic`` in log
        order, up to any damage (it ends there quietly)."""
        ...

    def window(self, topic: str, start_ns: int, end_ns: int) -> Generator[Decoded, None, None]:
        """The same for the messages logged in [start_ns, end_ns], found through the index."""
        ...
