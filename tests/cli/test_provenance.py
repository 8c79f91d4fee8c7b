"""Results say how they were made: version, source and settings digest on every
document and batch line; --out-dir keeps the settings; --resume refuses other ones."""

from __future__ import annotations

import json
from pathlib import Path

from helpers import FIXTURES
from helpers import run_clear as clear

FRAMES = [FIXTURES / n for n in ("isolated_box.pcd", "box_on_box.pcd")]


def _made_by(doc: dict) -> dict:
    made = doc["clear"]
    assert set(made) == {"version", "source", "settings_digest"}
    assert made["source"].startswith(("git ", "package "))
    return made


def test_single_document_says_which_clear_and_settings_made_it() -> None:
    a = json.loads(clear("segment", FRAMES[0], "--json").stdout)
    b = json.loads(clear("segment", FRAMES[0], "--json", "--set", "segment.voxel_m=0.006").stdout)
    c = json.loads(clear("segment", FRAMES[0], "--json", "--set", "plan.time_limit_s=5").stdout)
    assert a["schema"] == "clear.segmentation" and a["version"] == 3
    assert _made_by(a)["settings_digest"] != _made_by(b)["settings_digest"]
    # segment reads [segment] only: a [plan] change leaves its digest alone
    assert _made_by(a)["settings_digest"] == _made_by(c)["settings_digest"]


def test_batch_lines_and_their_documents_carry_provenance() -> None:
    proc = clear("plan", *FRAMES, "--json", "--jobs", "1")
    lines = [json.loads(x) for x in proc.stdout.splitlines()]
    assert [x["type"] for x in lines] == ["frame", "frame", "summary"]
    for line in lines:
        assert line["schema"] == "clear.batch"
        _made_by(line)
    for line in lines[:2]:
        assert _made_by(line["document"]) == _made_by(line)


def test_out_dir_keeps_the_settings_and_resume_refuses_other_ones(tmp_path: Path) -> None:
    out = tmp_path / "out"
    first = clear("segment", *FRAMES, "--out-dir", out, "--json", "--jobs", "1")
    assert first.returncode == 0, first.stderr
    record = (out / "settings.toml").read_text()
    assert "voxel_m = 0.005" in record and "clear segment" in record
    marks = {p.name: p.stat().st_mtime_ns for p in out.glob("*.json")}
    assert len(marks) == 2

    other = clear("segment", *FRAMES, "--out-dir", out, "--resume", "--set", "segment.voxel_m=0.006")
    assert other.returncode == 3
    assert len(other.stderr.strip().splitlines()) == 1 and "settings.toml" in other.stderr
    assert (out / "settings.toml").read_text() == record

    same = clear("segment", *FRAMES, "--out-dir", out, "--resume", "--json", "--jobs", "1")
    assert same.returncode == 0
    assert json.loads(same.stdout.splitlines()[-1])["resumed"] == 2

    # --resume --force redoes the frames made otherwise and keeps the rest
    (out / "isolated_box.json").write_text(
        (out / "isolated_box.json").read_text().replace('"settings_digest":"sha256:', '"settings_digest":"sha256:0')
    )
    forced = clear("segment", *FRAMES, "--out-dir", out, "--resume", "--force", "--json", "--jobs", "1")
    assert forced.returncode == 0, forced.stderr
    summary = json.loads(forced.stdout.splitlines()[-1])
    assert (summary["done"], summary["resumed"]) == (1, 1)
