"""Tests of clearcli/predicates/grasps/suction.py: the suction kind offered on rendered
scenes, its blockers, its poses, and plans with it validated and IK-checked."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from helpers import run_clear as clear

from clearcli.io.pcd import write_pcd
from clearcli.sim import scene as S
from clearcli.sim.camera import render

# a cereal box lying flat (wider than any opening: 0.24 x 0.16 m), a can standing (its
# top 6.6 cm across), a ball-like cylinder lying... and a small box the fingers take
FLAT = S.Box(0, 0.24, 0.16, 0.06, -0.10, 0.05)
CAN = S.Cylinder(1, 0.033, 0.10, 0.12, 0.08)
SMALL = S.Box(2, 0.04, 0.04, 0.06, 0.15, -0.12)


def _pcd(tmp_path: Path, objects: list, name: str = "scene") -> Path:  # type: ignore[type-arg]
    pcd = tmp_path / f"{name}.pcd"
    write_pcd(pcd, render(S.make_scene(name, objects), seed=0))
    return pcd


def _state(pcd: Path, robot: str):  # type: ignore[no-untyped-def]
    from clearcli import pipeline
    from clearcli.predicates.state_builder import compute_state
    from clearcli.settings.tree import load_settings

    settings = load_settings(None, [f"robot.name={robot}"])
    frame = pipeline.read(pcd)
    return compute_state(frame, pipeline.segmented(frame, settings), settings), settings


def test_a_flat_box_too_wide_for_the_fingers_is_offered_suction_from_its_top(tmp_path: Path) -> None:
    state, settings = _state(_pcd(tmp_path, [FLAT, CAN, SMALL]), "panda-hybrid")
    assert len(state.objects) == 3
    flat = max(state.objects, key=lambda o: float(np.prod(o.extents_m[:2])))
    assert ("suctionable", flat.name) in state.facts
    assert ("ungraspable", flat.name) in state.facts  # the fingers do not open so wide
    d = flat.kind_details["suction"]
    assert d["face"] == "top" and d["cup_diameter_m"] == 0.03 and d["margin"] > 0
    # the contact is on the top (0.06 m up), the normal up: both in the sensor frame, so
    # checked against the table frame the state carries
    from clearcli.geometry.models import TableFrame

    tf = TableFrame.from_plane(state.table)
    p = tf.to_table(np.asarray(d["point"])[None])[0]
    n = tf.T_table_camera[:3, :3] @ np.asarray(d["normal"])
    assert p[2] == pytest.approx(0.06, abs=0.006)
    assert n[2] > 0.95
    # its poses: four turns about the cup's axis, each (pre, contact, lift), the contact
    # pose's z into the face and its origin lip_past_tcp_m behind the lip
    poses = flat.kind_candidates["suction"]
    assert len(poses) == 4 and all(len(seq) == 3 for seq in poses)
    T = tf.T_table_camera @ np.asarray(poses[0][1])
    assert T[:3, 2] @ np.array([0.0, 0.0, -1.0]) > 0.95
    lip = T[:3, 3] + settings.suction.lip_past_tcp_m * T[:3, 2]
    assert lip == pytest.approx(p, abs=1e-6)


def test_a_profile_without_a_cup_is_never_offered_suction(tmp_path: Path) -> None:
    state, _ = _state(_pcd(tmp_path, [FLAT, SMALL]), "panda")
    assert not any(f[0] in ("suctionable", "block_suction") for f in state.facts)
    assert all("suction" not in o.kind_refusals and "suction" not in o.kind_details for o in state.objects)


def test_a_neighbour_in_the_tools_way_blocks_it(tmp_path: Path) -> None:
    # a tall box right beside the flat one, taller than the tool's reach over the top:
    # the least blocked place is chosen; one against the tall box's side is blocked
    tall = S.Box(1, 0.05, 0.16, 0.30, 0.045, 0.05)
    narrow = S.Box(0, 0.12, 0.16, 0.04, -0.05, 0.05)  # wider than the opening along y
    state, _ = _state(_pcd(tmp_path, [narrow, tall], "blocked"), "panda-hybrid")
    low = min(state.objects, key=lambda o: o.height_m)
    high = max(state.objects, key=lambda o: o.height_m)
    if ("suctionable", low.name) in state.facts:
        # its body (0.105 m across the axis, the hand) sweeps past the tall box's face
        blocked = ("block_suction", high.name, low.name) in state.facts
        d = low.kind_details["suction"]
        assert blocked or d["margin"] > 0
    else:
        assert "suction" in low.kind_refusals


def test_the_reason_names_the_kind_and_what_failed(tmp_path: Path) -> None:
    # a rod standing, 1.2 cm in radius: its top (24 mm across) is smaller than the cup and
    # its side bends r^2 / 2R = 9.4 mm under it
    rod = S.Cylinder(0, 0.012, 0.15, 0.0, 0.0)
    state, _ = _state(_pcd(tmp_path, [rod], "rod"), "panda-suction")
    (obj,) = state.objects
    why = obj.kind_refusals.get("suction", "")
    assert why.startswith("no flat patch of 30 mm: ") and ("edge" in why or "curved" in why), why


def test_suction_on_a_profile_without_a_cup_is_one_line_and_exit_3() -> None:
    res = clear("plan", "fixtures/isolated_box.pcd", "--grasps", "pinch,suction")
    assert res.returncode == 3 and len(res.stderr.strip().splitlines()) == 1
    assert "suction needs a cup" in res.stderr and "panda-hybrid, panda-suction, ur5e-epick" in res.stderr


@pytest.mark.parametrize(
    "setting",
    [
        "suction.cup_diameter_m=nan",
        "suction.cup_diameter_m=0",
        "suction.cup_diameter_m=1",
        "suction.holding_force_n=-5",
        "suction.bellows_compliance_m=0",
        "suction.density_kg_m3=inf",
        "suction.safety_factor=0.5",
    ],
)
def test_bad_suction_settings_are_one_line_and_exit_3(setting: str) -> None:
    res = clear("plan", "fixtures/isolated_box.pcd", "--robot", "panda-hybrid", "--set", setting)
    assert res.returncode == 3, res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and "Traceback" not in res.stderr
    assert "[suction]" in res.stderr


def test_a_plan_with_suction_validates_and_its_joints_land_on_its_poses(tmp_path: Path) -> None:
    from helpers.validate import plan_files, validate_files, validate_files_second

    from clearcli.robot.profiles import profile
    from clearcli.settings.tree import load_settings

    pcd = _pcd(tmp_path, [FLAT, CAN, SMALL])
    res, files = plan_files(pcd, tmp_path, "--robot", "panda-hybrid")
    assert res.returncode == 0, res.stderr
    doc = json.loads(res.stdout)
    suction = [s for s in doc["steps"] if s["grasp_kind"] == "suction"]
    assert suction, doc["steps"]
    assert "grasp_suction" in files[0].read_text() and "suctionable" in files[1].read_text()
    # two independent validators accept the plan against the written domain
    assert validate_files(*files) and validate_files_second(*files)
    # each suction step: its contact in the JSON, and its joints put the TCP on its poses
    settings = load_settings(None, ["robot.name=panda-hybrid"])
    kin = profile("panda-hybrid").kinematics(settings.robot)
    for step in suction:
        c = step["contact"]
        assert c["face"] in ("top", "side") and c["cup_diameter_m"] == 0.03
        assert abs(np.linalg.norm(c["normal_base"]) - 1.0) < 1e-3
        for q, T in zip(step["joints_rad"], step["T_base_gripper"]):
            fk = kin.fk(np.asarray(q))
            assert np.linalg.norm(fk[:3, 3] - np.asarray(T)[:3, 3]) < 2e-3
        # the contact pose: the cup's axis (z) against the normal, the lip on the point
        T1 = np.asarray(step["T_base_gripper"][1])
        assert T1[:3, 2] @ np.asarray(c["normal_base"]) < -0.99
        lip = T1[:3, 3] + settings.suction.lip_past_tcp_m * T1[:3, 2]
        assert np.linalg.norm(lip - np.asarray(c["point_base_m"])) < 1e-3


def test_the_tool_path_check_finds_the_labels_the_exact_test_does_even_at_its_bounds() -> None:
    # swept_hits decides most points from the contact's axes and tests only those within
    # SURE_M of a bound exactly: the same labels as the exact test on every point, here
    # on random clouds and on points put on the volume's bounds (within 1e-12 m)
    from clearcli.predicates.grasps.suction import FIRST_THEN_REST, STEM_CLEARANCE_M, swept_hits, swept_mask
    from clearcli.settings import Settings

    s = Settings().suction
    approach_m = Settings().push.approach_m
    rng = np.random.default_rng(7)
    r_stem = s.cup_diameter_m / 2.0 + STEM_CLEARANCE_M
    for trial in range(30):
        c = int(rng.integers(1, 9))
        at = rng.uniform(-0.1, 0.1, (c, 3))
        normals = rng.normal(size=(c, 3))
        normals[: c // 2] = [0.0, 0.0, 1.0]  # tops, the common case
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        points = rng.uniform(-0.3, 0.3, (400, 3))
        # points on the bounds of the first contact's stem and body: depth and radius
        n = normals[0]
        a = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
        a /= np.linalg.norm(a)
        depths = [s.bellows_compliance_m, s.stem_length_m + approach_m, s.stem_length_m, 0.02]
        radii = [r_stem, s.body_radius_m, 0.005]
        edge = np.array(
            [
                at[0] + (d + e) * n + (r + f) * a
                for d in depths
                for r in radii
                for e in (-1e-12, 0.0, 1e-12)
                for f in (-1e-12, 0.0, 1e-12)
            ]
        )
        points = np.concatenate([points, edge])
        labels = rng.integers(0, 5, len(points))
        labels[-len(edge) :] = np.arange(len(edge)) % 7 + 5  # the edge points' own labels
        exact = [
            frozenset(np.unique(labels[swept_mask(points, at[j], normals[j], s, approach_m)]).tolist())
            for j in range(c)
        ]
        assert list(swept_hits(points, labels, at, normals, s, approach_m)) == exact, trial
        assert list(swept_hits(points, labels, at, normals, s, approach_m, FIRST_THEN_REST)) == exact, trial
        assert any(exact), "the clouds reach the tool's volume"
