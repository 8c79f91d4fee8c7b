"""The files a batch writes beside its outputs (``<name>.json``, the mark that a frame
is done: clearcli/batch/run.py) against the batch schema: each is the frame's stdout
line without its two envelope keys (``schema``, ``version``), whole."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from helpers.schemas import SchemaMismatch, validate_document

REPO = Path(__file__).resolve().parents[2]


def _batch(tmp_path: Path) -> tuple[list[dict], dict[str, dict]]:
    out = tmp_path / "out"
    res = subprocess.run(
        [sys.executable, "-m", "clearcli.cli", "segment", "fixtures/clutter10.pcd", "fixtures/isolated_box.pcd"]
        + ["--out-dir", str(out), "--json"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert res.returncode == 0, res.stderr
    lines = [json.loads(x) for x in res.stdout.splitlines() if x.startswith("{")]
    marks = {p.stem: json.loads(p.read_text()) for p in out.glob("*.json")}
    return lines, marks


def test_every_mark_a_batch_writes_is_its_frame_line_and_validates(tmp_path: Path) -> None:
    lines, marks = _batch(tmp_path)
    frames = {x["name"]: x for x in lines if x.get("type") == "frame"}
    assert set(marks) == set(frames) == {"clutter10", "isolated_box"}
    for name, mark in marks.items():
        line = frames[name]
        assert {"schema": line["schema"], "version": line["version"], **mark} == line
        validate_document({"schema": line["schema"], "version": line["version"], **mark}, f"{name}.json")
        broken = {"schema": line["schema"], "version": line["version"], **mark}
        broken["document"] = {**broken["document"], "objects": "none"}
        with pytest.raises(SchemaMismatch):
            validate_document(broken, f"{name}.json, broken")
