"""What a file holds, as the payload of schema ``clear.info`` (documented in
`clearcli/commands/info.py`): a PCD's header, a log's or bag's channels, one frame's
points, fields and bounds. Each format describes its own files (`describe` of
clearcli/io/formats/); the frame part is `describe_frame`."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from clearcli.io.formats import check_color, format_of
from clearcli.io.formats.base import describe_frame

__all__ = ["describe_file", "describe_frame", "log_part"]


def describe_file(
    path: Path, topic: str | None = None, index: int = 0, images: Any = None, color: Path | None = None
) -> dict[str, Any]:
    """The info payload (without envelope) for `path`; raises ClearError on bad input.

    A damaged MCAP log or bag is described (mcap/bag.complete false) without raising; the
    caller decides what exit code that deserves.
    """
    path = Path(path)
    fmt = format_of(path)
    check_color(fmt, path, color)  # the reader checks --frame
    return fmt.describe(path, topic, index, images, color)


def log_part(info: dict[str, Any]) -> dict[str, Any] | None:
    """The `mcap` or `bag` object of an info payload (None for a PCD)."""
    return info.get("mcap") or info.get("bag")
