"""Helpers that several test modules share (from the tests of segment)."""

from __future__ import annotations

import pytest

from clearcli.io.frames import Frame
from clearcli.settings.segment import SegmentSettings

S = SegmentSettings()


def _render(scene, floor: bool = False) -> Frame:  # type: ignore[no-untyped-def]
    from clearcli.sim.camera import render

    return render(scene, seed=0, floor=floor)


@pytest.fixture(scope="module")
def box_frame() -> Frame:
    from clearcli.sim.scene import isolated_box

    return _render(isolated_box())
