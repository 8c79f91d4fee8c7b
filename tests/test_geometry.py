"""Object models, gripper model and poses, checked against hand-derived values."""

from __future__ import annotations

import numpy as np
import pytest

from clearcli.errors import SettingsError
from clearcli.geometry.gripper import gripper_model, load_gripper_settings
from clearcli.geometry.models import DegenerateObject, TableFrame, build_object, column_tops
from clearcli.settings.geometry import GripperSettings
from clearcli.perception.types import TablePlane
from clearcli.predicates.state_builder import compute_state
from clearcli.predicates.synthetic import Box, camera_pose, make_scene
from clearcli.settings import Settings, settings_from_dict

BOX = (0.10, 0.05, 0.05)


def one_box(box: Box, settings: Settings | None = None):
    frame, seg = make_scene([box])
    state = compute_state(frame, seg, settings or Settings())
    return state, state.objects[0]


def world_to_camera(v: np.ndarray) -> np.ndarray:
    """A world-frame direction in the synthetic camera's frame."""
    return camera_pose()[:3, :3].T @ np.asarray(v, float)


def world_point_to_camera(p: np.ndarray) -> np.ndarray:
    T = camera_pose()
    return T[:3, :3].T @ (np.asarray(p, float) - T[:3, 3])


# ------------------------------------------------------------------------------ table frame
def test_table_frame_axes_and_heights() -> None:
    n = np.array([0.0, -0.8, -0.6])
    table = TablePlane(normal=n, offset=0.7)
    tf = TableFrame.from_plane(table)
    R = tf.T_camera_table[:3, :3]
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-12) and np.isclose(np.linalg.det(R), 1.0)
    assert np.allclose(R[:, 2], n)
    assert R[2, 0] > 0  # table x: the camera's forward axis, flattened
    p = np.array([[0.1, 0.3, 0.9], [-0.2, 0.1, 1.2]])
    assert np.allclose(tf.to_table(p)[:, 2], table.height_of(p))
    assert np.allclose(tf.to_camera(tf.to_table(p)), p)


def test_column_tops_keep_the_highest_point_per_cell() -> None:
    q = np.array([[0.001, 0.001, 0.01], [0.002, 0.002, 0.05], [0.012, 0.001, 0.02], [0.004, 0.003, 0.03]])
    tops = column_tops(q, 0.005)
    assert sorted(tops[:, 2].tolist()) == [0.02, 0.05]


# ------------------------------------------------------------------------------ object model
def test_box_model_extents_axes_and_hull() -> None:
    state, obj = one_box(Box((0.0, 0.0), BOX, yaw_deg=30.0))
    assert np.allclose(obj.extents_m, [0.10, 0.05, 0.05], atol=0.004)
    # row 2 is the table normal; rows orthonormal
    assert np.allclose(obj.principal_axes @ obj.principal_axes.T, np.eye(3), atol=1e-9)
    assert np.allclose(obj.principal_axes[2], state.table.normal, atol=1e-9)
    yaw = np.radians(30.0)
    long_axis = world_to_camera([np.cos(yaw), np.sin(yaw), 0.0])
    assert abs(obj.principal_axes[0] @ long_axis) > 0.999
    # the hull reaches down to the table and up to the top, not beyond the box
    h = state.table.height_of(obj.hull_vertices)
    assert h.min() == pytest.approx(0.0, abs=1e-6) and h.max() == pytest.approx(0.05, abs=0.002)
    assert obj.height_m == pytest.approx(0.05, abs=0.002)
    # centroid of the sampled points lies within the box
    c = state.table.height_of(obj.centroid[None])[0]
    assert 0.0 < c < 0.05


def test_hull_is_solid_for_a_box_seen_from_above() -> None:
    """Points hidden from the camera (the far sides, the bottom) are inside the model."""
    import trimesh

    state, obj = one_box(Box((0.0, 0.0), BOX))
    mesh = trimesh.Trimesh(obj.hull_vertices, obj.hull_faces, process=False)
    assert mesh.is_watertight and mesh.volume == pytest.approx(0.10 * 0.05 * 0.05, rel=0.05)
    # faces are outward: hidden points are behind every face plane, an outside one is not
    hidden = np.array([world_point_to_camera(p) for p in ([0.049, 0.0, 0.001], [0.0, 0.024, 0.001], [0.0, 0.0, 0.001])])
    v = obj.hull_vertices[obj.hull_faces]
    normals = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    side = np.einsum("fj,pfj->pf", normals, hidden[:, None, :] - v[None, :, 0])
    assert (side <= 1e-12).all()
    outside = world_point_to_camera([0.0, 0.035, 0.01])
    assert (np.einsum("fj,fj->f", normals, outside - v[:, 0]) > 0).any()


def test_degenerate_inputs_raise() -> None:
    tf = TableFrame.from_plane(TablePlane(normal=np.array([0.0, -0.8, -0.6]), offset=0.7))
    with pytest.raises(DegenerateObject):
        build_object(np.zeros((3, 3)), tf, 0)
    line = np.column_stack([np.linspace(0, 0.1, 50), np.zeros(50), np.full(50, 0.5)])
    with pytest.raises(DegenerateObject):
        build_object(line, tf, 0)


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


# ------------------------------------------------------------------------------ gripper
def test_gripper_model_dimensions() -> None:
    g = gripper_model()
    corners = g.boxes(closed=False).corners()
    fingers = corners[:2]
    # inner faces at +/- opening / 2, outer at + thickness; tips at +closing_region / 2
    assert sorted(np.abs(fingers[..., 0]).min(axis=1)) == pytest.approx([0.035, 0.035])
    assert np.abs(fingers[..., 0]).max() == pytest.approx(0.045)
    assert fingers[..., 2].max() == pytest.approx(0.0225)
    assert fingers[..., 2].min() == pytest.approx(0.0225 - 0.06)
    closed = g.boxes(closed=True).corners()[:2]
    assert np.abs(closed[..., 0]).min() == pytest.approx(0.015)
    base = corners[2]
    assert base[:, 2].max() == pytest.approx(0.0225 - 0.06) and base[:, 2].min() == pytest.approx(0.0225 - 0.115)
    mesh = g.mesh(closed=False)
    assert mesh.bounds[1][2] == pytest.approx(0.0225)


def test_gripper_from_toml_file(tmp_path) -> None:
    path = tmp_path / "wide.toml"
    path.write_text("[gripper]\nopening_width_m = 0.12\nfinger_thickness_m = 0.015\n")
    s = load_gripper_settings(path)
    assert s.opening_width_m == 0.12 and s.closing_width_m == GripperSettings().closing_width_m
    g = gripper_model(s)
    assert np.abs(g.boxes(False).corners()[:2, :, 0]).max() == pytest.approx(0.075)
    # top-level keys work too; unknown keys and impossible values do not
    (tmp_path / "flat.toml").write_text("opening_width_m = 0.09\n")
    assert load_gripper_settings(tmp_path / "flat.toml").opening_width_m == 0.09
    (tmp_path / "typo.toml").write_text("[gripper]\nopening_widht_m = 0.09\n")
    with pytest.raises(SettingsError):
        load_gripper_settings(tmp_path / "typo.toml")
    (tmp_path / "bad.toml").write_text("[gripper]\nclosing_width_m = 0.2\n")
    with pytest.raises(SettingsError):
        load_gripper_settings(tmp_path / "bad.toml")


def test_wider_gripper_makes_a_wide_box_graspable() -> None:
    wide = Box((0.0, 0.0), (0.15, 0.09, 0.04))
    state, _ = one_box(wide)
    assert ("ungraspable", "o0") in state.facts
    cfg = settings_from_dict({"gripper": {"opening_width_m": 0.12}})
    state2, _ = one_box(wide, cfg)
    assert ("ungraspable", "o0") not in state2.facts


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
    # contacts switched off here: tests/test_clearing.py counts those)
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
