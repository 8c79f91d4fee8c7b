"""Tests of clearcli/perception/fragments.py."""

from __future__ import annotations

from dataclasses import replace

from helpers.families import S, _right

from clearcli.sim.camera import render
from clearcli.sim.families import FAMILIES
from clearcli.sim.scene import Box, make_scene


def test_fragments_of_a_face_seen_edge_on_join_their_object() -> None:
    """small_against_tall(73): the tall box's side, seen edge-on, thinned to strips by
    the outlier filter; joined with the stage, an extra object without it. A small box
    standing 1 cm from a tall one has a top: never a fragment."""
    frame = render(FAMILIES["small_against_tall"](73), seed=73)
    assert _right(frame)
    assert not _right(frame, replace(S, fragment_join_m=0.0))
    apart = make_scene(
        "apart", [Box(0, 0.10, 0.08, 0.20, x_m=0.0, y_m=0.05), Box(1, 0.04, 0.04, 0.05, x_m=0.0, y_m=-0.02)]
    )
    for seed in range(3):
        assert _right(render(apart, seed=seed))
