"""`clear plan` on the command line, as a user or a script runs it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import FIXTURES, REPO, shared_path
from helpers.validate import validate_files

from clearcli.sim import scene as S

DOMAIN = REPO / "pddl" / "domain.pddl"


def clear(*args: str, cwd: Path | None = None, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "clearcli.cli", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=cwd,
        env=env,
    )


def render_pcd(scene: S.Scene, path: Path, seed: int = 0) -> Path:
    from clearcli.io.pcd import write_pcd
    from clearcli.sim.camera import render

    write_pcd(path, render(scene, seed=seed))
    return path


def camera_pose_beside_table(scene: S.Scene, shoulder_table_x_m: float) -> str:
    """--camera-pose for a WAM whose shoulder stands at table x = ``shoulder_table_x_m``
    (y = 0, 0.346 m above the table top), facing the table's -x."""
    from scipy.spatial.transform import Rotation

    T_table_base = np.eye(4)
    T_table_base[:3, :3] = np.diag([-1.0, -1.0, 1.0])
    T_table_base[:3, 3] = (shoulder_table_x_m, 0.0, 0.346)
    T_base_camera = np.linalg.inv(T_table_base) @ np.linalg.inv(scene.T_camera_table)
    q = Rotation.from_matrix(T_base_camera[:3, :3]).as_quat()
    return " ".join(f"{v:.9f}" for v in (*T_base_camera[:3, 3], *q))


@pytest.fixture(scope="module")
def scenes(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("scenes")
    near = S.Box(0, 0.05, 0.04, 0.08, x_m=0.30, y_m=0.0)
    far = S.Box(1, 0.05, 0.04, 0.08, x_m=-0.32, y_m=0.05)
    wide = S.Box(0, 0.14, 0.12, 0.08, x_m=0.0, y_m=0.0, yaw_rad=0.3)
    # a long table seen from higher up: one box beside the robot, one ~2.4 m from it
    two_m = S.make_scene(
        "two_metres",
        [S.Box(0, 0.06, 0.05, 0.10, x_m=0.90, y_m=0.0), S.Box(1, 0.06, 0.05, 0.10, x_m=-1.10, y_m=0.1)],
        table=S.Table(2.6, 0.8),
        T_camera_table=S.camera_pose_T_camera_table(height_m=1.6, pitch_deg=55),
    )
    return {
        "two_metres": render_pcd(two_m, d / "two_metres.pcd", seed=7),
        "near_far": render_pcd(S.make_scene("near_far", [near, far]), d / "near_far.pcd", seed=5),
        "wide": render_pcd(S.make_scene("wide", [wide]), d / "wide.pcd", seed=6),
    }


def test_complete_plan_exit_0_files_validated(tmp_path: Path) -> None:
    out = tmp_path / "plan.txt"
    prob = tmp_path / "problem.pddl"
    res = clear("plan", FIXTURES / "two_touching_boxes.pcd", "--json", "-o", out, "--problem", prob)
    assert res.returncode == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["schema"] == "clear.plan" and doc["version"] == 5
    assert doc["status"] == "complete" and doc["left"] == [] and doc["check"] == "whole"
    assert doc["goal"] == ["o0", "o1"] and len(doc["actions"]) == 2
    for step in doc["steps"]:  # every action carries its joint solutions
        assert step["checked"] and step["candidate"] is not None
        assert len(step["joints_rad"]) >= 3 and all(len(q) == 7 for q in step["joints_rad"])
    assert out.read_text().splitlines()[-1] == "; cost = 2 (unit cost)"
    assert validate_files(DOMAIN, prob, out)
    # a tampered plan is rejected: the check can fail
    lines = out.read_text().splitlines()
    tampered = tmp_path / "tampered.txt"
    tampered.write_text("\n".join([lines[0], lines[0], *lines[1:]]) + "\n")  # o grasped twice
    assert not validate_files(DOMAIN, prob, tampered)
    dropped = tmp_path / "dropped.txt"
    dropped.write_text("\n".join(lines[1:]) + "\n")  # an object left on the table
    assert not validate_files(DOMAIN, prob, dropped)


def test_partial_plan_exit_10_unreachable_object_and_learnt_facts(scenes: dict[str, Path], tmp_path: Path) -> None:
    scene = S.make_scene("near_far", [])
    pose = camera_pose_beside_table(scene, 0.75)  # near box 0.45 m away, far one ~1.07 m
    out, prob = tmp_path / "plan.txt", tmp_path / "problem.pddl"
    res = clear("plan", scenes["near_far"], "--camera-pose", pose, "--json", "-o", out, "--problem", prob)
    assert res.returncode == 10, res.stderr
    doc = json.loads(res.stdout)
    assert doc["status"] == "partial" and len(doc["goal"]) == 1 and len(doc["left"]) == 1
    left = doc["left"][0]
    assert left["reason"] == "unreachable" and "beyond the arm's reach" in left["detail"]
    assert left["object"] == doc["unreachable"][0] and left["object"] not in doc["goal"]
    # what the reach check learnt is in the problem, and the plan solves that problem
    assert ["ik_unfeasible_grasp", left["object"]] in doc["ik_unfeasible"]
    text = prob.read_text()
    assert f"(ik_unfeasible_grasp {left['object']})" in text
    assert f"(:goal (and (removed {doc['goal'][0]})))" in text
    assert validate_files(DOMAIN, prob, out)
    # the human output lists what is left, and why
    human = clear("plan", scenes["near_far"], "--camera-pose", pose)
    assert human.returncode == 10 and f"{left['object']} unreachable" in human.stdout


def test_object_two_metres_away_unreachable_rest_planned(scenes: dict[str, Path], tmp_path: Path) -> None:
    pose = camera_pose_beside_table(
        S.make_scene("", [], T_camera_table=S.camera_pose_T_camera_table(height_m=1.6, pitch_deg=55)), 1.35
    )
    out, prob = tmp_path / "plan.txt", tmp_path / "problem.pddl"
    res = clear("plan", scenes["two_metres"], "--camera-pose", pose, "--json", "-o", out, "--problem", prob)
    assert res.returncode == 10, res.stderr
    doc = json.loads(res.stdout)
    assert doc["status"] == "partial" and doc["actions"] == [f"(grasp {doc['goal'][0]})"] and len(doc["goal"]) == 1
    # (at 2.4 m the far box may come out in pieces: each is unreachable, none is planned)
    assert doc["left"] and all(
        x["reason"] == "unreachable" and "beyond the arm's reach" in x["detail"] for x in doc["left"]
    )
    assert validate_files(DOMAIN, prob, out)
    # the problem file gives each object's centroid (sensor frame): the ones left stand
    # more than 2 m from the shoulder, the one planned within reach
    import re

    T = np.array(doc["T_base_camera"])
    text = prob.read_text()
    centroids = {
        m.group(1): np.array([float(m.group(k)) for k in (2, 3, 4)])
        for m in re.finditer(r";\s+(o\d+): \(([-+.\d]+), ([-+.\d]+), ([-+.\d]+)\)", text)
    }
    dist = {o: float(np.linalg.norm((T[:3, :3] @ c + T[:3, 3])[:2])) for o, c in centroids.items()}
    assert dist[doc["goal"][0]] < 0.9
    for x in doc["left"]:
        assert dist[x["object"]] > 2.0 and f"(ik_unfeasible_grasp {x['object']})" in text


def test_nothing_to_do_exit_5_with_json_and_files(scenes: dict[str, Path], tmp_path: Path) -> None:
    out, prob = tmp_path / "plan.txt", tmp_path / "problem.pddl"
    res = clear("plan", scenes["wide"], "--json", "-o", out, "--problem", prob)
    assert res.returncode == 5, res.stderr
    doc = json.loads(res.stdout)  # a document even though nothing can be done
    assert doc["status"] == "no_plan" and doc["actions"] == [] and doc["goal"] == []
    (left,) = doc["left"]
    assert left["reason"] == "ungraspable" and left["width_m"] > 0.07
    assert "the gripper opens to 0.070 m" in left["detail"]
    assert "too wide or narrow" in res.stderr
    assert out.read_text() == "; cost = 0 (unit cost)\n"
    assert "(:goal (and))" in prob.read_text()
    assert validate_files(DOMAIN, prob, out)


def test_non_unit_costs_write_their_domain(tmp_path: Path) -> None:
    settings = tmp_path / "costs.toml"
    settings.write_text("[predicates]\nclearance_cost = true\n")
    out, prob, dom = tmp_path / "plan.txt", tmp_path / "problem.pddl", tmp_path / "domain.pddl"
    res = clear(
        "plan",
        FIXTURES / "clutter10.pcd",
        "--settings",
        settings,
        "--json",
        "-o",
        out,
        "--problem",
        prob,
        "--domain",
        dom,
    )
    assert res.returncode in (0, 10), res.stderr
    doc = json.loads(res.stdout)
    assert doc["unit_cost"] is False
    assert out.read_text().splitlines()[-1] == f"; cost = {doc['cost']} (general cost)"
    assert "(push-cost ?o - obj ?d - direction)" in dom.read_text()
    assert "(= (push-cost o0 dir1)" in prob.read_text()
    assert validate_files(dom, prob, out)


def test_real_frame_partial_plan_validated(tmp_path: Path) -> None:
    pcd = shared_path("mosd/test/test57.pcd")
    out, prob = tmp_path / "plan.txt", tmp_path / "problem.pddl"
    res = clear("plan", pcd, "--json", "-o", out, "--problem", prob)
    assert res.returncode == 10, res.stderr  # mOSD test57: several boxes too wide
    doc = json.loads(res.stdout)
    assert doc["status"] == "partial" and doc["goal"] and doc["left"]
    assert {x["reason"] for x in doc["left"]} <= {"ungraspable", "stuck", "unreachable"}
    for x in doc["left"]:
        if x["reason"] == "stuck":
            assert x["blockers"] and set(x["blockers"]) <= {y["object"] for y in doc["left"]}
    assert all(s["checked"] for s in doc["steps"])
    assert validate_files(DOMAIN, prob, out)
    # --first-only: the thesis's check, only the first action has joint solutions
    first = clear("plan", pcd, "--json", "--first-only")
    d1 = json.loads(first.stdout)
    assert d1["check"] == "first" and d1["steps"][0]["checked"]
    assert all(s["checked"] is False and s["joints_rad"] is None for s in d1["steps"][1:])


def test_outputs_whole_or_not_at_all(tmp_path: Path) -> None:
    out, prob = tmp_path / "plan.txt", tmp_path / "problem.pddl"
    prob.write_text("mine")
    res = clear("plan", FIXTURES / "isolated_box.pcd", "-o", out, "--problem", prob)
    assert res.returncode == 8 and "--force" in res.stderr
    assert prob.read_text() == "mine" and not out.exists()  # nothing written, nothing lost
    res = clear("plan", FIXTURES / "isolated_box.pcd", "-o", out, "--problem", prob, "--force")
    assert res.returncode == 0 and "(removed o0)" in prob.read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.txt", "problem.pddl"]  # no temporaries left
    same = clear("plan", FIXTURES / "isolated_box.pcd", "-o", out, "--problem", out, "--force")
    assert same.returncode == 3 and "different files" in same.stderr


def test_planner_missing_is_exit_6_with_the_install_hint(tmp_path: Path) -> None:
    import os

    fake = tmp_path / "up_fast_downward"
    fake.mkdir()
    (fake / "__init__.py").write_text("")  # a package without the planner binary
    env = dict(os.environ, PYTHONPATH=str(tmp_path))
    res = clear("plan", FIXTURES / "isolated_box.pcd", env=env)
    assert res.returncode == 6
    assert "pip install up-fast-downward" in res.stderr and "Traceback" not in res.stderr
