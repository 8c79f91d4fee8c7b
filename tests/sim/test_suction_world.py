"""The simulated world's suction (issue 36), by hand: clearcli/sim/physics.py
`world_suction` and `world_suction_holds`, the objects' true mass and surface
(clearcli/sim/scene.py) and the `suction_mix` family (clearcli/sim/families.py)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from clearcli.settings.geometry import GripperSettings
from clearcli.settings.suction import SuctionSettings
from clearcli.sim import scene as S
from clearcli.sim.families import FAMILIES, suction_mix
from clearcli.sim.physics import (
    SUCTION_MAX_TILT_DEG,
    SUCTION_TOUCH_M,
    centre_of_mass,
    grasp_width_m,
    truly_ungraspable_by,
    world_suction,
    world_suction_holds,
)

CUP = SuctionSettings()  # a 30 mm cup, 5 mm bellows, 57 N, lip friction 0.5
DOWN = np.array([0.0, 0.0, -1.0])


def _alone(obj: S.SceneObject) -> S.Scene:
    return S.make_scene("alone", [obj])


def _top(obj: S.SceneObject, dx: float = 0.0, dy: float = 0.0) -> np.ndarray:
    return np.array([obj.x_m + dx, obj.y_m + dy, obj.top_z_m])


# --- the seal ------------------------------------------------------------------------------


def test_a_flat_box_top_seals_and_lifts() -> None:
    box = S.Box(0, 0.20, 0.15, 0.05, 0.05, -0.02, yaw_rad=0.4, mass_kg=1.0)
    ok, why, k = world_suction(_alone(box), _top(box), DOWN, CUP)
    assert (ok, k) == (True, 0) and why.startswith("lifted: 1.00 kg"), why
    # a few mm above or below the face the cup still meets it (the bellows give)
    for dz in (SUCTION_TOUCH_M * 0.9, -SUCTION_TOUCH_M * 0.9):
        assert world_suction(_alone(box), _top(box) + [0, 0, dz], DOWN, CUP)[0]


def test_the_cup_meets_nothing_or_strikes_the_object_short_of_its_contact() -> None:
    box = S.Box(0, 0.20, 0.15, 0.05, 0.0, 0.0)
    assert world_suction(_alone(box), _top(box) + [0, 0, 0.02], DOWN, CUP) == (
        False,
        "missed: the cup met nothing",
        None,
    )
    assert world_suction(_alone(box), np.array([0.3, 0.0, 0.05]), DOWN, CUP)[1:] == (
        "missed: the cup met nothing",
        None,
    )
    ok, why, k = world_suction(_alone(box), _top(box) - [0, 0, 0.02], DOWN, CUP)
    assert not ok and k == 0 and why.startswith("missed: the cup struck object 0 20 mm short")


def test_a_2cm_cylinder_side_does_not_seal_a_wide_one_does() -> None:
    # the sag of a 2 cm radius under a 30 mm cup: 20 - sqrt(20^2 - 15^2) = 6.8 mm > 5 mm
    thin = S.Cylinder(0, 0.02, 0.10, 0.0, 0.0, mass_kg=0.2)
    ok, why, k = world_suction(_alone(thin), np.array([0.02, 0.0, 0.05]), np.array([-1.0, 0.0, 0.0]), CUP)
    assert not ok and k == 0 and why == "no seal: the side curves 6.8 mm under the cup (the bellows follow 5.0)"
    # 8 cm: 1.4 mm; the shear of 0.2 kg across the lip and its moment are held
    wide = S.Cylinder(0, 0.08, 0.10, 0.0, 0.0, mass_kg=0.2)
    ok, why, _ = world_suction(_alone(wide), np.array([0.0, -0.08, 0.05]), np.array([0.0, 1.0, 0.0]), CUP)
    assert ok, why
    # its top too, and the 2 cm one's top (the disc fits in its 4 cm cap)
    assert world_suction(_alone(wide), _top(wide), DOWN, CUP)[0]
    assert world_suction(_alone(thin), _top(thin), DOWN, CUP)[0]


@pytest.mark.parametrize("surface", ["porous", "ribbed"])
def test_a_porous_or_ribbed_top_does_not_seal_its_smooth_sides_do(surface: str) -> None:
    box = S.Box(0, 0.20, 0.15, 0.06, 0.0, 0.0, mass_kg=0.3, surface=surface)
    ok, why, k = world_suction(_alone(box), _top(box), DOWN, CUP)
    assert (ok, why, k) == (False, f"no seal: the top is {surface}", 0)
    ok, why, _ = world_suction(_alone(box), np.array([0.10, 0.0, 0.03]), np.array([-1.0, 0.0, 0.0]), CUP)
    assert ok, why
    lid = S.Cylinder(0, 0.08, 0.10, 0.0, 0.0, surface=surface)
    assert world_suction(_alone(lid), _top(lid), DOWN, CUP)[1] == f"no seal: the top is {surface}"


def test_a_disc_over_the_face_edge_does_not_seal() -> None:
    box = S.Box(0, 0.20, 0.15, 0.05, 0.0, 0.0, yaw_rad=math.radians(30), mass_kg=0.2)
    along = np.array([math.cos(math.radians(30)), math.sin(math.radians(30)), 0.0])
    # the lip's edge 1 mm inside the 10 cm half-length: seals; 4 mm past it: not
    assert world_suction(_alone(box), _top(box) + 0.084 * along, DOWN, CUP)[0]
    ok, why, k = world_suction(_alone(box), _top(box) + 0.089 * along, DOWN, CUP)
    assert not ok and k == 0 and why == "no seal: the lip overhangs the top's edge by 4.0 mm"
    # a side 25 mm tall is lower than the cup (30 mm)
    low = S.Box(0, 0.20, 0.15, 0.025, 0.0, 0.0)
    why = world_suction(_alone(low), np.array([0.10, 0.0, 0.0125]), np.array([-1.0, 0.0, 0.0]), CUP)[1]
    assert why == "no seal: the lip overhangs the side's edge by 2.5 mm"
    # a lidded container's cap: the disc within its radius
    lid = S.Cylinder(0, 0.06, 0.08, 0.0, 0.0)
    assert world_suction(_alone(lid), _top(lid, dx=0.044), DOWN, CUP)[0]
    assert world_suction(_alone(lid), _top(lid, dx=0.05), DOWN, CUP)[1].startswith("no seal: the lip overhangs the top")


def test_an_open_container_a_handle_a_tilt_and_another_object_do_not_seal() -> None:
    bowl = S.Cylinder(0, 0.07, 0.06, 0.0, 0.0, wall_m=0.005)
    assert (
        world_suction(_alone(bowl), _top(bowl), DOWN, CUP)[1] == "no seal: an open container's top (its rim is no face)"
    )
    mug = S.Cylinder(0, 0.045, 0.095, 0.0, 0.0, wall_m=0.004, handle_m=0.025)  # handle along +x
    handle = mug.handle_box()
    assert handle is not None
    tip = np.array([handle.x_m + handle.size_x_m / 2, handle.y_m, handle.base_z_m + handle.size_z_m / 2])
    assert world_suction(_alone(mug), tip, np.array([-1.0, 0.0, 0.0]), CUP) == (
        False,
        "no seal: on the mug's handle",
        0,
    )
    box = S.Box(0, 0.20, 0.15, 0.05, 0.0, 0.0)
    tilt = math.radians(SUCTION_MAX_TILT_DEG + 5)
    askew = np.array([math.sin(tilt), 0.0, -math.cos(tilt)])
    assert (
        world_suction(_alone(box), _top(box), askew, CUP)[1]
        == "no seal: the cup meets the top 20 deg askew (the lip follows 15)"
    )
    tilt = math.radians(SUCTION_MAX_TILT_DEG - 5)
    assert world_suction(_alone(box), _top(box), np.array([math.sin(tilt), 0.0, -math.cos(tilt)]), CUP)[0]
    # a small box standing on the top, its edge 5 mm inside the cup's disc
    small = S.Box(1, 0.03, 0.03, 0.04, 0.02, 0.0, base_z_m=0.05)
    scene = S.make_scene("stack", [box, small])
    assert world_suction(scene, _top(box), DOWN, CUP) == (False, "no seal: object 1 under the cup", 0)
    assert world_suction(scene, _top(box, dx=-0.03), DOWN, CUP)[0]


def test_the_cup_meets_what_lies_under_it_not_what_the_planner_meant() -> None:
    a = S.Box(0, 0.12, 0.12, 0.04, -0.1, 0.0)
    b = S.Box(1, 0.12, 0.12, 0.06, 0.1, 0.0)
    ok, _, k = world_suction(S.make_scene("two", [a, b]), np.array([0.1, 0.0, 0.06]), DOWN, CUP)
    assert ok and k == 1


# --- the load -----------------------------------------------------------------------------


def test_a_heavy_box_lifts_from_its_centre_not_from_its_end() -> None:
    # 4 kg: its pull is 39 N of the cup's 57; 12 cm off its centre its weight's moment
    # (4.7 N m) is five times what the lip holds at its radius (57 N x 15 mm)
    box = S.Box(0, 0.30, 0.20, 0.06, 0.0, 0.0, mass_kg=4.0)
    ok, why, _ = world_suction(_alone(box), _top(box), DOWN, CUP)
    assert ok and "0.69 of the cup's hold" in why, why
    ok, why, k = world_suction(_alone(box), _top(box, dx=0.12), DOWN, CUP)
    assert not ok and k == 0 and why.startswith("dropped: too heavy: 4.00 kg, 6.20 of the cup's hold"), why
    # the world has no safety factor: 5.5 kg at the centre (54 N of 57) is lifted, 6 kg not
    assert world_suction(_alone(replace(box, mass_kg=5.5)), _top(box), DOWN, CUP)[0]
    assert world_suction(_alone(replace(box, mass_kg=6.0)), _top(box), DOWN, CUP)[1].startswith("dropped: too heavy")
    # from its side the weight is shear, against half the force (the lip's friction),
    # and its moment about the face, 5 cm from its middle: 1 kg is held, 1.5 kg drops
    deep = S.Box(0, 0.10, 0.20, 0.06, 0.0, 0.0, mass_kg=1.0)
    side = (np.array([0.05, 0.0, 0.03]), np.array([-1.0, 0.0, 0.0]))
    ok, why, _ = world_suction(_alone(deep), *side, CUP)
    assert ok and "shear 9.8 N, moment 0.49 N m" in why, why
    assert world_suction(_alone(replace(deep, mass_kg=1.5)), *side, CUP)[1].startswith("dropped: too heavy: 1.50 kg")


def test_true_mass_is_the_drawn_one_or_the_volume_at_the_world_density() -> None:
    box = S.Box(0, 0.1, 0.2, 0.05, 0.0, 0.0)
    assert box.mass_kg == 0.0 and box.surface == "smooth"
    assert box.true_mass_kg == pytest.approx(0.001 * S.WORLD_DENSITY_KG_M3)
    assert replace(box, mass_kg=2.0).true_mass_kg == 2.0
    can = S.Cylinder(0, 0.03, 0.1, 0.0, 0.0)
    assert can.true_mass_kg == pytest.approx(math.pi * 0.03**2 * 0.1 * S.WORLD_DENSITY_KG_M3)
    cup = S.Cylinder(0, 0.04, 0.1, 0.0, 0.0, wall_m=0.004, floor_m=0.01)
    walls = math.pi * (0.04**2 - 0.036**2) * 0.09 + math.pi * 0.04**2 * 0.01
    assert cup.volume_m3 == pytest.approx(walls)
    assert 0.0 < centre_of_mass(cup)[2] < 0.05  # its floor weighs it down
    assert centre_of_mass(can)[2] == pytest.approx(0.05)


def test_every_built_scene_keeps_its_objects_as_they_were() -> None:
    # the new fields default to "no drawn mass, a smooth top" in every scene but suction_mix
    scenes = [S.clutter(6, 0), S.dense(8, 3), S.deadlock_row(), S.box_on_box()]
    scenes += [build(seed) for name, build in FAMILIES.items() if name != "suction_mix" for seed in (0, 1)]
    for scene in scenes:
        assert all(o.mass_kg == 0.0 and o.surface == "smooth" for o in scene.objects), scene.name


# --- what the world's cup can ever take -----------------------------------------------------


def test_world_suction_holds_some_face_or_none() -> None:
    assert world_suction_holds(S.Box(0, 0.2, 0.15, 0.05, 0.0, 0.0, mass_kg=1.0))
    # porous on top, but its sides are smooth and 6 cm tall: held from a side
    assert world_suction_holds(S.Box(0, 0.2, 0.15, 0.06, 0.0, 0.0, mass_kg=0.3, surface="porous"))
    # porous on top and 2.5 cm tall (no side for the cup): none
    assert not world_suction_holds(S.Box(0, 0.2, 0.15, 0.025, 0.0, 0.0, surface="ribbed"))
    # 4 kg under a ribbed lid: its side would have to hold 39 N of shear (28.5 N at most)
    assert not world_suction_holds(S.Cylinder(0, 0.08, 0.10, 0.0, 0.0, mass_kg=4.0, surface="ribbed"))
    assert world_suction_holds(S.Cylinder(0, 0.08, 0.10, 0.0, 0.0, mass_kg=4.0))  # from its top
    assert not world_suction_holds(S.Box(0, 0.02, 0.02, 0.05, 0.0, 0.0))  # no face as wide as the cup
    assert world_suction_holds(S.Cylinder(0, 0.07, 0.06, 0.0, 0.0, wall_m=0.005))  # a bowl, by its outer wall
    # a bigger cup holds what the default one does not
    assert world_suction_holds(S.Box(0, 0.3, 0.2, 0.06, 0.0, 0.0, mass_kg=7.0), replace(CUP, holding_force_n=120.0))


def test_truly_ungraspable_by_counts_the_cup() -> None:
    gripper = GripperSettings()
    heavy_ribbed = S.Cylinder(0, 0.08, 0.10, 0.0, 0.0, mass_kg=4.0, surface="ribbed")
    flat = S.Box(0, 0.25, 0.2, 0.05, 0.0, 0.0, mass_kg=1.0)
    assert truly_ungraspable_by(flat, gripper, ("pinch",))
    assert not truly_ungraspable_by(flat, gripper, ("pinch", "suction"))
    assert truly_ungraspable_by(heavy_ribbed, gripper, ("pinch", "suction"))


# --- the suction_mix family ----------------------------------------------------------------


def test_suction_mix_draws_wide_objects_masses_and_surfaces() -> None:
    objects = [o for seed in range(40) for o in suction_mix(seed).objects]
    assert suction_mix(7) == suction_mix(7) and suction_mix(7) != suction_mix(8)
    boxes = [o for o in objects if isinstance(o, S.Box) and min(o.size_x_m, o.size_y_m) >= 0.10]
    lids = [o for o in objects if isinstance(o, S.Cylinder) and o.radius_m >= 0.06]
    small = [o for o in objects if o not in boxes and o not in lids]
    assert boxes and lids and small
    assert all(0.03 <= o.size_z_m <= 0.08 and max(o.size_x_m, o.size_y_m) <= 0.30 for o in boxes)
    assert all(not o.is_open and o.radius_m <= 0.10 for o in lids)
    assert all(o.mass_kg > 0 for o in objects)  # every true mass drawn
    assert all(S.MIN_WIDTH_M <= grasp_width_m(o) <= S.MAX_WIDTH_M for o in small)  # the fingers take them
    surfaces = {o.surface for o in boxes + lids}
    assert surfaces == {"smooth", "porous", "ribbed"}
    assert {o.surface for o in small} == {"smooth"}
    heavy = [o for o in boxes + lids if o.mass_kg >= 3.0]
    assert heavy and all(o.mass_kg <= 5.0 for o in heavy)
    assert len(heavy) < len(boxes + lids) / 3
    assert all(0.1 <= o.mass_kg <= 1.5 for o in boxes + lids if o not in heavy)


def test_a_side_is_taken_only_where_the_tool_lying_level_clears_the_table() -> None:
    from clearcli.settings.tree import load_settings

    hybrid = load_settings(None, ["robot.name=panda-hybrid"]).suction  # the hand's 21 cm round the cup
    assert hybrid.body_radius_m == pytest.approx(0.105)
    # porous on top, smooth sides 7 cm tall: an EPick (body 4 cm round) seals on a side
    # at 4 cm; the hand's cup would have to be 10.5 cm up, past the top
    low = S.Box(0, 0.2, 0.15, 0.07, 0.0, 0.0, mass_kg=0.3, surface="porous")
    assert world_suction_holds(low, CUP)
    assert not world_suction_holds(low, hybrid)
    gripper = GripperSettings()
    assert not truly_ungraspable_by(low, gripper, ("pinch", "suction"))
    assert truly_ungraspable_by(low, gripper, ("pinch", "suction"), hybrid)
    # 14 cm tall: the hand's cup on a side at 10.5 cm (its lip up to 12 cm)
    tall = replace(low, size_z_m=0.14)
    assert world_suction_holds(tall, hybrid)
    assert not truly_ungraspable_by(tall, gripper, ("pinch", "suction"), hybrid)
