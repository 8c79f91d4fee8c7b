"""Tests of clearcli/tasks/plan.py: `plan` through the task layer (Request, run -> Outcome).

Which object is which is worked out from the fixtures' own ground truth (the per-point
`label` field, read here with pypcd4, not with clear's reader): the centroid the problem
file notes for each object is matched to the nearest true object's centroid."""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import FIXTURES
from helpers.tasks import truth_centroids

from clearcli.errors import ClearError, SettingsError
from clearcli.settings import Settings, settings_from_dict
from clearcli.tasks import plan as task
from clearcli.tasks.base import Outputs, Source

ACTION = re.compile(r"^\((grasp|push|[a-z_]+) (o\d+)(?: (dir\d+))?\)$")


def _noted_centroids(problem_text: str) -> dict[str, np.ndarray]:
    """The ``;   o3: (+0.012, -0.034, +0.880)`` comments of a problem file."""
    found = re.findall(r";\s+(o\d+): \(([-+0-9.]+), ([-+0-9.]+), ([-+0-9.]+)\)", problem_text)
    return {name: np.array([float(x), float(y), float(z)]) for name, x, y, z in found}


def _objects_of(problem_text: str) -> list[str]:
    m = re.search(r"\(:objects ([^)]*?) - obj", problem_text)
    assert m is not None, problem_text[:400]
    return m.group(1).split()


@pytest.fixture(scope="module")
def box_on_box(tmp_path_factory: pytest.TempPathFactory) -> dict:
    out = tmp_path_factory.mktemp("plan")
    files = {"problem": out / "p.pddl", "domain": out / "d.pddl", "plan": out / "x.plan", "png": out / "x.png"}
    outcome = task.run(task.Request(Settings(), outputs=Outputs.of(**files)), Source(FIXTURES / "box_on_box.pcd"))
    return {"outcome": outcome, "files": files}


def test_box_on_box_plan_takes_the_upper_box_first_and_removes_both(box_on_box: dict) -> None:
    outcome = box_on_box["outcome"]
    payload = outcome.payload
    assert outcome.exit_code == 0
    assert payload["status"] == "complete" and payload["left"] == [] and payload["no_plan_reason"] is None
    problem = box_on_box["files"]["problem"].read_text()
    names = _objects_of(problem)
    assert len(names) == 2  # fixtures/README.md: a small box lying on a larger one
    assert sorted(payload["goal"]) == sorted(names)
    # the names' centroids against the fixture's own labels: 10 the lower box, 20 the upper
    truth = truth_centroids(FIXTURES / "box_on_box.pcd")
    noted = _noted_centroids(problem)
    which = {}
    for name in names:
        label = min(truth, key=lambda k: float(np.linalg.norm(truth[k] - noted[name])))
        assert np.linalg.norm(truth[label] - noted[name]) < 0.03
        which[label] = name
    assert set(which) == {10, 20}
    # two grasps, the upper box before the one it stands on
    assert payload["actions"] == [f"(grasp {which[20]})", f"(grasp {which[10]})"]
    assert payload["cost"] == 2 and payload["unit_cost"] is True


def test_payload_steps_match_the_actions(box_on_box: dict) -> None:
    payload = box_on_box["outcome"].payload
    assert len(payload["steps"]) == len(payload["actions"])
    for step, action in zip(payload["steps"], payload["actions"]):
        kind, obj, direction = ACTION.match(action).groups()  # type: ignore[union-attr]
        assert (step["kind"], step["object"], step["direction"]) == (kind, obj, direction)
        assert step["checked"] is True
        # every checked pose is a rigid transform with its IK solution: one joint vector per pose
        assert len(step["joints_rad"]) == len(step["T_base_gripper"]) >= 1
        for T in step["T_base_gripper"]:
            T = np.asarray(T)
            assert np.allclose(T[3], [0, 0, 0, 1])
            assert np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-4)
        assert all(len(q) == len(payload["robot"]["joint_names"]) for q in step["joints_rad"])
    assert payload["robot"]["name"] == "wam"


def test_written_files_agree_with_the_payload_and_validate(box_on_box: dict) -> None:
    from pddl import parse_domain, parse_problem

    outcome = box_on_box["outcome"]
    files = box_on_box["files"]
    assert set(outcome.written) == set(files.values())
    assert files["png"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    lines = [ln.strip() for ln in files["plan"].read_text().splitlines() if ln.strip() and not ln.startswith(";")]
    assert lines == outcome.payload["actions"]
    assert f"; cost = {outcome.payload['cost']}" in files["plan"].read_text()
    dom = parse_domain(files["domain"])
    prob = parse_problem(files["problem"])
    assert {a.name for a in dom.actions} >= {"grasp", "push"}
    assert sorted(o.name for o in prob.objects if str(o.name).startswith("o")) == sorted(outcome.payload["goal"])
    from helpers.validate import validate_files

    assert validate_files(files["domain"], files["problem"], files["plan"])


def test_clutter10_plan_removes_all_ten_objects() -> None:
    outcome = task.run(task.Request(Settings()), Source(FIXTURES / "clutter10.pcd"))
    payload = outcome.payload
    assert outcome.exit_code == 0 and payload["status"] == "complete"
    assert len(truth_centroids(FIXTURES / "clutter10.pcd")) == 10
    assert sorted(payload["goal"]) == sorted(f"o{k}" for k in range(10))
    grasped = [ACTION.match(a).group(2) for a in payload["actions"] if a.startswith("(grasp")]  # type: ignore[union-attr]
    assert sorted(grasped) == sorted(payload["goal"])  # each removed exactly once
    assert payload["left"] == [] and payload["unreachable"] == []
    assert payload["cost"] == len(payload["actions"])  # unit costs by default
    json.dumps(payload, allow_nan=False)  # what --json prints: plain JSON, no NaN


def test_outcome_carries_the_schema_the_cli_prints(capsys, monkeypatch) -> None:
    from clearcli import cli

    frame = FIXTURES / "isolated_box.pcd"
    outcome = task.run(task.Request(Settings()), Source(frame))
    monkeypatch.setattr(sys, "argv", ["clear", "plan", str(frame), "--json"])
    with pytest.raises(SystemExit) as exit_info:
        cli.main()
    assert int(exit_info.value.code or 0) == outcome.exit_code == 0
    doc = json.loads(capsys.readouterr().out)
    assert (doc["schema"], doc["version"]) == (f"clear.{outcome.schema}", outcome.version) == ("clear.plan", 5)
    assert set(doc) - {"schema", "version", "clear"} == set(outcome.payload)
    assert doc["actions"] == outcome.payload["actions"] == ["(grasp o0)"]


def test_first_only_checks_the_first_action_and_another_robot_is_named() -> None:
    settings = settings_from_dict({"robot": {"name": "panda"}})
    outcome = task.run(task.Request(settings, first_only=True), Source(FIXTURES / "two_touching_boxes.pcd"))
    payload = outcome.payload
    assert payload["check"] == "first"
    assert payload["robot"]["name"] == "panda"
    assert payload["robot"]["gripper"]["opening_width_m"] == 0.08  # the Franka Hand's (settings/profiles.py)
    assert sorted(payload["goal"]) == ["o0", "o1"]
    assert payload["steps"][0]["checked"] is True


@pytest.mark.parametrize("pose", ["1 2 3", "nan 0 0 0 0 0 1", "a b c d e f g"])
def test_a_bad_camera_pose_is_a_settings_error(pose: str) -> None:
    with pytest.raises(SettingsError, match="camera pose"):
        task.run(task.Request(Settings(), camera_pose=pose), Source(FIXTURES / "isolated_box.pcd"))


def test_a_missing_frame_is_a_clear_error(tmp_path: Path) -> None:
    with pytest.raises(ClearError) as info:
        task.run(task.Request(Settings()), Source(tmp_path / "nothing.pcd"))
    assert info.value.exit_code == 3 and "nothing.pcd" in str(info.value)


def test_a_request_is_built_without_loading_the_stages() -> None:
    """A batch's parent builds the Request and its workers run it: importing the task and
    building one loads neither NumPy nor the pipeline (issue 39: ~0.3 s of CPU in the
    parent before its workers started); `run` imports them."""
    import subprocess

    code = (
        "import sys\n"
        "from clearcli.settings import Settings\n"
        "from clearcli.tasks import plan as task\n"
        "task.Request(Settings())\n"
        "print(sorted(m for m in ('numpy', 'scipy', 'fcl', 'clearcli.pipeline') if m in sys.modules))\n"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "[]"
