"""Tests of clearcli/geometry/poses.py."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from helpers.clearing import _settings
from helpers.geometry import BOX, one_box, world_point_to_camera, world_to_camera

from clearcli.geometry.poses import raised_contact_lifts
from clearcli.predicates.synthetic import Box
from clearcli.settings import settings_from_dict
from clearcli.settings.geometry import PushSettings
from clearcli.sim import scene as S


def test_raised_contact_heights_by_hand() -> None:
    push = PushSettings()  # fingertips at 0.01 m; raised at 0.03, 0.05, 0.07; friction 0.4
    closing = 0.045
    # 12 cm along the push, 12 cm tall. Fingertips at 0.07: the band 0.07-0.115 meets
    # 4.5 cm of the face; its middle 0.0925 m x 0.4 = 0.037 < 0.06 (half the length)
    assert raised_contact_lifts(push, closing, 0.12, 0.12) == pytest.approx([0.02, 0.04, 0.06])
    # 6 cm tall: at 0.05 the band 0.05-0.06 meets only 1 cm of the face (< 1.5 cm)
    assert raised_contact_lifts(push, closing, 0.12, 0.06) == pytest.approx([0.02])
    # 3 cm along the push, 14 cm tall: at 0.03 the middle 0.0525 x 0.4 = 0.021 > 0.015
    # (half of 3 cm): the object would tip over its front edge
    assert raised_contact_lifts(push, closing, 0.03, 0.14) == []
    # 8 cm along: 0.03 (0.021 <= 0.04) and 0.05 (0.0725 x 0.4 = 0.029) pass; 0.07
    # (0.0925 x 0.4 = 0.037 <= 0.04) too
    assert raised_contact_lifts(push, closing, 0.08, 0.14) == pytest.approx([0.02, 0.04, 0.06])
    assert raised_contact_lifts(push, closing, 0.07, 0.14) == pytest.approx([0.02, 0.04])
    # switched off
    assert raised_contact_lifts(dataclasses.replace(push, raised_fingertips_m=()), closing, 0.12, 0.12) == []


def test_raised_push_not_offered_where_the_object_would_tip() -> None:
    from clearcli.geometry.gripper import gripper_model
    from clearcli.geometry.models import TableFrame
    from clearcli.geometry.poses import push_geometry

    settings = _settings()
    # a narrow tall box (3 x 3 x 14 cm): no raised contact in any direction
    narrow = S.make_scene("narrow", [S.Box(0, 0.03, 0.03, 0.14, x_m=0.0, y_m=0.05)])
    # a long box (12 x 5 x 12 cm): raised contacts along its length
    long_box = S.make_scene("long", [S.Box(0, 0.12, 0.05, 0.12, x_m=0.0, y_m=0.05)])
    gripper = gripper_model(settings.gripper)

    def n_options(world: S.Scene) -> dict[str, int]:
        from clearcli.geometry.models import build_from_columns, object_columns
        from clearcli.sim.camera import render
        from clearcli.sim.truth import truth_segment

        frame = render(world, seed=4)
        seg = truth_segment(frame)
        tf = TableFrame.from_plane(seg.table)
        cols = object_columns(frame.points, [o.indices for o in seg.objects], tf, settings.predicates.model_cell_m)
        geom = build_from_columns(cols[0], 0, settings.predicates)
        pushes = push_geometry(geom, gripper, settings.push)
        return {d: 1 + len(p.alternatives) for d, p in pushes.items()}

    # two yaws per direction, nothing raised
    assert n_options(narrow) == {"dir1": 2, "dir2": 2, "dir3": 2, "dir4": 2}
    # along the 12 cm length: 2 yaws x (standard + 3 raised); across the 5 cm width,
    # fingertips at 0.03 only (middle 0.0525 x 0.4 = 0.021 <= 0.025; at 0.05, 0.029)
    long_options = n_options(long_box)
    assert long_options["dir1"] == long_options["dir2"] == 8
    assert long_options["dir3"] == long_options["dir4"] == 4


# ------------------------------------------------------------------------------ directions
def test_directions_sign_rule_and_relations() -> None:
    state, obj = one_box(Box((0.0, 0.0), BOX, yaw_deg=100.0))
    u = {d: p.unit_vector for d, p in obj.pushes.items()}
    n = state.table.normal
    for v in u.values():
        assert np.linalg.norm(v) == pytest.approx(1.0) and abs(v @ n) < 1e-9
    assert np.allclose(u["dir2"], -u["dir1"]) and np.allclose(u["dir4"], -u["dir3"])
    assert np.allclose(u["dir3"], np.cross(n, u["dir1"]))
    # dir1 points away from the camera: positive along the flattened optical axis
    forward = np.array([0.0, 0.0, 1.0]) - n[2] * n
    assert u["dir1"] @ forward > 0
    # yaw 100 deg: the long axis is (cos 100, sin 100); away from the camera = world +x
    # is the opposite sense, so dir1 = -(cos 100, sin 100)
    yaw = np.radians(100.0)
    assert np.allclose(u["dir1"], world_to_camera([-np.cos(yaw), -np.sin(yaw), 0.0]), atol=0.01)


# ------------------------------------------------------------------------------ poses
def test_grasp_pose() -> None:
    state, obj = one_box(Box((0.0, 0.0), (0.10, 0.05, 0.08)))
    n = state.table.normal
    # the centred grasp's two half-turns first; then (IK fallbacks) the off-centre ones
    (pre, grasp, lift), (pre2, grasp2, lift2) = obj.grasp_candidates[:2]
    assert len(obj.grasp_candidates) == 6  # 10 cm long: 3 cm either way along it, 2 half-turns each
    x, z, p = grasp[:3, 0], grasp[:3, 2], grasp[:3, 3]
    assert np.allclose(z, -n, atol=0.02)  # approach straight down for a box lying flat
    assert abs(x @ obj.pushes["dir1"].unit_vector) < 0.02  # closing across the long axis
    # closing point: top centroid (0.08) moved down by half the closing region (0.0225)
    assert state.table.height_of(p[None])[0] == pytest.approx(0.0575, abs=0.002)
    assert np.allclose(p, world_point_to_camera([0.0, 0.0, 0.0575]), atol=0.004)
    assert np.allclose(pre[:3, 3], p - 0.10 * z)
    assert np.allclose(lift[:3, 3], p + 0.10 * n)
    # the other half-turn candidate: same point and approach, closing reversed
    assert np.allclose(grasp2[:3, 3], p) and np.allclose(grasp2[:3, 2], z) and np.allclose(grasp2[:3, 0], -x)
    for T in (pre, grasp, lift, grasp2):
        R = T[:3, :3]
        assert np.allclose(R.T @ R, np.eye(3), atol=1e-9) and np.isclose(np.linalg.det(R), 1.0)
    assert obj.grasp_width_m == pytest.approx(0.05, abs=0.003)


@pytest.mark.parametrize("height", [0.02, 0.05])
def test_low_object_grasp_keeps_fingertips_above_table(height: float) -> None:
    state, obj = one_box(Box((0.0, 0.0), (0.10, 0.05, height)))
    p = obj.grasp_candidates[0][1][:3, 3]
    # height - 0.0225 - 0.0225 would put the tips below 0.01: raised to tips at 0.01
    assert state.table.height_of(p[None])[0] == pytest.approx(0.01 + 0.0225, abs=1e-6)


def test_push_poses_and_paths() -> None:
    # the two half-turns of the documented yaw, then those of the other yaw (raised
    # contacts switched off here: the raised-contact tests below count those)
    _, plain = one_box(Box((0.0, 0.0), BOX), settings_from_dict({"push": {"raised_fingertips_m": []}}))
    assert all(len(plain.pushes[d].candidates) == 4 for d in ("dir1", "dir2", "dir3", "dir4"))
    state, obj = one_box(
        Box((0.0, 0.0), BOX), settings_from_dict({"push": {"lateral_shift": True, "raised_fingertips_m": []}})
    )
    n = state.table.normal
    for d, along, extent in (("dir1", 0.025, 0.10), ("dir3", 0.015, 0.05)):
        push = obj.pushes[d]
        u = push.unit_vector
        seq = push.candidates[0]
        pre, start, path, retreat = seq[0], seq[1], seq[2:-1], seq[-1]
        x = start[:3, 0]
        if d == "dir1":
            assert abs(abs(x @ u) - 1.0) < 1e-9  # closing direction parallel to the push
        else:
            assert abs(x @ u) < 1e-9  # orthogonal
        assert np.allclose(start[:3, 2], -n)
        p = start[:3, 3]
        # fingertips (0.0225 past the closing point) 0.01 above the table
        assert state.table.height_of(p[None])[0] - 0.0225 == pytest.approx(0.01, abs=1e-9)
        # the fingers' front 0.03 behind the object's rear face (at -extent / 2 along u)
        centre_along = world_point_to_camera([0, 0, 0]) @ u
        front = p @ u + along
        assert front == pytest.approx(centre_along - extent / 2 - 0.03, abs=0.003)
        assert np.allclose(pre[:3, 3], p + 0.10 * n)
        assert push.push_length_m == pytest.approx(extent, abs=0.004)
        steps = np.diff(np.array([p] + [T[:3, 3] for T in path]), axis=0)
        assert np.all(np.linalg.norm(steps, axis=1) <= 0.03 + 1e-9)
        assert np.allclose(path[-1][:3, 3], p + push.push_length_m * u)
        assert np.allclose(push.object_path[-1], push.push_length_m * u)
        assert np.allclose(retreat[:3, 3], path[-1][:3, 3] + 0.10 * n)
        assert np.allclose(push.candidates[1][1][:3, 0], -x)
        # IK fallbacks after the two half-turns (a lone box: nothing blocks any option):
        # the other yaw (2 candidates), then (lateral_shift) contact points off the middle
        # of the rear face, 5 mm short of its ends. dir1's rear face is 5 cm wide: the documented yaw
        # (a 3 cm finger across) moves 2.5 - 1.5 - 0.5 = 0.5 cm either way, the other yaw
        # (the 5 cm finger pair across) not at all. dir3's is 10 cm: 5 - 2.5 - 0.5 = 2 cm
        # for the documented yaw, 5 - 1.5 - 0.5 = 3 cm for the other.
        side = np.cross(n, u)
        starts = [c[1][:3, 3] for c in push.candidates]
        shifts = {"dir1": [0.005], "dir3": [0.02, 0.03]}[d]
        assert len(push.candidates) == 4 + 4 * len(shifts)
        assert abs(float((starts[2] - p) @ side)) < 1e-9  # the other yaw: centred
        offsets = sorted(abs(round(float((t - p) @ side), 4)) for t in starts[4:])
        assert offsets == pytest.approx(sorted(v for v in shifts for _ in range(4)), abs=1e-4)
        assert all(abs(float(t @ n - p @ n)) < 1e-9 for t in starts)  # all at the same height


def test_push_length_is_capped() -> None:
    cfg = settings_from_dict({"push": {"pushing_step": 10.0}})
    _, obj = one_box(Box((0.0, 0.0), BOX), cfg)
    assert obj.pushes["dir1"].push_length_m == pytest.approx(0.6)
    assert obj.pushes["dir3"].push_length_m == pytest.approx(0.5, abs=0.04)


# ------------------------------------------------------------------------------ push poses
def _push_sequence_one_by_one(
    x: np.ndarray, start: np.ndarray, up_approach: np.ndarray, translations: np.ndarray, n: int
) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]:
    """A push's two candidates built pose by pose, as before they were built together:
    rotation columns x, z cross x, z (z down), then the half turn's -x, z cross -x, z."""
    from clearcli.transforms import cross3

    down = -np.array([0.0, 0.0, 1.0])

    def pose(xx: np.ndarray) -> np.ndarray:
        T = np.eye(4)
        T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = xx, cross3(down, xx), down, start
        return T

    T, T_turned = pose(x), pose(-x)
    seq = np.repeat(T[None], n + 3, axis=0)
    seq[0, :3, 3] += up_approach
    seq[2:-1, :3, 3] += translations
    seq[-1, :3, 3] += translations[-1] + up_approach
    turned = seq.copy()
    turned[:, :3, :3] = T_turned[:3, :3]
    return tuple(seq), tuple(turned)


def test_push_variants_built_together_are_those_built_one_by_one() -> None:
    """`_push_sequences` (an object's variants of one direction at once) gives each
    variant's poses bit for bit as building it alone does, signs of zero included."""
    from clearcli.geometry.poses import _push_sequence, _push_sequences

    gen = np.random.default_rng(8)
    up_approach = np.array([0.0, 0.0, 0.05])
    for n in (1, 3, 7):
        angles = gen.uniform(-np.pi, np.pi, size=6)
        xs = np.column_stack([np.cos(angles), np.sin(angles), np.zeros(6)])
        xs[0] = (1.0, 0.0, 0.0)  # axis-aligned: products that come out zero
        xs[1] = (0.0, -1.0, 0.0)
        starts = gen.uniform(-0.5, 0.5, size=(6, 3))
        d = xs[2]
        translations = (0.04 * np.arange(1, n + 1) / n)[:, None] * d[None, :]
        together = _push_sequences(xs, starts, up_approach, translations, n)
        assert len(together) == 6
        for k in range(6):
            want = _push_sequence_one_by_one(xs[k], starts[k], up_approach, translations, n)
            for got_seq, want_seq in (
                (together[k], want),
                (_push_sequence(xs[k], starts[k], up_approach, translations, n), want),
            ):
                for got_half, want_half in zip(got_seq, want_seq, strict=True):
                    assert len(got_half) == n + 3
                    for got_T, want_T in zip(got_half, want_half, strict=True):
                        assert got_T.tobytes() == want_T.tobytes()
