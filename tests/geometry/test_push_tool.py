"""The push of a tool with a cup and no fingers (issue 36): the cup and its body push,
not the Franka Hand's fingers (clearcli/geometry/gripper.py `push_tool_model`)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.geometry import BOX, one_box

from clearcli.geometry.gripper import cup_pusher_model, gripper_model, push_contact_halves, push_tool_model
from clearcli.settings import load_settings


def test_a_tool_with_fingers_pushes_with_them_and_a_cup_alone_with_the_cup() -> None:
    for name in ("wam", "panda", "panda-hybrid"):
        s = load_settings(None, [f"robot.name={name}"])
        # the very model the fingers' pushes always used: their outputs cannot change
        assert push_tool_model(s.gripper, s.suction, ("fingers",)) is gripper_model(s.gripper)
        assert push_tool_model(s.gripper, s.suction, ("fingers", "cup")) is gripper_model(s.gripper)
    s = load_settings(None, ["robot.name=panda-suction"])  # an EPick: 30 mm cup, 4 cm stem, body r 4 cm
    cup = push_tool_model(s.gripper, s.suction, ("cup",))
    assert cup is cup_pusher_model(s.gripper, s.suction)
    part = cup.push_contact
    assert (part.tip_z_m, part.half_x_m, part.half_y_m, part.band_m) == pytest.approx((0.027, 0.015, 0.015, 0.04))
    # two boxes round the two cylinders: the cup and stem from the lip back 4 cm, the
    # body 9 cm behind it; open and closed alike
    boxes = cup.collision_boxes(closed=True)
    assert np.allclose(boxes.centers, [[0, 0, 0.027 - 0.02], [0, 0, 0.027 - 0.04 - 0.045]])
    assert np.allclose(boxes.half_extents, [[0.015, 0.015, 0.02], [0.04, 0.04, 0.045]])
    assert cup.collision_boxes(closed=False) is boxes
    # the world's contact: the cup's radius both ways, whatever the yaw
    x, d = np.array([1.0, 0.0]), np.array([0.0, 1.0])
    assert push_contact_halves(cup, x, d) == push_contact_halves(cup, x, x) == (0.015, 0.015)
    # the fingers' (settings or model) as before: the closed pair along x, a finger across
    fingers = gripper_model(s.gripper)
    assert push_contact_halves(fingers, x, x) == push_contact_halves(s.gripper, x, x) == pytest.approx((0.02, 0.01))
    assert push_contact_halves(s.gripper, x, d) == pytest.approx((0.01, 0.02))


def test_a_cup_alone_pushes_from_its_own_place_at_its_own_height() -> None:
    from clearcli.geometry.models import TableFrame
    from clearcli.predicates.synthetic import Box

    box = Box((0.0, 0.0), BOX)
    starts = {}
    for name in ("panda", "panda-suction"):
        state, obj = one_box(box, load_settings(None, [f"robot.name={name}"]))
        tf = TableFrame.from_plane(state.table)
        push = obj.pushes["dir1"]
        start = tf.to_table(np.asarray(push.candidates[0][1], dtype=float)[:3, 3][None])[0]
        d = tf.to_table(np.asarray(push.unit_vector, dtype=float)[None])[0] - tf.to_table(np.zeros((1, 3)))[0]
        starts[name] = (start, d / np.linalg.norm(d))
    (f_start, d), (c_start, _) = starts["panda"], starts["panda-suction"]
    # the TCP: the fingertips 1 cm above the table, 2 cm below the TCP; the lip 1 cm
    # above the table, 2.7 cm past the TCP
    assert f_start[2] == pytest.approx(0.01 + 0.02, abs=1e-6)
    assert c_start[2] == pytest.approx(0.01 + 0.027, abs=1e-6)
    # behind the rear face by [push] gripper_behind_m and the half size along the push:
    # the closed pair's 2 cm (closing along the push) against the cup's 1.5 cm
    assert float((c_start - f_start)[:2] @ d[:2]) == pytest.approx(0.005, abs=1e-6)
