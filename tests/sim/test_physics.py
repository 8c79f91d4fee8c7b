"""Tests of clearcli/sim/physics.py."""

from __future__ import annotations

import numpy as np
import pytest

from clearcli.settings.geometry import GripperSettings
from clearcli.sim import scene as S


def test_push_contacts_by_hand() -> None:
    from clearcli.sim.physics import push_contacts

    # two 4 cm boxes side by side along x (faces at x = -0.04, 0, 0.04), 6 cm long along y
    a = S.Box(0, 0.04, 0.06, 0.08, x_m=-0.02, y_m=0.0)
    b = S.Box(1, 0.04, 0.06, 0.08, x_m=0.02, y_m=0.0)
    c = S.Box(2, 0.04, 0.04, 0.08, x_m=0.0, y_m=0.2)  # far ahead
    scene = S.make_scene("pair", [a, b, c])
    up = np.array([0.0, 1.0])
    # fingers 1.5 cm to either side of x = -0.02, 3 cm behind the rear faces (y = -0.03)
    assert push_contacts(scene, np.array([-0.02, -0.06]), up, 0.015, 0.1) == [0]
    assert push_contacts(scene, np.array([0.02, -0.06]), up, 0.015, 0.1) == [1]
    # centred on the seam: both, the one overlapped more (equal here: the first) first
    assert sorted(push_contacts(scene, np.array([0.0, -0.06]), up, 0.015, 0.1)) == [0, 1]
    # 4 mm over the seam onto b: b alone (a overlapped by less than 5 mm)
    assert push_contacts(scene, np.array([0.019, -0.06]), up, 0.015, 0.1) == [1]
    # beside both: nothing; and c only within reach
    assert push_contacts(scene, np.array([0.2, -0.06]), up, 0.015, 0.1) == []
    assert push_contacts(scene, np.array([0.0, 0.1]), up, 0.015, 0.2) == [2]
    assert push_contacts(scene, np.array([0.0, 0.1]), up, 0.015, 0.05) == []


def test_grasp_contacts_and_opening_by_hand() -> None:
    from clearcli.geometry.gripper import gripper_model
    from clearcli.predicates.relations import grasp_opening_m
    from clearcli.sim.physics import grasp_contacts

    g = gripper_model(GripperSettings())  # opens to 7 cm, closes to 3 cm
    assert grasp_opening_m(0.04, g, 0.01) == pytest.approx(0.06)  # 4 + 2 x 1 cm
    assert grasp_opening_m(0.041, g, 0.01) == pytest.approx(0.065)  # rounded up to 5 mm
    assert grasp_opening_m(0.055, g, 0.01) == pytest.approx(0.07)  # at most the opening
    assert grasp_opening_m(0.005, g, 0.01) == pytest.approx(0.03)  # at least the closing width
    assert grasp_opening_m(0.04, g, 0.0) == pytest.approx(0.07)  # 0: fully
    # a 4 cm box and a neighbour whose face is at x = 0.040 (2 cm from the box)
    box = S.Box(0, 0.04, 0.04, 0.08, x_m=0.0, y_m=0.0)
    near = S.Box(1, 0.04, 0.04, 0.08, x_m=0.060, y_m=0.0)
    scene = S.make_scene("near", [box, near])
    tcp = np.array([0.0, 0.0, 0.0575])
    tips = 0.0575 - 0.0225
    x = np.array([1.0, 0.0, 0.0])
    # fully open, a finger spans x = 0.035-0.045: it comes down on the neighbour (by
    # 5 mm, more than the 3 mm a finger nudges aside)
    assert grasp_contacts(scene, tcp, x, 0.07, 0.03, tips) == [0, 1]
    # opened to 6 cm (finger at 0.030-0.040): only the box
    assert grasp_contacts(scene, tcp, x, 0.06, 0.03, tips) == [0]
    # a neighbour 2 mm into the finger's path is nudged aside (face at 0.043)
    nudged = S.make_scene("nudged", [box, S.Box(1, 0.04, 0.04, 0.08, x_m=0.063, y_m=0.0)])
    assert grasp_contacts(nudged, tcp, x, 0.07, 0.03, tips) == [0]
    # a neighbour reaching in between the fingers (face at 0.03) is squeezed too
    inside = S.make_scene("inside", [box, S.Box(1, 0.04, 0.04, 0.08, x_m=0.05, y_m=0.0)])
    assert grasp_contacts(inside, tcp, x, 0.07, 0.03, tips) == [0, 1]
    # closing along y: the neighbour is beside the fingers, not under or between them
    assert grasp_contacts(scene, tcp, np.array([0.0, 1.0, 0.0]), 0.07, 0.03, tips) == [0]
    # a neighbour lower than the fingertips is not touched
    low = S.make_scene("low", [box, S.Box(1, 0.04, 0.04, 0.03, x_m=0.05, y_m=0.0)])
    assert grasp_contacts(low, tcp, x, 0.07, 0.03, tips) == [0]


def test_world_push_slides_shoves_and_stalls() -> None:
    from clearcli.sim.episode import WorldParams
    from clearcli.sim.physics import separation, world_push
    from clearcli.sim.scene import Box, make_scene

    quiet = WorldParams(heading_noise_deg=0.0, yaw_noise_deg=0.0)
    rng = np.random.default_rng(0)
    alone = make_scene("alone", [Box(0, 0.05, 0.04, 0.08, x_m=0.0, y_m=0.0)])
    moved, outcome = world_push(alone, 0, np.array([1.0, 0.0]), 0.1, rng, quiet)
    assert moved.objects[0].x_m == pytest.approx(0.1) and moved.objects[0].y_m == pytest.approx(0.0)
    assert outcome == "pushed 0.100 m of 0.100 m"
    # a box in the way, touching: it is shoved ahead by the same distance
    pair = make_scene(
        "pair", [Box(0, 0.05, 0.04, 0.08, x_m=0.0, y_m=0.0), Box(1, 0.04, 0.04, 0.06, x_m=0.046, y_m=0.0)]
    )
    moved, outcome = world_push(pair, 0, np.array([1.0, 0.0]), 0.05, rng, quiet)
    assert moved.objects[0].x_m == pytest.approx(0.05)
    assert moved.objects[1].x_m - moved.objects[0].x_m >= 0.045 - 1e-6
    assert outcome.endswith("shoved 1")
    # a chain of four touching boxes is too much: the push stalls at once
    chain = make_scene("chain", [Box(i, 0.04, 0.04, 0.06, x_m=0.0401 * i, y_m=0.0) for i in range(4)])
    moved, outcome = world_push(chain, 0, np.array([1.0, 0.0]), 0.05, rng, quiet)
    assert moved.objects == chain.objects and outcome.startswith("pushed 0.000 m")
    # pushed off the table's edge, the object falls and is gone
    edge = make_scene("edge", [Box(0, 0.05, 0.04, 0.08, x_m=0.37, y_m=0.0)])
    moved, outcome = world_push(edge, 0, np.array([1.0, 0.0]), 0.1, rng, quiet)
    assert moved.objects == () and outcome.startswith("fell off")
    # the separating translation of two overlapping squares
    a = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    np.testing.assert_allclose(separation(a, a + [0.9, 0.2]), [0.1, 0.0])
    assert separation(a, a + [1.5, 0.0]) is None


def test_world_push_turns_the_object_with_seeded_noise() -> None:
    from clearcli.sim.physics import world_push
    from clearcli.sim.scene import Box, make_scene

    alone = make_scene("alone", [Box(0, 0.05, 0.04, 0.08, x_m=0.0, y_m=0.0)])
    a, _ = world_push(alone, 0, np.array([0.0, 1.0]), 0.1, np.random.default_rng(4))
    b, _ = world_push(alone, 0, np.array([0.0, 1.0]), 0.1, np.random.default_rng(4))
    assert a == b  # seeded
    obj = a.objects[0]
    assert obj.yaw_rad != 0.0 and abs(obj.yaw_rad) < np.radians(20)
    assert 0.09 < obj.y_m <= 0.1 + 1e-9 and abs(obj.x_m) < 0.01


def test_world_grasp_of_a_tight_object_slips_sometimes() -> None:
    from clearcli.sim.physics import world_grasp
    from clearcli.sim.scene import Box, make_scene

    rng = np.random.default_rng(1)
    narrow = make_scene("narrow", [Box(0, 0.1, 0.04, 0.08, x_m=0.0, y_m=0.0)])
    assert all(world_grasp(narrow, 0, 0.07, rng)[1] == "removed" for _ in range(20))
    tight = make_scene("tight", [Box(0, 0.1, 0.065, 0.08, x_m=0.0, y_m=0.0)])
    outcomes = [world_grasp(tight, 0, 0.07, rng)[1] for _ in range(40)]
    assert 8 <= outcomes.count("slipped") <= 32 and "removed" in outcomes
    scene, outcome = next((s, o) for s, o in (world_grasp(tight, 0, 0.07, rng) for _ in range(50)) if o == "slipped")
    assert len(scene.objects) == 1 and scene.objects[0] != tight.objects[0]


def test_world_grasp_never_holds_an_object_too_wide_or_too_narrow() -> None:
    from clearcli.sim.physics import truly_ungraspable, world_grasp
    from clearcli.sim.scene import Box, Cylinder, make_scene

    rng = np.random.default_rng(2)
    wide = make_scene("wide", [Box(0, 0.1, 0.08, 0.08, x_m=0.0, y_m=0.0)])
    thin = make_scene("thin", [Cylinder(0, 0.012, 0.1, x_m=0.0, y_m=0.0)])
    for _ in range(10):
        assert world_grasp(wide, 0, 0.07, rng, closing_width_m=0.03) == (wide, "too wide")
        assert world_grasp(thin, 0, 0.07, rng, closing_width_m=0.03) == (thin, "too narrow")
    assert truly_ungraspable(wide.objects[0], 0.07, 0.03) and truly_ungraspable(thin.objects[0], 0.07, 0.03)
    # 6.9 cm across its narrow side: the gripper fits it (it may slip, never refuses)
    fits = make_scene("fits", [Box(0, 0.1, 0.069, 0.08, x_m=0.0, y_m=0.0)])
    assert not truly_ungraspable(fits.objects[0], 0.07, 0.03)
    assert {world_grasp(fits, 0, 0.07, rng, closing_width_m=0.03)[1] for _ in range(20)} <= {"removed", "slipped"}
