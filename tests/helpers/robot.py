"""Helpers that several test modules share (from the tests of robot)."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

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


def rotation_angle(Ra: np.ndarray, Rb: np.ndarray) -> float:
    """The angle (rad) of the rotation between two rotation matrices."""
    return float(np.arccos(np.clip((np.trace(Ra.T @ Rb) - 1.0) / 2.0, -1.0, 1.0)))


def solved_on_their_poses(
    kin: Any, poses: Iterable[np.ndarray], position_m: float, angle_rad: float, slack: float
) -> int:
    """How many of ``poses`` the IK of ``kin`` solves; every solution within the joint
    limits (at most ``slack`` past them) and landing on its pose by forward kinematics
    within ``position_m`` and ``angle_rad``."""
    solved = 0
    for T in poses:
        q = kin.ik(T)
        if q is None:
            continue
        solved += 1
        assert np.all(q >= kin.lower - slack) and np.all(q <= kin.upper + slack)
        got = kin.fk(q)
        assert np.linalg.norm(got[:3, 3] - T[:3, 3]) < position_m
        assert rotation_angle(got[:3, :3], T[:3, :3]) < angle_rad
    return solved
