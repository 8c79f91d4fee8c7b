"""Behaviour is pinned: every golden document (tests/golden/goldens.py) is reproduced
exactly. A change meant to alter outputs re-records them (`python tests/golden/goldens.py
record`) in the same commit and summarises the diff in its note."""

from __future__ import annotations

import pytest
from golden import goldens
from helpers import shared_path

NEEDS_SHARED = {"mosd": "mosd/learn/learn0.pcd", "uois": "scenes/uois_realsense/uois_image_0000.pcd"}


@pytest.mark.parametrize("name", sorted(goldens.recorders()))
def test_golden_outputs_are_reproduced(name: str) -> None:
    for key, rel in NEEDS_SHARED.items():
        if name.endswith("_" + key):
            shared_path(rel)
    found = goldens.compare(name)
    assert not found, f"{name}: {len(found)} differences, first: " + "; ".join(found[:10])
