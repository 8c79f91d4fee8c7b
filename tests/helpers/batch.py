"""Helpers that several test modules share (from the tests of batch)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

from helpers import FIXTURES

FRAMES = [FIXTURES / n for n in ("isolated_box.pcd", "two_touching_boxes.pcd", "box_on_box.pcd", "clutter10.pcd")]


def clear(*args: Any, env: dict[str, str] | None = None, timeout: float = 600) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "clearcli.cli", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
    )


def hooked_env(folder: Path, code: str) -> dict[str, str]:
    """The environment of a `clear` whose Python runs ``code`` first (a sitecustomize.py
    in ``folder``/hook, on PYTHONPATH): a test's way into the child's modules."""
    hook = folder / "hook"
    hook.mkdir()
    (hook / "sitecustomize.py").write_text(code)
    # the caller's PYTHONPATH kept after it: a checkout run that way is the one tested
    return dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in (str(hook), os.environ.get("PYTHONPATH")) if p))


def lines_of(out: str) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    rows = [json.loads(x) for x in out.splitlines() if x.strip()]
    assert all(r["schema"] == "clear.batch" for r in rows)
    assert rows[-1]["type"] == "summary" and all(r["type"] == "frame" for r in rows[:-1])
    return rows[:-1], rows[-1]


def comparable(doc: dict[str, Any]) -> dict[str, Any]:
    """A document without what differs between two runs of the same frame (timings)."""
    doc = {k: v for k, v in doc.items() if k != "timings_s"}
    if "steps" in doc:  # the plan's trace: its search timings ride along nowhere else
        doc["backtracking"] = [{k: v for k, v in b.items()} for b in doc["backtracking"]]
    return doc
