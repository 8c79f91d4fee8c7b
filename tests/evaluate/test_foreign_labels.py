"""The hand-written labels of other labs' frames (benchmarks/foreign/*.toml) make sound
ground truth: every labelled object has points, each point belongs to one object, and
each frame is in the part it says (choose or report)."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest
from helpers import REPO, load_script, shared_path

LABELS = sorted((REPO / "benchmarks" / "foreign").glob("*.toml"))


def _tool():
    return load_script("benchmarks/foreign.py")


def test_there_is_a_choose_part_and_a_report_part() -> None:
    parts = [tomllib.loads(p.read_text(encoding="utf-8"))["part"] for p in LABELS]
    assert set(parts) == {"choose", "report"} and parts.count("report") >= 3


@pytest.mark.parametrize("label_file", LABELS, ids=[p.stem for p in LABELS])
def test_every_labelled_object_has_points(label_file: Path) -> None:
    spec = tomllib.loads(label_file.read_text(encoding="utf-8"))
    shared_path(spec["source"])  # skips (or fails under CLEAR_REQUIRE_SHARED) without the data
    frame, labels, spec = _tool().load(label_file.stem)
    assert labels.shape == (frame.n_points,)
    for k, obj in enumerate(spec["object"]):
        n = int((labels == 10 * (k + 1)).sum())
        assert n >= 50, f"{label_file.stem}: {obj['name']} has {n} points"
    # labels never sit on invalid (NaN) pixels
    assert not np.any((labels >= 10) & ~np.isfinite(frame.points).all(axis=1))
