"""Tests of the simulated world's wide objects (mug handles, `families.wide_objects`) and
its rules for the rim grasp, the slide and the edge pinch (clearcli/sim/physics.py).

Every expected value is worked out by hand in the comments."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from clearcli.sim.camera import DepthNoise, render
from clearcli.sim.families import FAMILIES, _edge_gap, wide_objects
from clearcli.sim.physics import approach_tilt_deg, world_edge_pinch, world_rim_grasp, world_slide
from clearcli.sim.scene import Box, Cylinder, Scene, make_scene, objects_overlap

EXACT = DepthNoise(enabled=False)

# --- rim grasp ---------------------------------------------------------------------------
#
# The cup: radius 0.05, wall 0.004 (inner wall at 0.046), 0.08 tall, at the origin; its
# floor's top at 0.005. The gripper: straight down (approach -z), closing along +x (the
# radial direction at (0.048, 0)); y = z x x = (0, -1, 0). Opening 0.02, fingers 0.008
# thick, 0.015 wide, 0.04 long, tips 0.02 past the closing point.
#   +x finger (outer): x 0.058..0.066; -x finger (inner): x 0.030..0.038, y +/-0.0075.
#   inner finger's farthest corner from the axis: hypot(0.038, 0.0075) = 0.0387 < 0.046;
#   outer finger's nearest point: 0.058 > 0.05. The wall 0.046..0.050 lies between the
#   inner faces at 0.038 and 0.058. Closing point at z 0.05: the tips at 0.03, 50 mm
#   below the rim (>= 10 mm) and 25 mm above the floor; the fingers span z 0.03..0.07.

CUP = Cylinder(0, 0.05, 0.08, 0.0, 0.0, wall_m=0.004)
FINGERS = dict(opening_m=0.02, finger_thickness_m=0.008, finger_width_m=0.015, finger_depth_m=0.04)


def _down(x: float, y: float, z: float, yaw: float = 0.0) -> np.ndarray:
    """T_table_gripper: approach straight down, closing along (cos yaw, sin yaw, 0)."""
    c, s = math.cos(yaw), math.sin(yaw)
    T = np.eye(4)
    T[:3, 0] = (c, s, 0.0)
    T[:3, 2] = (0.0, 0.0, -1.0)
    T[:3, 1] = np.cross(T[:3, 2], T[:3, 0])
    T[:3, 3] = (x, y, z)
    return T


def _rim(scene: Scene, T: np.ndarray) -> tuple[bool, str]:
    return world_rim_grasp(scene, 0, T, **FINGERS)


def test_rim_grasp_holds_an_open_cylinder_by_its_wall() -> None:
    ok, why = _rim(make_scene("cup", [CUP]), _down(0.048, 0.0, 0.05))
    assert ok, why
    # the same by symmetry on the other side of the cup, closing along -y (radial there)
    ok, why = _rim(make_scene("cup", [CUP]), _down(0.0, -0.048, 0.05, yaw=-math.pi / 2))
    assert ok, why


def test_rim_grasp_fails_on_a_closed_cylinder() -> None:
    ok, why = _rim(make_scene("can", [replace(CUP, wall_m=0.0)]), _down(0.048, 0.0, 0.05))
    assert not ok and "open container" in why


def test_rim_grasp_fails_with_the_closing_point_at_the_centre() -> None:
    ok, why = _rim(make_scene("cup", [CUP]), _down(0.0, 0.0, 0.05))
    assert not ok and "axis" in why
    # at radius 0.02 the inner faces are at 0.01 and 0.03: the wall (0.046..0.05) is not
    # between them
    ok, why = _rim(make_scene("cup", [CUP]), _down(0.02, 0.0, 0.05))
    assert not ok and "not between" in why


def test_rim_grasp_fails_when_a_box_inside_stands_where_the_inner_finger_goes() -> None:
    # a 2 x 2 x 5 cm box on the cup's floor, x 0.015..0.035: 5 mm into the inner finger's
    # x 0.030..0.038, and z 0.005..0.055 overlaps the finger's 0.03..0.07; its farthest
    # corner hypot(0.035, 0.01) = 0.0364 is inside the inner wall (a physical scene)
    inside = Box(1, 0.02, 0.02, 0.05, x_m=0.025, y_m=0.0, base_z_m=CUP.floor_m)
    ok, why = _rim(make_scene("cup+box", [CUP, inside]), _down(0.048, 0.0, 0.05))
    assert not ok and "inner finger meets object 1" in why
    # 1 cm nearer the axis (x 0.005..0.025) it leaves 5 mm to the finger: held
    clear = replace(inside, x_m=0.015)
    ok, why = _rim(make_scene("cup+box", [CUP, clear]), _down(0.048, 0.0, 0.05))
    assert ok, why


def test_rim_grasp_depth_tilt_and_direction_limits() -> None:
    scene = make_scene("cup", [CUP])
    # closing point at 0.095: tips at 0.075, only 5 mm below the rim
    ok, why = _rim(scene, _down(0.048, 0.0, 0.095))
    assert not ok and "below the rim" in why
    # closing point at 0.02: tips at 0.0, under the floor's top at 0.005
    ok, why = _rim(scene, _down(0.048, 0.0, 0.02))
    assert not ok and "floor" in why
    # closing along y at (0.048, 0): 90 deg off radial
    ok, why = _rim(scene, _down(0.048, 0.0, 0.05, yaw=math.pi / 2))
    assert not ok and "off radial" in why
    # tilted 20 deg about the closing axis: beyond 15 deg
    T = _down(0.048, 0.0, 0.05)
    a = math.radians(20.0)
    Rx = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(a), -math.sin(a)], [0.0, math.sin(a), math.cos(a)]])
    T[:3, :3] = T[:3, :3] @ Rx
    ok, why = _rim(scene, T)
    assert not ok and "straight down" in why


def test_rim_grasp_outer_finger_meets_the_mugs_handle() -> None:
    # handle along +x (yaw 0), 2 cm long: x 0.05..0.07, y +/-0.006, z 0.016..0.064; the
    # outer finger (x 0.058..0.066, z 0.03..0.07) is in it. On the -x side it is held.
    mug = replace(CUP, handle_m=0.02)
    ok, why = _rim(make_scene("mug", [mug]), _down(0.048, 0.0, 0.05))
    assert not ok and "handle" in why
    ok, why = _rim(make_scene("mug", [mug]), _down(-0.048, 0.0, 0.05, yaw=math.pi))
    assert ok, why


# --- slide and edge pinch ----------------------------------------------------------------


def test_slide_stops_at_a_neighbour() -> None:
    # A: 4 cm wide at x = -0.10, its +x face at -0.08; B: 4 cm wide at x = 0, its -x face at
    # -0.02. Sliding A along +x for 0.10 it travels the 0.06 gap and stops at B.
    a = Box(0, 0.04, 0.04, 0.05, x_m=-0.10, y_m=0.0)
    b = Box(1, 0.04, 0.06, 0.05, x_m=0.0, y_m=0.01)
    scene = make_scene("pair", [a, b])
    moved, travelled = world_slide(scene, 0, np.array([1.0, 0.0]), 0.10)
    assert travelled == pytest.approx(0.06, abs=1e-5)
    assert moved.objects[0].x_m == pytest.approx(-0.04, abs=1e-5) and moved.objects[1] == b
    # a slide shorter than the gap goes all the way; one away from B is not stopped by it
    assert world_slide(scene, 0, np.array([1.0, 0.0]), 0.03)[1] == pytest.approx(0.03, abs=1e-12)
    assert world_slide(scene, 0, np.array([-2.0, 0.0]), 0.05)[1] == pytest.approx(0.05, abs=1e-12)
    # B lifted above A's top (0.05) does not stop it
    lifted = make_scene("lifted", [a, replace(b, base_z_m=0.06)])
    assert world_slide(lifted, 0, np.array([1.0, 0.0]), 0.10)[1] == pytest.approx(0.10, abs=1e-12)


# The table's right edge is at x = 0.40. A flat box 20 x 12 x 3 cm; grip depth 3 cm, so the
# overhang needs 0.03 + 0.005 = 0.035; jaws 0.08 open, 0.0 closed, the 3 cm fits.
FLAT = Box(0, 0.20, 0.12, 0.03, x_m=0.25, y_m=0.0)
PINCH = dict(grip_depth_m=0.03, opening_m=0.08, closing_m=0.0)


def test_edge_pinch_holds_with_enough_overhang() -> None:
    # slid +x by 0.10 from x 0.25 to 0.35: it reaches 0.35 + 0.10 = 0.45, 0.05 past the edge
    scene, travelled = world_slide(make_scene("flat", [FLAT]), 0, np.array([1.0, 0.0]), 0.10)
    assert travelled == pytest.approx(0.10)
    ok, why = world_edge_pinch(scene, 0, np.array([1.0, 0.0]), **PINCH)
    assert ok and "overhang 50.0 mm" in why
    # too thick for the jaws: 10 cm > 8 cm
    thick = make_scene("thick", [replace(FLAT, x_m=0.35, size_z_m=0.10)])
    ok, why = world_edge_pinch(thick, 0, np.array([1.0, 0.0]), **PINCH)
    assert not ok and "thick" in why
    # mirrored on the left edge (x = -0.40), sliding along -x
    left = make_scene("left", [replace(FLAT, x_m=-0.35)])
    assert world_edge_pinch(left, 0, np.array([-1.0, 0.0]), **PINCH)[0]


def test_edge_pinch_span_follows_the_approach_tilt() -> None:
    # a 6 cm slab with the 8 cm jaws: from 45 deg it spans 6 / cos 45 = 8.49 cm across the
    # fingers (> 8 - 1 cm), from 20 deg 6 / cos 20 = 6.39 cm (< 7 cm); below 20 deg the
    # world's arms do not come
    scene = make_scene("slab", [replace(FLAT, x_m=0.35, size_z_m=0.06)])
    ok, why = world_edge_pinch(scene, 0, np.array([1.0, 0.0]), **PINCH, tilt_deg=45.0)
    assert not ok and "at most 49.5 mm" in why  # 0.07 * cos 45
    ok, why = world_edge_pinch(scene, 0, np.array([1.0, 0.0]), **PINCH, tilt_deg=20.0)
    assert ok, why
    ok, why = world_edge_pinch(scene, 0, np.array([1.0, 0.0]), **PINCH, tilt_deg=10.0)
    assert not ok and "cannot come that low" in why
    # the tilt read off a pose: approach 30 deg below the horizontal along +x
    T = np.eye(4)
    T[:3, 2] = [np.cos(np.radians(30.0)), 0.0, -np.sin(np.radians(30.0))]
    assert approach_tilt_deg(T) == pytest.approx(30.0, abs=1e-9)


def test_edge_pinch_slips_with_too_little_overhang() -> None:
    # at x = 0.32 it reaches 0.42: 0.02 past the edge < 0.035
    scene = make_scene("flat", [replace(FLAT, x_m=0.32)])
    ok, why = world_edge_pinch(scene, 0, np.array([1.0, 0.0]), **PINCH)
    assert not ok and why.startswith("slips") and "20.0 mm" in why


def test_edge_pinch_tips_when_the_centre_is_past_the_edge() -> None:
    scene = make_scene("flat", [replace(FLAT, x_m=0.41)])
    ok, why = world_edge_pinch(scene, 0, np.array([1.0, 0.0]), **PINCH)
    assert not ok and "tipped off the table" in why


# --- the handle: footprint and render ----------------------------------------------------

# Yaw 0: the handle points along +x, seen side-on from the camera (which looks along +y).
MUG = Cylinder(0, 0.045, 0.095, 0.0, 0.05, wall_m=0.004, handle_m=0.025)


def test_handle_footprint() -> None:
    bare = replace(MUG, handle_m=0.0)
    n = 32
    angles = np.arange(n) * (2 * math.pi / n)
    r = 0.045 / math.cos(math.pi / n)
    circle = np.stack([r * np.cos(angles), 0.05 + r * np.sin(angles)], axis=1)
    assert np.array_equal(bare.footprint(), circle)  # unchanged without a handle
    fp = MUG.footprint()
    # the handle's far corners: 0.045 + 0.025 = 0.07 out along +x, 0.006 to either side
    assert fp[:, 0].max() == pytest.approx(0.07, abs=1e-12)
    far = fp[np.isclose(fp[:, 0], 0.07)]
    assert sorted(far[:, 1]) == pytest.approx([0.05 - 0.006, 0.05 + 0.006], abs=1e-12)
    # the rest of the hull is the circle's polygon
    assert fp[:, 0].min() == pytest.approx(-r) and fp[:, 1].max() == pytest.approx(0.05 + r)


def test_handle_renders_with_the_mugs_label() -> None:
    with_handle = render(make_scene("mug", [MUG]), seed=0, noise=EXACT)
    without = render(make_scene("mug", [replace(MUG, handle_m=0.0)]), seed=0, noise=EXACT)
    lab_h, lab_0 = with_handle.fields["label"], without.fields["label"]
    assert np.count_nonzero(lab_h == 10) > np.count_nonzero(lab_0 == 10) + 50
    # the handle only adds: every pixel not the mug's in the handle render is unchanged
    other = lab_h != 10
    assert np.array_equal(lab_h[other], lab_0[other])
    assert np.array_equal(with_handle.points[other], without.points[other], equal_nan=True)
    # and the pixels it adds have the mug's colour (a shade of it)
    gained = (lab_h == 10) & (lab_0 != 10)
    # object 0's colour is (220, 50, 47) times a shade: the same shade in every channel,
    # to within the rounding to whole values (0.5 / 47 < 0.015)
    rgb = with_handle.colors[gained].astype(float) / np.array([220.0, 50.0, 47.0])
    assert gained.any() and np.allclose(rgb, rgb[:, :1], atol=0.015)


@pytest.mark.parametrize("name", ["open_container", "small_against_tall", "dense_mix"])
def test_no_handle_renders_as_before(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """handle_m = 0 (the default) takes the path of before handles existed: the same
    frame, bit for bit, as a renderer that never looks for a handle."""
    scenes = [FAMILIES[name](seed) for seed in (0, 1)]
    now = [render(sc, seed=i) for i, sc in enumerate(scenes)]
    monkeypatch.setattr(Cylinder, "handle_box", lambda self: None)
    before = [render(sc, seed=i) for i, sc in enumerate(scenes)]
    for a, b in zip(now, before):
        assert np.array_equal(a.points, b.points, equal_nan=True)
        assert np.array_equal(a.colors, b.colors)
        assert np.array_equal(a.fields["label"], b.fields["label"])


# --- the wide_objects family ---------------------------------------------------------------


def test_wide_objects_is_deterministic_and_physical() -> None:
    kinds: set[str] = set()
    for seed in range(40):
        scene = wide_objects(seed)
        assert scene == wide_objects(seed)
        objs = scene.objects
        assert 4 <= len(objs) <= 9
        for i in range(len(objs)):
            # 3 cm in from the border, and no two overlapping (the builder keeps 1 cm apart)
            assert _edge_gap(objs[i].footprint(), scene.table) >= 0.03
            for j in range(i + 1, len(objs)):
                assert not objects_overlap(objs[i], objs[j], clearance_m=0.009), (seed, i, j)
        wide = [o for o in objs if _is_wide(o)]
        assert 1 <= len(wide) <= 3 and wide == list(objs[: len(wide)])
        assert min(_edge_gap(o.footprint(), scene.table) for o in wide) <= 0.12
        kinds |= {_kind(o) for o in wide}
    assert kinds == {"bowl", "mug", "plate", "flat box"}
    assert wide_objects(0) != wide_objects(1)


def _kind(o: Cylinder | Box) -> str:
    if isinstance(o, Box):
        return "flat box"
    if o.has_handle:
        return "mug"
    return "bowl" if o.is_open else "plate"


def _is_wide(o: Cylinder | Box) -> bool:
    """Wider than any small object (`_small`: 3-7 cm, so a radius <= 0.035)."""
    if isinstance(o, Box):
        return min(o.size_x_m, o.size_y_m) >= 0.10
    return o.radius_m >= 0.04
