"""Tests of clearcli/geometry/suction.py: the seal and the load, against surfaces and
figures worked out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from clearcli.geometry.suction import (
    UP,
    Contact,
    CupSpec,
    FaceFrame,
    FaceJob,
    ObjectJob,
    disc_cells,
    hull_volume_and_centroid,
    judge_face,
    judge_faces,
    judge_object,
    judge_objects,
    load_margin,
    quadric_design,
    sags,
    volume_above,
)

# a 30 mm cup, 5 mm of bellows, 40 N, factor 2, lip friction 0.5, 20 deg, 4 mm gaps
SPEC = CupSpec(0.03, 0.005, 40.0, 2.0, 0.5, 20.0, 0.004)
STEP = 0.002  # a Kinect's point spacing at ~1 m
NONE = np.zeros((0, 3))


def _grid(half: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    g = np.arange(-half, half + 1e-9, STEP)
    u, v = np.meshgrid(g, g)
    return u.ravel(), v.ravel()


def _flat(z: float = 0.1, half: float = 0.05) -> np.ndarray:
    u, v = _grid(half)
    return np.stack([u, v, np.full_like(u, z)], axis=1)


TOP = FaceFrame("top", np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), UP)


def _judge(points: np.ndarray, centre: tuple[float, float] = (0.0, 0.0), others: np.ndarray = NONE, frame=TOP):
    """The place of the face whose cup is centred nearest ``centre`` (along e1, e2)."""
    places = judge_face(points, others, frame, SPEC)
    assert places is not None and len(places)
    along = places.points @ np.stack([frame.e1, frame.e2]).T
    return places.contact(int(np.argmin(np.hypot(*(along - np.asarray(centre)).T))))


def test_a_flat_face_seals_with_nothing_bent_or_spread() -> None:
    c = _judge(_flat())
    assert c.why == "" and c.seal_margin > 0.5
    assert c.sag_m == pytest.approx(0.0, abs=1e-9) and c.spread_m == pytest.approx(0.0, abs=1e-9)
    # the cup over a cell whose centre is nearest (0, 0): 2 mm off in x and y
    assert c.covered == 1.0 and np.abs(c.point) == pytest.approx([0.002, 0.002, 0.1], abs=1e-9)


def test_a_flat_face_seen_with_kinect_noise_still_seals() -> None:
    # 1.5 mm of depth noise: the quadric's bending averages it out, the spread stays
    # under 0.6 x 5 mm
    pts = _flat()
    pts[:, 2] += np.random.default_rng(0).normal(0.0, 0.0015, len(pts))
    c = _judge(pts)
    assert c.why == "", c.why
    assert c.sag_m < 0.0025


def test_a_cylinder_of_radius_2_cm_is_curved_beyond_the_bellows() -> None:
    # its side under a 30 mm cup bends r^2 / (2 R) ~ 15^2 / 40 = 5.6 mm (the circle's
    # exact sag 20 - sqrt(20^2 - 15^2) = 6.8 mm): more than the 5 mm of bellows
    R = 0.02
    u = np.arange(-0.05, 0.05 + 1e-9, STEP)
    a = np.arange(-math.pi / 2, math.pi / 2, STEP / R)
    uu, aa = np.meshgrid(u, a)
    pts = np.stack([uu.ravel(), R * np.sin(aa.ravel()), 0.08 + R * np.cos(aa.ravel())], axis=1)
    c = _judge(pts)
    assert c.seal_margin < 0 and "curved" in c.why
    assert 0.005 < c.sag_m < 0.0075


def test_a_sphere_of_radius_2_cm_is_curved_and_one_of_10_cm_seals() -> None:
    def sphere(R: float) -> np.ndarray:
        u, v = _grid()
        keep = u * u + v * v < R * R
        return np.stack([u[keep], v[keep], 0.1 - R + np.sqrt(R * R - u[keep] ** 2 - v[keep] ** 2)], axis=1)

    small = _judge(sphere(0.02))
    assert small.seal_margin < 0 and "curved" in small.why
    large = _judge(sphere(0.10))
    # bending 15^2 / (2 * 100) = 1.1 mm: within the bellows
    assert large.why == "" and large.sag_m == pytest.approx(0.015**2 / 0.2, rel=0.15)


def test_a_ribbed_top_is_rough() -> None:
    # ribs 8 mm apart, 3 mm up and down: the lip cannot follow 6 mm grooves with 5 mm of
    # bellows; the spread about the fitted face is 3 mm > 0.6 x 5 mm
    pts = _flat()
    pts[:, 2] += 0.003 * np.sign(np.sin(2 * math.pi * pts[:, 0] / 0.008))
    c = _judge(pts)
    assert c.seal_margin < 0 and "rough" in c.why
    assert c.spread_m >= 0.003


def test_at_an_edge_the_disc_is_not_covered() -> None:
    pts = _flat()
    pts = pts[pts[:, 0] <= 0.005]  # the face ends 5 mm past the cup's centre
    c = _judge(pts)
    assert c.seal_margin < 0 and "edge" in c.why
    # the cup centred on the place nearest 0 (x = 2 mm, the centre of cell 0, places on
    # every other cell): its cells two and three columns on (x 8-16 mm) hold no point: 5
    # and 3 of its 37 cells
    assert c.covered == pytest.approx(29 / 37)
    # 20 mm in from the end it seals
    assert _judge(pts, (-0.02, 0.0)).why == ""


def test_a_hole_under_the_cup_is_not_covered() -> None:
    pts = _flat()
    pts = pts[np.hypot(pts[:, 0] - 0.008, pts[:, 1]) > 0.006]  # a 12 mm hole
    c = _judge(pts)
    assert c.seal_margin < 0 and "hole" in c.why


def test_a_lone_missed_pixel_is_no_hole() -> None:
    # one 4 mm cell with no point (the sensor missed it) under the cup: filled from its
    # neighbours, the face seals and stays flat
    pts = _flat()
    pts = pts[~((pts[:, 0] >= 0.004) & (pts[:, 0] < 0.008) & (pts[:, 1] >= 0.004) & (pts[:, 1] < 0.008))]
    c = _judge(pts)
    assert c.why == "" and c.covered < 1.0 and c.sag_m == pytest.approx(0.0, abs=1e-9)


def test_another_object_under_the_cup_spoils_the_seal_but_one_above_it_does_not() -> None:
    other_in_seal = np.array([[0.005, 0.0, 0.101]])
    assert "another object" in _judge(_flat(), others=other_in_seal).why
    # 10 cm above the face it is in the approach's way (a blocker), not in the seal
    far_above = np.array([[0.005, 0.0, 0.2]])
    assert _judge(_flat(), others=far_above).why == ""


def test_a_tilted_face_beyond_the_limit_is_refused() -> None:
    pts = _flat()
    for deg, ok in ((10.0, True), (30.0, False)):
        t = math.radians(deg)
        tilted = pts.copy()
        tilted[:, 2] = 0.1 + math.tan(t) * pts[:, 0]
        c = _judge(tilted)
        assert c.tilt_deg == pytest.approx(deg, abs=0.2)
        assert (c.why == "") is ok, c.why


def test_the_quadric_bending_is_the_largest_curvature_times_r_squared() -> None:
    # w = 2 u^2 - 3 v^2: half the Hessian has eigenvalues 2 and -3: the sag over r = 0.01
    # is 3 x 0.01^2 = 3e-4
    u, v = _grid(0.01)
    A = quadric_design(np.stack([u, v], axis=1))
    coef, *_ = np.linalg.lstsq(A, 2 * u * u - 3 * v * v, rcond=None)
    assert sags(coef[None], 0.01)[0] == pytest.approx(3e-4)


def test_the_disc_cells_lie_within_the_cup() -> None:
    # a 30 mm cup on 4 mm cells: offsets up to 3 cells, those within 14.25 mm / 4 mm =
    # 3.56 cells of the centre (squared distance <= 12): 1 + 4 + 4 + 4 + 8 + 4 + 4 + 8 = 37
    d = disc_cells(0.015, 0.004)
    assert len(d) == 37 and tuple(d[0]) == (0, 0)
    assert np.hypot(d[:, 0], d[:, 1]).max() * 0.004 <= 0.95 * 0.015


# The load, by hand: 40 N, factor 2: a pull alone holds up to 20 N (2.04 kg).


def _contact(point: tuple[float, float, float], normal: tuple[float, float, float] = (0.0, 0.0, 1.0)) -> Contact:
    return Contact("top", np.array(point), np.array(normal), 1.0, 0.0, 0.0, 0.0, 0, 1.0)


def test_a_pull_alone_uses_the_force_over_the_safety_factor() -> None:
    c = _contact((0.0, 0.0, 0.1))
    margin, why = load_margin(c, 1.0, np.array([0.0, 0.0, 0.05]), SPEC)
    # 9.81 N x 2 / 40 N = 0.4905 used
    assert margin == pytest.approx(1 - 2 * 9.81 / 40) and why == ""
    margin, why = load_margin(c, 2.2, np.array([0.0, 0.0, 0.05]), SPEC)
    assert margin < 0 and "too heavy" in why and "pull 21.6 N" in why


def test_a_heavy_box_holds_from_its_centre_but_not_from_its_end() -> None:
    # a 1.5 kg box, 0.2 m long: from the centre 2 x 14.7 / 40 = 0.74 used; from 8 cm off
    # the centre the moment 14.7 N x 0.08 m = 1.18 N m against 40 N x 0.015 m adds 3.9
    com = np.array([0.0, 0.0, 0.05])
    centre, _ = load_margin(_contact((0.0, 0.0, 0.1)), 1.5, com, SPEC)
    assert centre == pytest.approx(1 - 2 * 1.5 * 9.81 / 40)
    end, why = load_margin(_contact((0.08, 0.0, 0.1)), 1.5, com, SPEC)
    expected = 1 - 2 * (1.5 * 9.81 / 40 + 1.5 * 9.81 * 0.08 / (40 * 0.015))
    assert end == pytest.approx(expected) and end < 0
    assert "moment 1.18 N m" in why


def test_a_side_face_seals_and_holds_by_friction() -> None:
    # a vertical face x = 0.1 m facing +x: it seals; the weight slides along the lip:
    # shear 0.5 kg x 9.81 = 4.9 N against 0.5 x 40 N, factor 2; the centre of mass 3 cm
    # behind the face adds a moment of 4.9 N x 0.03 m
    u, v = _grid()
    pts = np.stack([np.full_like(u, 0.1), u, 0.1 + v], axis=1)
    x = np.array([1.0, 0.0, 0.0])
    side = FaceFrame("side", np.array([0.0, 1.0, 0.0]), UP, x)
    c = _judge(pts, (0.0, 0.1), frame=side)
    assert c.why == "" and c.normal == pytest.approx(x)
    margin, _ = load_margin(_contact((0.1, 0.0, 0.1), (1.0, 0.0, 0.0)), 0.5, np.array([0.07, 0.0, 0.1]), SPEC)
    w = 0.5 * 9.81
    assert margin == pytest.approx(1 - 2 * (w / 20 + w * 0.03 / (40 * 0.015)))


def _box_mesh(lo: np.ndarray, size: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A box's 8 corners and its 12 triangles, outward."""
    from scipy.spatial import ConvexHull

    corners = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], dtype=float) * size + lo
    faces = ConvexHull(corners).simplices.copy()
    centre = corners.mean(axis=0)
    for f in faces:  # outward
        n = np.cross(corners[f[1]] - corners[f[0]], corners[f[2]] - corners[f[0]])
        if n @ (corners[f[0]] - centre) < 0:
            f[[1, 2]] = f[[2, 1]]
    return corners, faces


def test_hull_volume_and_centroid_of_a_box() -> None:
    # a 0.1 x 0.2 x 0.3 box from (1, 2, 3): 0.006 m^3, centre (1.05, 2.1, 3.15)
    corners, faces = _box_mesh(np.array([1.0, 2.0, 3.0]), np.array([0.1, 0.2, 0.3]))
    vol, com = hull_volume_and_centroid(corners, faces)
    assert vol == pytest.approx(0.006) and com == pytest.approx([1.05, 2.1, 3.15])


def test_a_box_lying_flat_wider_than_any_opening_is_taken_from_the_top() -> None:
    # a cereal box lying flat, 0.3 x 0.2 x 0.08 m, its top and a side seen
    u = np.arange(-0.15, 0.15 + 1e-9, STEP)
    v = np.arange(-0.10, 0.10 + 1e-9, STEP)
    uu, vv = np.meshgrid(u, v)
    top = np.stack([uu.ravel(), vv.ravel(), np.full(uu.size, 0.08)], axis=1)
    z = np.arange(0.0, 0.08, STEP)
    zz, uu2 = np.meshgrid(z, u)
    side = np.stack([uu2.ravel(), np.full(uu2.size, -0.10), zz.ravel()], axis=1)
    pts = np.concatenate([top, side])
    axes2d = np.array([[1.0, 0.0], [0.0, 1.0]])
    judged = judge_object(pts, NONE, axes2d, 0.08, 0.4, np.array([0.0, 0.0, 0.04]), SPEC, 0.045)
    assert judged.best is not None and judged.best.face == "top"
    # the best is the place nearest the centre of mass (the smallest moment): the cell
    # centre nearest it, 2 mm off in x and y
    assert np.hypot(*judged.best.point[:2]) <= 0.003
    # a side's cup stays 0.045 m up (the tool clears the table) and a radius below the top
    sides = [c for c in judged.ranked if c.face == "side"]
    assert all(0.045 <= c.point[2] <= 0.065 for c in sides)
    assert judged.n_kept > 100 and judged.why_not(SPEC) == ""


# ---------------------------------------------------------------- what stands on it
# a camera 1 m above the table and 0.6 m back (table frame: x away from it), looking at
# the table's origin: T_camera_table maps table points into its frame (z forward)
def _camera(eye: tuple[float, float, float] = (-0.6, 0.0, 1.0)) -> np.ndarray:
    eye_a = np.asarray(eye)
    z = -eye_a / np.linalg.norm(eye_a)
    x = np.cross(z, UP)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    R_table_camera = np.column_stack([x, y, z])
    T = np.eye(4)
    T[:3, :3] = R_table_camera.T
    T[:3, 3] = -R_table_camera.T @ eye_a
    return T


def _box_top_with_a_can_on_it() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A box lying flat (0.3 x 0.2, top at 0.08 m) and a can (radius 4 cm, 0.15 m tall)
    standing on its middle: the box's top as the camera sees it (the can's footprint and
    the shadow behind it removed, by casting each top point's ray at the can), and the
    can's points (its top and the side facing the camera)."""
    T = _camera()
    eye = -T[:3, :3].T @ T[:3, 3]
    u = np.arange(-0.15, 0.15 + 1e-9, STEP)
    v = np.arange(-0.10, 0.10 + 1e-9, STEP)
    uu, vv = np.meshgrid(u, v)
    top = np.stack([uu.ravel(), vv.ravel(), np.full(uu.size, 0.08)], axis=1)
    r, z0, z1 = 0.04, 0.08, 0.23
    # a top point is hidden where its ray from the eye passes within the can
    s = np.linspace(0.0, 1.0, 200)[None, :, None]
    ray = eye + s * (top[:, None, :] - eye)
    inside = (np.hypot(ray[..., 0], ray[..., 1]) < r) & (ray[..., 2] > z0) & (ray[..., 2] < z1)
    seen = top[~inside[:, :-1].any(axis=1) & (np.hypot(top[:, 0], top[:, 1]) >= r)]
    a = np.arange(0.0, 2 * np.pi, STEP / r)
    h = np.arange(z0, z1, STEP)
    aa, hh = np.meshgrid(a, h)
    side = np.stack([r * np.cos(aa.ravel()), r * np.sin(aa.ravel()), hh.ravel()], axis=1)
    side = side[side[:, 0] < 0]  # the half facing the camera (it stands at -x)
    g = np.arange(-r, r + 1e-9, STEP)
    gx, gy = np.meshgrid(g, g)
    lid = np.stack([gx.ravel(), gy.ravel(), np.full(gx.size, z1)], axis=1)
    can = np.concatenate([side, lid[np.hypot(lid[:, 0], lid[:, 1]) <= r]])
    return seen, can, T


def test_where_what_stands_on_it_hides_the_top_the_top_goes_on() -> None:
    seen, can, T = _box_top_with_a_can_on_it()
    axes2d = np.array([[1.0, 0.0], [0.0, 1.0]])
    com = np.array([0.0, 0.0, 0.04])
    # a heavy box (1.5 kg: only a place within ~6 mm of its centre holds it): without the
    # can the hole it leaves is a hole; with it, the top goes on under the can
    blind = judge_object(seen, NONE, axes2d, 0.08, 1.5, com, SPEC, 0.045)
    told = judge_object(seen, NONE, axes2d, 0.08, 1.5, com, SPEC, 0.045, can, T)
    assert blind.best is None
    assert told.best is not None and np.hypot(*told.best.point[:2]) <= 0.01
    assert told.best.point[2] == pytest.approx(0.08, abs=1e-6)
    # the hidden cells are the can's footprint and its shadow on the far side, not the
    # near side the camera sees: the box's near half keeps its own points
    places = judge_face(seen, NONE, TOP, SPEC, hidden_by=can, T_camera_table=T)
    assert places is not None
    assert len(places) > len(judge_face(seen, NONE, TOP, SPEC))
    # the world's edge stays an edge: no place beyond the box's outline
    assert np.all(np.abs(places.points[:, 0]) <= 0.152) and np.all(np.abs(places.points[:, 1]) <= 0.102)


def test_the_reason_when_places_seal_but_none_holds_is_the_weight() -> None:
    # a flat top with a hole in one corner: the nearest miss by margin is a hole, but
    # the top seals elsewhere: what stops the cup is the 10 kg
    pts = _flat(half=0.08)
    pts = pts[~((pts[:, 0] > 0.05) & (pts[:, 1] > 0.05) & (pts[:, 0] < 0.07) & (pts[:, 1] < 0.07))]
    judged = judge_object(pts, NONE, np.eye(2), 0.1, 10.0, np.array([0.0, 0.0, 0.05]), SPEC, 0.045)
    assert judged.best is None
    assert judged.why_not(SPEC).startswith("too heavy for the cup: ~10.00 kg")


def test_an_object_standing_on_another_weighs_what_lies_above_its_bottom() -> None:
    # a 0.2 x 0.1 footprint; its solid modelled down to the table from a top at 0.3 m;
    # it stands on something 0.25 m high: its own volume is 0.2 x 0.1 x 0.05 = 1 L
    corners, faces = _box_mesh(np.zeros(3), np.array([0.2, 0.1, 0.3]))
    footprint = np.array([[0.0, 0.0], [0.2, 0.0], [0.2, 0.1], [0.0, 0.1]])
    vol, com = volume_above(corners, faces, footprint, 0.25)
    assert vol == pytest.approx(0.001) and com == pytest.approx([0.1, 0.05, 0.275])
    # on the table: the whole solid
    vol0, com0 = volume_above(corners, faces, footprint, 0.0)
    assert vol0 == pytest.approx(0.006) and com0 == pytest.approx([0.1, 0.05, 0.15])
    # a solid narrower low down than its footprint says (nothing left above): the prism
    # of the footprint from the bottom to the top stands for it
    vol1, com1 = volume_above(corners, faces, footprint * 2.0, 0.25)
    assert vol1 == pytest.approx(0.08 * 0.05) and com1 == pytest.approx([0.2, 0.1, 0.275])


# ---------------------------------------------------------------- many at once
def _same_contact(a: Contact | None, b: Contact | None) -> bool:
    """Every field equal to the bit (the arrays too)."""
    if a is None or b is None:
        return a is b
    return all(
        np.array_equal(getattr(a, f), getattr(b, f), equal_nan=True)
        if isinstance(getattr(a, f), np.ndarray)
        else (getattr(a, f) == getattr(b, f) or (getattr(a, f) != getattr(a, f) and getattr(b, f) != getattr(b, f)))
        for f in a.__dataclass_fields__
    )


def test_judging_objects_together_gives_each_what_it_gets_alone() -> None:
    # judge_objects bins every face at once and judges every place in one pass: each
    # object's places, margins and contacts must be those it gets alone, to the bit (a
    # matrix product's rounding depends on its rows' count: the fits stay per face)
    seen, can, T = _box_top_with_a_can_on_it()
    holed = _flat(half=0.08)
    holed = holed[~((holed[:, 0] > 0.05) & (holed[:, 1] > 0.05) & (holed[:, 0] < 0.07) & (holed[:, 1] < 0.07))]
    # a can lying on its side (radius 3 cm, curved on top): its top seals nowhere, so
    # its sides are judged too
    a, x = np.meshgrid(np.linspace(0.0, np.pi, 60), np.arange(-0.1, 0.1 + 1e-9, STEP))
    curved = np.stack([x.ravel(), 0.3 + 0.03 * np.cos(a.ravel()), 0.03 + 0.03 * np.sin(a.ravel())], axis=1)
    yawed = np.array([[np.cos(0.4), np.sin(0.4)], [-np.sin(0.4), np.cos(0.4)]])
    # a box lying flat, its top and its side at y = -0.1 seen; its top not to be tried
    u, z = np.meshgrid(np.arange(0.42, 0.58 + 1e-9, STEP), np.arange(0.0, 0.08, STEP))
    side = np.stack([u.ravel(), np.full(u.size, -0.08), z.ravel()], axis=1)
    box = np.concatenate([holed + [0.5, 0.0, -0.02], side])
    jobs = [
        ObjectJob(seen, NONE, np.eye(2), 0.08, 1.5, np.array([0.0, 0.0, 0.04]), 0.045, can, T),
        ObjectJob(holed, NONE, np.eye(2), 0.1, 0.3, np.array([0.0, 0.0, 0.05]), 0.045),
        ObjectJob(curved, seen[::7], yawed, 0.06, 0.2, np.array([0.0, 0.3, 0.03]), 0.02),
        ObjectJob(box, curved, np.eye(2), 0.08, 0.3, np.array([0.5, -0.06, 0.04]), 0.045, skip=frozenset({"top"})),
    ]
    together = judge_objects(jobs, SPEC)
    assert any(c.face == "side" for j in together for c in j.ranked)  # the sides were judged
    for job, got in zip(jobs, together):
        alone = judge_object(
            job.own, job.others, job.axes2d, job.top_height_m, job.mass_kg, job.com_table, SPEC,
            job.min_height_m, job.hidden_by, job.T_camera_table, job.skip,
        )  # fmt: skip
        assert got.order == alone.order and got.n_kept == alone.n_kept
        assert _same_contact(got.best, alone.best) and _same_contact(got.closest, alone.closest)
        assert all(_same_contact(p, q) for p, q in zip(got.ranked, alone.ranked))
        assert np.array_equal(got.points, alone.points) and np.array_equal(got.normals, alone.normals)


def test_judging_faces_together_gives_every_place_what_it_gets_alone() -> None:
    # every place of every face, each array to the bit: faces of odd and even counts of
    # places, a top hidden in part, a side, and others under the cup
    seen, can, T = _box_top_with_a_can_on_it()
    x = np.array([1.0, 0.0, 0.0])
    side = FaceFrame("side", np.array([0.0, 1.0, 0.0]), UP, x)
    u, v = _grid()
    wall = np.stack([np.full_like(u, 0.1), u, 0.1 + v], axis=1)
    bumpy = _flat(half=0.033) + [0.0, 0.0, 0.001] * np.sin(np.arange(len(_flat(half=0.033))))[:, None]
    jobs = [
        FaceJob(seen, NONE, TOP, hidden_by=can, T_camera_table=T),
        FaceJob(bumpy, NONE, TOP),
        FaceJob(wall, NONE, side, (0.09, 0.125)),
        FaceJob(_flat(half=0.031) + [0.3, 0.0, 0.0], bumpy + [0.3, 0.0, 0.002], TOP),
        FaceJob(_flat()[:2], NONE, TOP),  # two points: no face
    ]
    together = judge_faces(jobs, SPEC)
    assert together[-1] is None and len({len(p) % 2 for p in together[:-1] if p is not None}) == 2
    for job, got in zip(jobs, together):
        alone = judge_face(job.own, job.others, job.frame, SPEC, job.e2_range, job.hidden_by, job.T_camera_table)
        if alone is None:
            assert got is None
            continue
        assert got is not None
        for f in (
            "points",
            "normals",
            "covered",
            "empty",
            "full",
            "sag_m",
            "spread_m",
            "tilt_deg",
            "intruders",
            "margins",
        ):
            assert np.array_equal(getattr(got, f), getattr(alone, f)), f
