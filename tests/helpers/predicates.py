"""Helpers that several test modules share (from the tests of predicates)."""

from __future__ import annotations

from clearcli.predicates.state import SymbolicState
from clearcli.predicates.state_builder import compute_state
from clearcli.predicates.synthetic import Box, make_scene
from clearcli.settings import Settings

BOX = (0.10, 0.05, 0.05)  # graspable: 5 cm across its closing direction


def state_of(boxes: list[Box], settings: Settings | None = None, **kw) -> SymbolicState:
    frame, seg = make_scene(boxes, **kw)
    return compute_state(frame, seg, settings or Settings())


def by_segment(state: SymbolicState) -> dict[int, str]:
    """segment index (= position in the boxes list) -> object name."""
    return {o.segment_index: o.name for o in state.objects}
