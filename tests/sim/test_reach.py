"""Tests of clearcli/sim/reach.py."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clearcli.settings.geometry import GripperSettings, PushSettings
from clearcli.sim import scene as S


def _reach():  # type: ignore[no-untyped-def]
    from clearcli.sim.reach import WorldReach

    # the robot's shoulder 0.55 m before the table's centre, 0.25 m above its top
    T_base_table = np.eye(4)
    T_base_table[:3, 3] = (0.55, 0.0, -0.25)
    return WorldReach(T_base_table, GripperSettings(), PushSettings())


def test_world_accepts_a_grasp_in_front_of_the_arm_and_fk_confirms_it() -> None:
    reach = _reach()
    box = S.Box(0, 0.05, 0.04, 0.08, x_m=0.05, y_m=0.1, yaw_rad=0.3)
    assert reach.why_not(box) == ""
    motion = reach.grasp_motion(box)
    assert motion is not None
    T_base_tcp, q = motion
    assert np.all(q >= reach.kin.lower - 1e-9) and np.all(q <= reach.kin.upper + 1e-9)
    T_fk = reach.kin.fk(q)
    assert np.linalg.norm(T_fk[:3, 3] - T_base_tcp[:3, 3]) < 0.002
    assert np.allclose(T_fk[:3, :3], T_base_tcp[:3, :3], atol=0.02)
    # the grasp point: the box's top centre, half the closing region down, in the base frame
    expected = reach.T_base_table @ np.array([0.05, 0.1, 0.08 - 0.0225, 1.0])
    assert np.allclose(T_base_tcp[:3, 3], expected[:3], atol=1e-9)
    # the gripper points down and closes across the 4 cm side (yaw 0.3 + 90 deg)
    assert T_base_tcp[2, 2] == pytest.approx(-1.0)
    closing = T_base_tcp[:2, 0]
    assert abs(float(closing @ np.array([-math.sin(0.3), math.cos(0.3)]))) == pytest.approx(1.0, abs=1e-9)


def test_world_rejects_what_the_arm_cannot_reach_or_the_gripper_cannot_hold() -> None:
    reach = _reach()
    # 1.0 m from the shoulder on the table: beyond the tool plate's 0.915 m
    far = S.Box(0, 0.05, 0.05, 0.08, x_m=0.45, y_m=0.0)
    assert reach.why_not(far) == "no arm motion reaches a top-down grasp of it"
    assert reach.grasp_motion(far) is None
    # 9 x 9 cm: wider than the 7 cm opening whichever way it closes
    wide = S.Box(0, 0.09, 0.09, 0.08, x_m=0.0, y_m=0.0)
    assert "cannot hold" in reach.why_not(wide)
    # and on a scene: one reachable, one not
    scene = S.make_scene("two", [S.Box(0, 0.05, 0.05, 0.08, x_m=0.0, y_m=0.0), far])
    assert reach.reachable(scene, 0) and not reach.reachable(scene, 1)
