"""Which `clear` made a result, with which settings, and the one JSON envelope.

Every JSON document and batch line carries ``"clear": {"version", "source",
"settings_digest"}``: the package version, the source identity (``git <commit>`` when run
from a checkout, with ``+dirty`` never guessed: a checkout's commit is what can be
checked out again; ``package <version>`` otherwise) and a digest of the resolved settings
sections the command reads (clearcli/settings/tree.py `READS`). These keys are added to
every schema without changing its version.
"""

from __future__ import annotations

import functools
import json
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from clearcli import __version__, interrupts
from clearcli.settings import READS, digest

if TYPE_CHECKING:
    from clearcli.settings import Settings


def _git_commit(start: Path) -> str | None:
    """The commit HEAD names in the checkout holding ``start``, read from .git's files
    (no `git` process: this runs on every call)."""
    for folder in (start, *start.parents):
        git = folder / ".git"
        if git.is_file():  # a worktree: "gitdir: PATH"
            text = git.read_text(encoding="utf-8").strip()
            if not text.startswith("gitdir:"):
                return None
            git = (folder / text.split(":", 1)[1].strip()).resolve()
        if not git.is_dir():
            continue
        try:
            head = (git / "HEAD").read_text(encoding="utf-8").strip()
            if not head.startswith("ref:"):
                return head
            ref = head.split(":", 1)[1].strip()
            common = git
            if (git / "commondir").is_file():
                common = (git / (git / "commondir").read_text(encoding="utf-8").strip()).resolve()
            for base in (git, common):
                if (base / ref).is_file():
                    return (base / ref).read_text(encoding="utf-8").strip()
            packed = common / "packed-refs"
            if packed.is_file():
                for line in packed.read_text(encoding="utf-8").splitlines():
                    if line.endswith(" " + ref):
                        return line.split(" ", 1)[0]
        except OSError:
            return None
        return None
    return None


@functools.lru_cache(maxsize=1)
def source_identity() -> str:
    commit = _git_commit(Path(__file__).resolve().parent)
    return f"git {commit}" if commit else f"package {__version__}"


def stamp(settings: Settings | None, command: str) -> dict[str, Any]:
    """The ``clear`` object of a document made by ``command`` with ``settings``."""
    sections = READS.get(command, ())
    return {
        "version": __version__,
        "source": source_identity(),
        "settings_digest": digest(settings, sections) if settings is not None and sections else None,
    }


def envelope(schema: str, version: int, payload: Mapping[str, Any], made_by: Mapping[str, Any]) -> dict[str, Any]:
    """The one JSON envelope: ``{"schema": "clear.<schema>", "version", "clear", ...payload}``.
    A schema's version rises when a key is removed, renamed or changes meaning."""
    return {"schema": f"clear.{schema}", "version": version, "clear": dict(made_by), **payload}


def dumps(doc: Mapping[str, Any]) -> str:
    return json.dumps(doc, separators=(",", ":"), allow_nan=False)


def print_document(doc: Mapping[str, Any]) -> None:
    """One document as one line on stdout."""
    print_line(dumps(doc))


def print_line(text: str) -> None:
    """One line on stdout, whole: Ctrl-C or SIGTERM while it is written (a plan document
    is tens of kilobytes, written in several pieces into a pipe) is raised after its
    newline, so a script reading the lines never gets half of one."""
    with interrupts.deferred():
        out = sys.stdout
        buf = getattr(out, "buffer", None)
        if buf is None:  # a replaced stdout (a test's capture): text as is
            out.write(text + "\n")
            out.flush()
            return
        out.flush()
        # A signal that interrupts the write of a large line into a full pipe makes the
        # binary buffer return short, and the text layer above it drops the rest without
        # a word (seen: a 2 MB line cut at 64 KiB). Write the bytes until all are out.
        view = memoryview((text + "\n").encode("utf-8"))
        while view:
            n = buf.write(view)
            view = view[n if n is not None else 0 :]
        buf.flush()
