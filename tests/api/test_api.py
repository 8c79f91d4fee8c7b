"""The Python API (clearcli/api.py) against the command line: the same documents for the
same frame and settings (the round trip), the same errors with the same messages, the
arrays consistent with the documents, and an import that loads nothing heavy.

The documents carry timings (``timings_s``; a replay's summary its ``time_s``,
``mean_time_s`` and ``frames_per_s``), which differ between any two runs: the round
trips compare the documents with those fields removed, and everything else exactly, but
for the commit in ``clear.source``: the test process reads HEAD once, and a commit made
in the checkout while the suite runs moves it for the CLI's later process (compared by
its kind, "git ..." or "package ...")."""

from __future__ import annotations

import json
import subprocess
import sys
from typing import Any

import numpy as np
import pytest

from clearcli import api
from tests.helpers import FIXTURES, REPO, run_clear

FRAME = FIXTURES / "box_on_box.pcd"  # two objects: the quickest fixture to plan
LOG = FIXTURES / "session.mcap"  # frames 0.5 s apart (fixtures/README.md)

# timings: measured per run, never equal between two runs
TIMED = {"timings_s"}
SUMMARY_TIMED = {"time_s", "mean_time_s", "frames_per_s"}


def untimed(doc: Any, timed: set[str] = TIMED) -> Any:
    if isinstance(doc, dict):
        out = {k: untimed(v, timed) for k, v in doc.items() if k not in timed}
        if "schema" in doc and isinstance(doc.get("clear"), dict):
            out["clear"] = {**doc["clear"], "source": doc["clear"]["source"].split(" ")[0]}
        return out
    if isinstance(doc, list):
        return [untimed(v, timed) for v in doc]
    return doc


def cli_document(*args: object) -> tuple[dict[str, Any], int]:
    out = run_clear(*args, "--json")
    assert out.stdout.strip(), out.stderr
    return json.loads(out.stdout), out.returncode


@pytest.mark.parametrize("command", ["segment", "predicates", "plan"])
def test_round_trip_equals_the_cli_document(command: str) -> None:
    rel = FRAME.relative_to(REPO)  # the CLI runs in the checkout: the same source text
    settings = api.Settings.default().with_(**{"segment.voxel_m": 0.005})
    result = getattr(api, command)(rel, settings=settings)
    cli, code = cli_document(command, rel, "--set", "segment.voxel_m=0.005")
    doc = result.to_json()
    assert doc["schema"] == f"clear.{command if command != 'segment' else 'segmentation'}"
    assert set(doc["timings_s"]) == set(cli["timings_s"])  # the same stages timed
    assert untimed(doc) == untimed(cli)
    if command == "plan":
        assert result.exit_code == code and result.status == cli["status"]


def test_round_trip_of_replay_frames_and_summary() -> None:
    rel = LOG.relative_to(REPO)
    out = run_clear("replay", rel, "--to", "0.6", "--json")
    lines = [json.loads(line) for line in out.stdout.splitlines()]
    assert out.returncode == 0 and [x["type"] for x in lines] == ["frame", "frame", "summary"], out.stderr
    run = api.replay(rel, to_s=0.6)
    frames = list(run)
    assert [untimed(f.to_json()) for f in frames] == [untimed(x) for x in lines[:2]]
    assert run.summary is not None
    assert untimed(run.summary.to_json(), TIMED | SUMMARY_TIMED) == untimed(lines[2], TIMED | SUMMARY_TIMED)
    first = frames[0]
    assert first.index == 0 and first.status == lines[0]["status"]
    assert [o.id for o in first.objects] == [o["id"] for o in lines[0]["objects"]]
    assert first.labels is not None and first.points is not None
    assert first.labels.shape == (first.points.shape[0],)
    for obj in first.objects:
        assert obj.indices is not None
        np.testing.assert_allclose(np.nanmean(first.points[obj.indices], axis=0), obj.centroid_m, atol=1e-4)


def test_replay_stops_when_closed() -> None:
    run = api.replay(LOG)
    first = next(run)
    assert first.index == 0
    run.close()
    assert list(run) == [] and run.summary is None
    assert run._thread is not None and not run._thread.is_alive()  # the replay's thread ended


def test_segmentation_arrays_agree_with_the_document() -> None:
    seg = api.segment(FRAME)
    doc = seg.to_json()
    truth = api.read_frame(FRAME).fields["label"]  # the fixture's exact labels
    assert seg.labels.shape == truth.shape == (seg.points.shape[0],)
    assert [o.id for o in seg.objects] == [o["id"] for o in doc["objects"]] == [0, 1]
    for obj, o in zip(seg.objects, doc["objects"]):
        assert obj.indices.shape == (o["n_points"],)
        assert set(np.unique(seg.labels[obj.indices])) == {obj.label}
        np.testing.assert_allclose(seg.points[obj.indices].mean(axis=0), obj.centroid_m, atol=1e-5)
    assert np.count_nonzero(seg.labels == 1) == doc["table"]["n_points"] == seg.table_indices.shape[0]
    with pytest.raises(ValueError):
        seg.labels[0] = 5  # read-only: a result is frozen


def test_plan_arrays_agree_with_the_document() -> None:
    p = api.plan(FRAME)
    doc = p.to_json()
    assert p.status == "complete" and p.exit_code == 0
    assert [s.action for s in p.steps] == doc["actions"]
    for step, s in zip(p.steps, doc["steps"]):
        assert step.joints_rad is not None and step.T_base_gripper is not None
        assert step.joints_rad.shape == (len(s["joints_rad"]), len(p.joint_names))
        assert step.T_base_gripper.shape == (len(s["T_base_gripper"]), 4, 4)
        np.testing.assert_allclose(step.T_base_gripper[:, 3, :], [[0, 0, 0, 1]] * len(s["T_base_gripper"]))
    np.testing.assert_array_equal(p.T_base_camera, doc["T_base_camera"])


def test_predicates_poses_as_arrays() -> None:
    pred = api.predicates(FRAME)
    doc = pred.to_json()
    assert pred.facts == tuple(doc["facts"])
    assert [f for f in pred.facts if f.startswith("(on ")] in (["(on o0 o1)"], ["(on o1 o0)"])  # one box on the other
    for obj, o in zip(pred.objects, doc["objects"]):
        assert obj.grasp_poses.shape == (len(o["grasp_poses"]), 4, 4)
        rotations = obj.grasp_poses[:, :3, :3]
        np.testing.assert_allclose(
            rotations @ rotations.transpose(0, 2, 1), np.broadcast_to(np.eye(3), rotations.shape), atol=1e-5
        )


@pytest.mark.parametrize(
    ("values", "says"),
    [
        ({"segment.voxel_m": -1}, "settings: [segment] voxel_m = -1: out of range; accepted: >= 0.001 and <= 0.05"),
        ({"segment.voxel_m": "big"}, "settings: [segment] voxel_m = 'big': must be a number"),
        ({"segment.no_such_key": 1}, "unknown key(s) no_such_key in [segment]"),
        ({"robot.name": "r2d2"}, "is not a robot profile"),
    ],
)
def test_a_bad_setting_raises_before_any_work_as_the_cli_says(values: dict[str, Any], says: str) -> None:
    with pytest.raises(api.SettingsError) as caught:
        api.Settings.default().with_(**values)  # no frame named: nothing was read or run
    assert says in str(caught.value)
    ((key, value),) = values.items()
    text = value if isinstance(value, str) and value != "big" else json.dumps(value)
    out = run_clear("segment", "no-such-file.pcd", "--set", f"{key}={text}")
    assert out.returncode == caught.value.exit_code == 3
    assert out.stderr.strip() == f"clear: error: {caught.value}"  # the same line, before the missing file


@pytest.mark.parametrize(
    ("call", "args"),
    [
        (lambda: api.segment("no-such-file.pcd"), ("segment", "no-such-file.pcd")),
        (lambda: api.plan(FIXTURES / "README.md"), ("plan", FIXTURES / "README.md")),
        (lambda: api.plan(FRAME, camera_pose="1 2"), ("plan", FRAME, "--camera-pose", "1 2")),
        (
            lambda: api.plan(FRAME, settings=api.Settings.default().with_(**{"plan.grasps": "pinch,suction"})),
            ("plan", FRAME, "--grasps", "pinch,suction"),
        ),
    ],
)
def test_bad_input_raises_the_cli_error(call: Any, args: tuple[object, ...]) -> None:
    with pytest.raises(api.ClearError) as caught:
        call()
    out = run_clear(*args)
    assert out.returncode == caught.value.exit_code
    assert out.stderr.strip().splitlines()[-1] == f"clear: error: {caught.value}"


def test_settings_round_trip_through_toml(tmp_path: Any) -> None:
    s = api.Settings.default(robot="ur5e").with_(segment={"voxel_m": 0.006}, **{"plan.time_limit_s": 20})
    assert s.get("robot.name") == "ur5e" and s.get("segment.voxel_m") == 0.006
    path = tmp_path / "s.toml"
    path.write_text(s.to_toml(), encoding="utf-8")
    assert api.Settings.from_file(path).to_toml() == s.to_toml()
    with pytest.raises(api.SettingsError, match="no key 'segment.nope'"):
        s.get("segment.nope")


def test_import_is_cheap() -> None:
    """Importing the API loads neither NumPy nor the settings tree nor a stage."""
    code = (
        "import sys, clearcli.api; heavy = [m for m in sys.modules if m.split('.')[0] == 'numpy' or "
        "m.startswith(('clearcli.settings.tree', 'clearcli.tasks', 'clearcli.pipeline', 'typer'))]; print(heavy)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
