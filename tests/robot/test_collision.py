"""Tests of clearcli/robot/collision.py."""

from __future__ import annotations

import numpy as np
from helpers.robot import kin  # noqa: F401  (fixtures)

from clearcli.robot.collision import Obstacles, capsule_spheres, hull_planes
from clearcli.robot.wam_kinematics import WamKinematics


def test_capsules_and_collisions(kin: WamKinematics) -> None:
    q = np.zeros(7)
    a, b, r = kin.capsules(q)
    # at q = 0 the upper arm runs from the shoulder (origin) to the elbow (0.045, 0, 0.55)
    np.testing.assert_allclose(a[0], [0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(b[0], [0.045, 0, 0.55], atol=1e-12)
    centres, radii = capsule_spheres(a, b, r)
    table_low = Obstacles(np.array([0, 0, 1.0]), 0.346, margin_m=0.01)  # table 0.346 below
    assert table_low.collisions(centres, radii) == []
    table_high = Obstacles(np.array([0, 0, 1.0]), -0.5, margin_m=0.01)  # a plane at z = 0.5
    assert table_high.collisions(centres, radii) == ["table"]
    # a box around the forearm at q = 0 (z 0.6 .. 0.85) is hit; one beside it is not
    cube = np.array([[x, y, z] for x in (-0.05, 0.05) for y in (-0.05, 0.05) for z in (0.65, 0.75)])
    from scipy.spatial import ConvexHull

    faces = ConvexHull(cube).simplices
    planes = hull_planes(cube, faces)
    assert np.all(cube.mean(0) @ planes[:, :3].T + planes[:, 3] < 0)
    obs = Obstacles(np.array([0, 0, 1.0]), 0.346, ("o0",), (planes,), ((cube.min(0), cube.max(0)),))
    assert obs.collisions(centres, radii) == ["o0"]
    assert obs.collisions(centres, radii, ignore=("o0",)) == []
    moved = cube + [0.3, 0, 0]
    obs2 = Obstacles(
        np.array([0, 0, 1.0]), 0.346, ("o0",), (hull_planes(moved, faces),), ((moved.min(0), moved.max(0)),)
    )
    assert obs2.collisions(centres, radii) == []


def test_capsule_spheres_by_hand() -> None:
    import math

    from clearcli.robot.collision import capsule_spheres

    # a 0.1 m capsule of radius 0.02: spheres every 1 cm (half a radius), 11 of them,
    # and a zero-length one (a sphere) as two coincident spheres
    a = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])
    b = np.array([[0.1, 0.0, 0.0], [1.0, 1.0, 1.0]])
    c, r = capsule_spheres(a, b, np.array([0.02, 0.05]))
    assert c.shape == (13, 3) and r.tolist() == [0.02] * 11 + [0.05] * 2
    np.testing.assert_allclose(c[:11, 0], np.linspace(0, 0.1, 11))
    assert c[10, 0] == 0.1 and np.all(c[11:] == 1.0)
    assert capsule_spheres(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0))[0].shape == (0, 3)
    assert math.isclose(float(np.diff(c[:11, 0]).max()), 0.01)


def test_a_cylinder_capped_by_spheres_is_one_capsule() -> None:
    from clearcli.robot.generic import _without_covered

    z = np.zeros(3)
    top = np.array([0.0, 0.0, 0.2])
    parts = [(3, z, top, 0.06), (3, z, z, 0.06), (3, top, top, 0.06), (4, z, z, 0.06), (3, z, z, 0.08)]
    kept = _without_covered(parts)
    # the end spheres go; a sphere on another joint and a wider sphere stay
    assert [(j, r) for j, _, _, r in kept] == [(3, 0.06), (4, 0.06), (3, 0.08)]
