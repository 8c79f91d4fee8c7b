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


def _git_dir(start: Path) -> tuple[Path, Path] | None:
    """(the work tree's root, its git directory) of the checkout holding ``start``, or
    None outside one. A linked work tree's ``.git`` is a file naming its git directory."""
    for folder in (start, *start.parents):
        git = folder / ".git"
        try:
            if git.is_file():  # a worktree: "gitdir: PATH"
                text = git.read_text(encoding="utf-8").strip()
                if not text.startswith("gitdir:"):
                    return None
                git = (folder / text.split(":", 1)[1].strip()).resolve()
        except OSError:
            return None
        if git.is_dir():
            return folder, git
    return None


def _git_commit(start: Path) -> str | None:
    """The commit HEAD names in the checkout holding ``start``, read from .git's files
    (no `git` process: this runs on every call)."""
    found = _git_dir(start)
    if found is None:
        return None
    git = found[1]
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


# `clear --version` gives up reading the work tree after this long and says +dirty: a
# clean claim must be true (a commit is what can be checked out again)
DIRTY_CHECK_BUDGET_S = 1.0


def _git_dirty(root: Path, git: Path, budget_s: float = DIRTY_CHECK_BUDGET_S) -> bool:
    """Whether a file git tracks differs in the work tree from the index (changed,
    deleted, unmerged), as `git describe --dirty` sees it, read from .git/index (format
    versions 2 to 4) without a `git` process: a file whose size and modification time
    match its entry is unchanged (git's own rule); one whose time differs is hashed as a
    blob and compared. Untracked files do not count (as for git). Not seen: changes
    staged and not committed while the work tree matches the index, and files whose
    content git filters (line endings, LFS). An index it cannot read, a SHA-256
    repository, or a work tree larger than ``budget_s`` can check counts as dirty."""
    import hashlib  # noqa: PLC0415  (--version only)
    import os  # noqa: PLC0415
    import stat as st  # noqa: PLC0415
    import struct  # noqa: PLC0415
    import time  # noqa: PLC0415

    deadline = time.monotonic() + budget_s
    try:
        index_path = git / "index"
        data = index_path.read_bytes()
        index_mtime = index_path.stat().st_mtime
    except OSError:
        return True
    if len(data) < 12 or data[:4] != b"DIRC":
        return True
    version, count = struct.unpack(">II", data[4:12])
    if version not in (2, 3, 4):
        return True
    pos, previous = 12, b""
    for _ in range(count):
        if time.monotonic() > deadline:
            return True
        if pos + 62 > len(data):
            return True
        _, _, mtime_s, mtime_ns, _, _, mode, _, _, size = struct.unpack(">10I", data[pos : pos + 40])
        sha = data[pos + 40 : pos + 60]
        (flags,) = struct.unpack(">H", data[pos + 60 : pos + 62])
        start, p = pos, pos + 62
        skip = bool(flags & 0x8000)  # assume-valid
        if flags & 0x4000:  # extended flags (version 3+): skip-worktree, intent-to-add
            (extended,) = struct.unpack(">H", data[p : p + 2])
            skip = skip or bool(extended & 0x4000)
            p += 2
        if version == 4:  # the path: drop N bytes of the previous one, add a NUL-ended suffix
            byte = data[p]
            p += 1
            strip = byte & 0x7F
            while byte & 0x80:  # git's offset varint (varint.c)
                byte = data[p]
                p += 1
                strip = ((strip + 1) << 7) | (byte & 0x7F)
            end = data.index(b"\0", p)
            name = previous[: len(previous) - strip] + data[p:end]
            pos = end + 1
        else:
            end = data.index(b"\0", p)
            name = data[p:end]
            pos = start + ((end - start) // 8 + 1) * 8  # NUL-padded to a multiple of 8
        previous = name
        if (flags >> 12) & 0x3:
            return True  # an unmerged path
        if skip or st.S_IFMT(mode) == 0o160000:  # a submodule: its own checkout
            continue
        path = root / os.fsdecode(name)
        try:
            info = path.lstat()
        except OSError:
            return True  # deleted
        # git "smudges" an entry it wrote racily clean by setting its size to 0: hash it
        if (info.st_size & 0xFFFFFFFF) != size and size != 0:
            return True
        same_time = int(info.st_mtime) == mtime_s and info.st_mtime_ns % 1_000_000_000 == mtime_ns
        if same_time and (info.st_size & 0xFFFFFFFF) == size and info.st_mtime < int(index_mtime):
            continue  # not "racily clean": a change would have changed its time
        try:
            body = os.readlink(path).encode() if st.S_ISLNK(info.st_mode) else path.read_bytes()
        except OSError:
            return True
        if hashlib.sha1(b"blob %d\0" % len(body) + body, usedforsecurity=False).digest() != sha:
            return True
    return False


def version_line() -> str:
    """What `clear --version` prints: ``clear <version>``, and from a checkout the commit
    it runs (``clear 0.1.0 (commit dc5f6f5)``, ``+dirty`` when a tracked file differs
    from it). A wheel installed outside a checkout says the version alone."""
    here = Path(__file__).resolve().parent
    found = _git_dir(here)
    commit = _git_commit(here) if found is not None else None
    if found is None or not commit:
        return f"clear {__version__}"
    dirty = "+dirty" if _git_dirty(*found) else ""
    return f"clear {__version__} (commit {commit[:7]}{dirty})"


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
