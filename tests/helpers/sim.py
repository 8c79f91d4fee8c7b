"""Helpers that several test modules share (from the tests of sim)."""

from __future__ import annotations

import pytest

from clearcli.sim import scene as S

H, W = 480, 640


@pytest.fixture(scope="module")
def clutter_scene() -> S.Scene:
    return S.clutter(10, seed=3)
