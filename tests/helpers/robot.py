"""Helpers that several test modules share (from the tests of robot)."""

from __future__ import annotations

import numpy as np
import pytest

from clearcli.robot.wam_kinematics import WamKinematics


@pytest.fixture(scope="module")
def kin() -> WamKinematics:
    return WamKinematics()


def _trans(x: float, y: float, z: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = [x, y, z]
    return T
