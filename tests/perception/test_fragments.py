"""Tests of clearcli/perception/fragments.py."""

from __future__ import annotations

from dataclasses import replace

import pytest
from helpers.families import S, _right

from clearcli.sim.camera import render
from clearcli.sim.families import FAMILIES
from clearcli.sim.scene import Box, make_scene


@pytest.mark.xfail(
    strict=True,
    reason="since the voxel grid's boundaries left the whole millimetre (issue 37, 6a58839) small_against_tall(73) "
    "comes out right without the fragments stage too, and no seed of 60-119 shows the effect: the stage needs a new case",
)
def test_without_the_fragments_stage_the_face_seen_edge_on_is_an_extra_object() -> None:
    frame = render(FAMILIES["small_against_tall"](73), seed=73)
    assert not _right(frame, replace(S, fragment_join_m=0.0))


def test_fragments_of_a_face_seen_edge_on_join_their_object() -> None:
    """small_against_tall(73): the tall box's side, seen edge-on, thinned to strips by
    the outlier filter; joined with the stage, an extra object without it. A small box
    standing 1 cm from a tall one has a top: never a fragment."""
    frame = render(FAMILIES["small_against_tall"](73), seed=73)
    assert _right(frame)
    apart = make_scene(
        "apart", [Box(0, 0.10, 0.08, 0.20, x_m=0.0, y_m=0.05), Box(1, 0.04, 0.04, 0.05, x_m=0.0, y_m=-0.02)]
    )
    for seed in range(3):
        assert _right(render(apart, seed=seed))
