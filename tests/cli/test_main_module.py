"""``python -m clearcli``: the same program as the ``clear`` script, named ``clear`` in its
usage lines, with the same exit codes (clearcli/__main__.py)."""

from __future__ import annotations

import json
import subprocess
import sys

from helpers import REPO


def module(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "clearcli", *args], cwd=REPO, capture_output=True, text=True, timeout=300
    )


def test_python_m_clearcli_segments_a_fixture_as_the_script_does() -> None:
    out = module("segment", "fixtures/clutter10.pcd", "--json")
    assert out.returncode == 0, out.stderr
    assert len(json.loads(out.stdout)["objects"]) == 10


def test_python_m_clearcli_names_itself_clear_and_keeps_the_exit_codes() -> None:
    usage = module("--help")
    assert usage.returncode == 0
    assert usage.stdout.startswith("Usage: clear "), usage.stdout[:80]
    bad = module("plan", "fixtures/clutter10.pcd", "--set", "segment.voxel_m=nan")
    assert bad.returncode == 3, bad.stderr
    assert len(bad.stderr.strip().splitlines()) == 1
    assert "voxel_m = nan: out of range" in bad.stderr
    assert "Traceback" not in bad.stderr
