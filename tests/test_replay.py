"""`clear replay`: the loop over real and simulated logs, stable ids, monitoring, bad input."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from clearcli.errors import EXIT_PARTIAL, InputError
from clearcli.io.frames import Frame
from clearcli.perception.types import Segmentation, SegmentedObject, TablePlane
from clearcli.pipeline import Pipeline
from clearcli.planning.types import Action, Plan
from clearcli.predicates.state import ObjectModel, PushModel, SymbolicState
from clearcli.io.tf import base_camera_from_log, lookup_transform
from clearcli.replay.session import ReplayOptions, Session, replay
from clearcli.settings import Settings
from clearcli.sim import scene as scenes
from clearcli.sim.truth import truth_segment, world_object_of
from replay_helpers import simulated_session
from utils import REPO, shared_path

# --- helpers ----------------------------------------------------------------------------


def _clear_subprocess(*args: str) -> subprocess.CompletedProcess[str]:
    exe = Path(sys.executable).parent / "clear"
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "clearcli.cli"]
    return subprocess.run([*cmd, *args], capture_output=True, text=True, cwd=REPO, timeout=120)


def _clear_inprocess(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, *args: str) -> tuple[int, str, str]:
    """The real entry point in this process (so that monkeypatched stages apply)."""
    from clearcli import cli

    monkeypatch.setattr(sys, "argv", ["clear", *args])
    with pytest.raises(SystemExit) as exit_info:
        cli.main()
    out, err = capsys.readouterr()
    code = exit_info.value.code
    return int(code or 0), out, err


def _lines(text: str) -> list[dict[str, Any]]:
    return [json.loads(line) for line in text.splitlines() if line.strip()]


@pytest.fixture
def truth_segmentation(monkeypatch: pytest.MonkeyPatch) -> None:
    """Segment simulated frames from their labels: fast, and it isolates the replay loop
    from the segmenter's errors."""
    import clearcli.pipeline as pipeline

    monkeypatch.setattr(pipeline, "_default_segment", lambda: truth_segment)


@pytest.fixture(scope="module")
def sim_log(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """A simulated session in which an object is pushed (see replay_helpers)."""
    return simulated_session(tmp_path_factory.mktemp("sim"))


# --- a simulated session ------------------------------------------------------------------


def test_sim_session_has_a_push_and_is_cleared(sim_log: dict[str, Any]) -> None:
    result = sim_log["result"]
    assert result.end == "cleared" and result.remaining == ()
    assert any(s.action.startswith("(push") for s in result.steps)
    assert sim_log["frames"] == len(result.steps)


def test_ids_stable_across_a_simulated_session_with_pushes(sim_log: dict[str, Any]) -> None:
    from clearcli.io.read import iter_frames

    # the robot where the log's /tf_static puts it, as `clear replay` does
    session = Session(Pipeline(Settings(), T_base_camera=sim_log["T_base_camera"], segment_fn=truth_segment))
    world_of_track: dict[int, int] = {}
    track_of_world: dict[int, int] = {}
    pushed: list[int] = []
    executions = []
    for report in replay(iter_frames(sim_log["path"]), session):
        frame = report.frame
        assert frame is not None and report.result.segmentation is not None
        for obj in report.objects:
            wid = world_object_of(frame, report.result.segmentation, obj.segment_index)
            assert wid is not None
            assert world_of_track.setdefault(obj.track_id, wid) == wid
            assert track_of_world.setdefault(wid, obj.track_id) == obj.track_id
        first = report.first_action()
        if first is not None and first.kind == "push":
            pushed.append(report.ids_by_name[first.obj])
        if report.execution is not None:
            executions.append(report.execution)
    assert pushed, "the session should push an object"
    assert len(track_of_world) == sim_log["n_objects"]  # one id per object, none re-issued
    # every action was seen to happen, the push included
    push_checks = [e for e in executions if e.action.startswith("(push")]
    assert push_checks and all(e.outcome == "done" for e in push_checks)
    summary = session.summary
    assert summary.cleared and summary.failed == 0 and summary.objects_seen == sim_log["n_objects"]


def test_cli_json_lines(sim_log: dict[str, Any], truth_segmentation: None, capsys, monkeypatch) -> None:
    code, out, err = _clear_inprocess(capsys, monkeypatch, "replay", str(sim_log["path"]), "--json")
    assert code == 0, err
    lines = _lines(out)
    assert all(d["schema"] == "clear.replay" and d["version"] == 1 for d in lines)
    assert [d["type"] for d in lines] == ["frame"] * sim_log["frames"] + ["summary"]
    frames, summary = lines[:-1], lines[-1]
    assert [d["index"] for d in frames] == list(range(sim_log["frames"]))
    assert [d["time_s"] for d in frames] == pytest.approx([float(i) for i in range(sim_log["frames"])])
    assert frames[-1]["status"] == "cleared" and all(d["status"] == "ok" for d in frames[:-1])
    for d in frames[:-1]:
        first = d["first_action"]
        assert first["id"] in {o["id"] for o in d["objects"]}
        assert d["plan"]["actions"][0] == {k: first[k] for k in d["plan"]["actions"][0]}
        assert d["plan_length"] == len(d["plan"]["actions"])
        assert set(d["timings_s"]) >= {"read", "segment", "predicates", "plan", "total"}
    assert summary["frames"] == sim_log["frames"] and summary["cleared"] is True
    assert summary["actions"] == sim_log["frames"] - 1
    # the world lets grasps of objects near the opening width slip: the monitor sees it
    slipped = sum(1 for step in sim_log["result"].steps if step.outcome == "slipped")
    assert summary["executions"] == {"done": summary["actions"] - slipped, "failed": slipped}
    assert summary["back_and_forth"] == 0
    assert "robot base: wam_base" in err


def test_every_from_to(sim_log: dict[str, Any], truth_segmentation: None, capsys, monkeypatch) -> None:
    code, out, _ = _clear_inprocess(capsys, monkeypatch, "replay", str(sim_log["path"]), "--json", "--every", "2")
    assert code == 0
    assert [d["index"] for d in _lines(out) if d["type"] == "frame"] == list(range(0, sim_log["frames"], 2))
    code, out, _ = _clear_inprocess(
        capsys, monkeypatch, "replay", str(sim_log["path"]), "--json", "--from", "1.5", "--to", "3.5"
    )
    assert code == 0
    lines = _lines(out)
    assert [d["index"] for d in lines if d["type"] == "frame"] == [2, 3]
    assert lines[-1]["frames"] == 2


def test_truncated_log_replays_complete_frames_then_exit_9(
    sim_log: dict[str, Any], truth_segmentation: None, tmp_path: Path, capsys, monkeypatch
) -> None:
    data = sim_log["path"].read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * 0.55)])
    annotated = tmp_path / "cut-annotated.mcap"
    code, out, err = _clear_inprocess(capsys, monkeypatch, "replay", str(cut), "--json", "--out", str(annotated))
    assert code == EXIT_PARTIAL
    lines = _lines(out)
    frames = [d for d in lines if d["type"] == "frame"]
    assert 1 <= len(frames) < sim_log["frames"]
    assert lines[-1]["type"] == "summary" and lines[-1]["frames"] == len(frames)
    assert "truncated or corrupt" in lines[-1]["stopped"]
    assert "truncated or corrupt" in err.strip().splitlines()[-1] and "Traceback" not in err
    # the annotated log holds every complete frame
    from clearcli.io.mcap import read_summary

    assert read_summary(annotated).count("/clear/scene") == len(frames)


def test_transforms_from_the_log(sim_log: dict[str, Any]) -> None:
    T, base = base_camera_from_log(sim_log["path"], "camera_rgb_optical_frame")
    assert base == "wam_base"
    np.testing.assert_allclose(T, sim_log["T_base_camera"], atol=1e-9)
    assert base_camera_from_log(sim_log["path"], "another_frame") == (None, "")


def test_lookup_transform_chains_and_inverts() -> None:
    def tf(x: float, yaw_deg: float) -> np.ndarray:
        a = np.radians(yaw_deg)
        T = np.eye(4)
        T[:2, :2] = [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]
        T[0, 3] = x
        return T

    transforms = {("base", "link"): tf(1.0, 90), ("link", "camera"): tf(0.5, 0), ("camera", "optical"): tf(0.0, -90)}
    T = lookup_transform(transforms, "base", "optical")
    np.testing.assert_allclose(T, tf(1.0, 90) @ tf(0.5, 0) @ tf(0.0, -90), atol=1e-12)
    np.testing.assert_allclose(lookup_transform(transforms, "optical", "base"), np.linalg.inv(T), atol=1e-12)
    assert lookup_transform(transforms, "base", "nowhere") is None
    np.testing.assert_allclose(lookup_transform(transforms, "/base", "base"), np.eye(4))


# --- shuffled order, skipped and failing frames -------------------------------------------


def _relabelled(frame: Frame, permutation: dict[int, int]) -> Frame:
    """The frame with object k's labels given to object permutation[k]: the segmentation
    then lists the objects in another order."""
    labels = np.asarray(frame.fields["label"]).copy()
    out = labels.copy()
    for k, j in permutation.items():
        out[labels // 10 == k + 1] = 10 * (j + 1)
    return dataclasses.replace(frame, fields={"label": out})


def test_ids_stable_when_frames_list_objects_in_shuffled_order() -> None:
    from clearcli.sim.camera import render

    world = scenes.clutter(6, 3)
    rng = np.random.default_rng(0)
    session = Session(Pipeline(Settings(), segment_fn=truth_segment), ReplayOptions())
    seen: dict[int, int] = {}
    for index in range(4):
        frame = render(world, seed=index, stamp_s=float(index))
        permutation = dict(enumerate(rng.permutation(6).tolist()))
        shuffled = _relabelled(frame, permutation)
        segmentation = truth_segment(shuffled)
        report = session.step(shuffled, index, float(index))
        # undo the relabelling to know which world object each track is
        inverse = {j: k for k, j in permutation.items()}
        for obj in report.objects:
            labels = np.asarray(shuffled.fields["label"])[segmentation.objects[obj.segment_index].indices]
            world_id = inverse[int(np.bincount(labels // 10).argmax()) - 1]
            assert seen.setdefault(obj.track_id, world_id) == world_id
        assert report.gone == ()
    assert sorted(seen) == list(range(6))


def test_no_table_and_failed_frames_are_reported_and_skipped() -> None:
    from clearcli.predicates.state_builder import compute_state
    from clearcli.sim.camera import render

    world = scenes.clutter(3, 1)
    good = [dataclasses.replace(render(world, seed=i, stamp_s=float(i)), source=f"good{i}") for i in range(3)]
    nan = dataclasses.replace(good[0], points=np.full_like(good[0].points, np.nan), stamp_s=1.5, source="nan")
    bad = dataclasses.replace(good[1], stamp_s=1.7, source="bad")

    def state_fn(frame: Frame, seg: Segmentation, settings: Settings) -> SymbolicState:
        if frame.source == "bad":
            raise InputError("bad: the predicates cannot use this frame")
        return compute_state(frame, seg, settings)

    def segment_fn(frame: Frame, settings: Any) -> Segmentation:
        from clearcli.errors import SceneError

        if not frame.finite_mask.any():
            raise SceneError(f"{frame.source}: the frame has no finite points")
        return truth_segment(frame, settings)

    frames = [good[0], nan, bad, good[2]]
    session = Session(Pipeline(Settings(), segment_fn=segment_fn, state_fn=state_fn))
    statuses = [r.status for r in replay(frames, session)]
    assert statuses == ["ok", "no_table", "failed", "ok"]
    s = session.summary
    assert (s.frames, s.ok, s.no_table, s.failed) == (4, 2, 1, 1)
    # the same with --fail-fast stops at the failing frame, with its error type
    session = Session(
        Pipeline(Settings(), segment_fn=segment_fn, state_fn=state_fn), ReplayOptions(fail_fast=True)
    )
    with pytest.raises(InputError, match="--fail-fast"):
        for _ in replay(frames, session):
            pass
    assert session.summary.frames == 3


def test_empty_table_ends_the_session_as_cleared() -> None:
    from clearcli.sim.camera import render

    full = scenes.clutter(2, 0)
    empty = dataclasses.replace(full, objects=())
    frames = [render(full, seed=0), render(empty, seed=1, stamp_s=1.0), render(full, seed=2, stamp_s=2.0)]
    session = Session(Pipeline(Settings(), segment_fn=truth_segment))
    reports = list(replay(frames, session))
    assert [r.status for r in reports] == ["ok", "cleared"]
    assert session.summary.cleared and session.summary.frames_read == 2


# --- the thesis's back-and-forth, through the whole session ---------------------------------
#
# A toy world: one object must travel 0.2 m out of the clutter before it can be grasped;
# each push moves it 0.1 m. Both directions along its axis are free, at the same cost;
# its PCA axis flips every frame, so dir1/dir2 swap meaning; the planner breaks ties the
# worst way (towards where the object came from), as the thesis observed (section 7.2).

TABLE = TablePlane(normal=np.array([0.0, -1.0, 0.0]), offset=0.5)


def _toy_segment(frame: Frame, settings: Any) -> Segmentation:
    x = float(frame.fields["x"][0])
    centre = np.array([x, 0.45, 0.8])
    obj = SegmentedObject(
        indices=np.arange(0),
        centroid=centre,
        obb_center=centre,
        obb_axes=np.eye(3),
        obb_extents=np.array([0.1, 0.06, 0.08]),
        principal_axes=np.eye(3),
    )
    return Segmentation(
        n_points=0, table=TABLE, table_polygon=np.zeros((0, 3)), table_indices=np.arange(0), objects=(obj,)
    )


def _toy_state(frame: Frame, seg: Segmentation, settings: Any) -> SymbolicState:
    sign = 1.0 if frame.stamp_s % 2 == 0 else -1.0
    axis = np.array([sign, 0.0, 0.0])
    pushes = {
        "dir1": PushModel("dir1", axis, 0.1, (), ()),
        "dir2": PushModel("dir2", -axis, 0.1, (), ()),
    }
    model = ObjectModel(
        name="o0",
        segment_index=0,
        centroid=seg.objects[0].centroid,
        principal_axes=np.eye(3),
        extents_m=np.array([0.1, 0.06, 0.08]),
        hull_vertices=np.zeros((0, 3)),
        hull_faces=np.zeros((0, 3), dtype=int),
        grasp_candidates=(),
        pushes=pushes,
    )
    free = abs(float(seg.objects[0].centroid[0])) >= 0.2 - 1e-9
    facts = frozenset() if free else frozenset({("block_grasp", "clutter", "o0")})
    return SymbolicState(objects=(model,), table=TABLE, table_polygon=np.zeros((0, 3)), facts=facts)


class _ToyPlanner:
    def __init__(self) -> None:
        self.last_motion: np.ndarray | None = None

    def __call__(self, state: SymbolicState, settings: Any, T_base_camera: Any = None, check: str = "first") -> Plan:
        obj = state.objects[0]
        if not state.facts:
            return Plan((Action("grasp", "o0"),), 1, True, None, frozenset(), (), 1)
        cost = {d: state.push_costs.get(("o0", d), 1) for d in obj.pushes}
        best = min(cost.values())
        ties = [d for d in obj.pushes if cost[d] == best]

        def backwards(d: str) -> float:
            if self.last_motion is None:
                return 0.0
            return -float(obj.pushes[d].unit_vector @ self.last_motion)

        choice = max(ties, key=backwards)
        self.last_motion = obj.pushes[choice].unit_vector
        return Plan((Action("push", "o0", choice), Action("grasp", "o0")), best + 1, True, None, frozenset(), (), 1)


def _toy_session(push_memory: bool, budget: int = 10) -> Session:
    session = Session(
        Pipeline(Settings(), segment_fn=_toy_segment, state_fn=_toy_state, plan_fn=_ToyPlanner()),
        ReplayOptions(push_memory=push_memory),
    )
    x = 0.0
    for index in range(budget):
        frame = Frame(points=np.zeros((1, 3), dtype=np.float32), fields={"x": np.array([x])}, stamp_s=float(index))
        report = session.step(frame, index, float(index))
        first = report.first_action()
        if first is None or first.kind == "grasp":
            break
        x += 0.1 * float(report.result.state.by_name("o0").pushes[first.direction].unit_vector[0])  # type: ignore[union-attr]
    return session


def test_without_push_memory_the_session_pushes_back_and_forth() -> None:
    summary = _toy_session(push_memory=False).summary
    assert summary.pushes == 10 and summary.grasps == 0
    assert summary.back_and_forth == 9
    # the object always went back to where it was, so the monitor saw pushes carried out
    assert summary.executions_done == 9


def test_with_push_memory_the_back_and_forth_cannot_happen() -> None:
    summary = _toy_session(push_memory=True).summary
    assert summary.back_and_forth == 0
    assert (summary.pushes, summary.grasps) == (2, 1)
    assert summary.objects_seen == 1  # the pushed object kept its id throughout


# --- the real logs ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "n_frames"),
    [
        ("mosd_tabletop_ros2_pointcloud2.mcap", 3),
        ("mosd_tabletop_foxglove_protobuf.mcap", 2),
        ("mosd_tabletop_foxglove_json.mcap", 1),
    ],
)
def test_replay_real_logs(name: str, n_frames: int, capsys, monkeypatch) -> None:
    path = shared_path(f"mcap/{name}")
    code, out, err = _clear_inprocess(capsys, monkeypatch, "replay", str(path), "--json")
    assert code == 0, err
    lines = _lines(out)
    assert [d["type"] for d in lines] == ["frame"] * n_frames + ["summary"]
    for d in lines[:-1]:
        # mOSD test57 / test55 / learn21: cluttered tables (learn21's stacked boxes are
        # all too wide for the gripper: no plan, with the reason)
        assert d["status"] in ("ok", "no_plan"), d["error"]
        assert len(d["objects"]) >= 2
        if d["status"] == "ok":
            assert d["first_action"]["id"] in {o["id"] for o in d["objects"]}
            assert d["plan_length"] == len(d["plan"]["actions"]) >= 1
        else:
            assert d["error"].startswith("no plan")
        assert len({o["id"] for o in d["objects"]}) == len(d["objects"])
    assert lines[0]["status"] == "ok"  # test57
    assert [d["time_s"] for d in lines[:-1]] == pytest.approx([0.5 * i for i in range(n_frames)])
    assert lines[-1]["frames"] == n_frames and lines[-1]["failed"] == 0


def test_user_errors_are_one_line_with_their_exit_codes(tmp_path: Path) -> None:
    from clearcli.errors import EXIT_INPUT

    result = _clear_subprocess("replay", str(tmp_path / "missing.mcap"))
    assert result.returncode == EXIT_INPUT and "file not found" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and "Traceback" not in result.stderr
    rosbag = shared_path("mcap/rosbag2")
    logs = sorted(rosbag.rglob("*.mcap"))
    if logs:
        result = _clear_subprocess("replay", str(logs[0]))
        assert result.returncode == EXIT_INPUT and "point-cloud topic" in result.stderr
    result = _clear_subprocess("replay", str(tmp_path / "missing.mcap"), "--from", "3", "--to", "1")
    assert result.returncode == EXIT_INPUT and "--to" in result.stderr


# --- the simulated world and `clear simulate` ---------------------------------------------------


def test_world_push_slides_shoves_and_stalls() -> None:
    from clearcli.sim.episode import WorldParams
    from clearcli.sim.physics import separation, world_push
    from clearcli.sim.scene import Box, make_scene

    quiet = WorldParams(heading_noise_deg=0.0, yaw_noise_deg=0.0)
    rng = np.random.default_rng(0)
    alone = make_scene("alone", [Box(0, 0.05, 0.04, 0.08, x_m=0.0, y_m=0.0)])
    moved, outcome = world_push(alone, 0, np.array([1.0, 0.0]), 0.1, rng, quiet)
    assert moved.objects[0].x_m == pytest.approx(0.1) and moved.objects[0].y_m == pytest.approx(0.0)
    assert outcome == "pushed 0.100 m of 0.100 m"
    # a box in the way, touching: it is shoved ahead by the same distance
    pair = make_scene("pair", [Box(0, 0.05, 0.04, 0.08, x_m=0.0, y_m=0.0), Box(1, 0.04, 0.04, 0.06, x_m=0.046, y_m=0.0)])
    moved, outcome = world_push(pair, 0, np.array([1.0, 0.0]), 0.05, rng, quiet)
    assert moved.objects[0].x_m == pytest.approx(0.05)
    assert moved.objects[1].x_m - moved.objects[0].x_m >= 0.045 - 1e-6
    assert outcome.endswith("shoved 1")
    # a chain of four touching boxes is too much: the push stalls at once
    chain = make_scene("chain", [Box(i, 0.04, 0.04, 0.06, x_m=0.0401 * i, y_m=0.0) for i in range(4)])
    moved, outcome = world_push(chain, 0, np.array([1.0, 0.0]), 0.05, rng, quiet)
    assert moved.objects == chain.objects and outcome.startswith("pushed 0.000 m")
    # pushed off the table's edge, the object falls and is gone
    edge = make_scene("edge", [Box(0, 0.05, 0.04, 0.08, x_m=0.37, y_m=0.0)])
    moved, outcome = world_push(edge, 0, np.array([1.0, 0.0]), 0.1, rng, quiet)
    assert moved.objects == () and outcome.startswith("fell off")
    # the separating translation of two overlapping squares
    a = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    np.testing.assert_allclose(separation(a, a + [0.9, 0.2]), [0.1, 0.0])
    assert separation(a, a + [1.5, 0.0]) is None


def test_world_push_turns_the_object_with_seeded_noise() -> None:
    from clearcli.sim.physics import world_push
    from clearcli.sim.scene import Box, make_scene

    alone = make_scene("alone", [Box(0, 0.05, 0.04, 0.08, x_m=0.0, y_m=0.0)])
    a, _ = world_push(alone, 0, np.array([0.0, 1.0]), 0.1, np.random.default_rng(4))
    b, _ = world_push(alone, 0, np.array([0.0, 1.0]), 0.1, np.random.default_rng(4))
    assert a == b  # seeded
    obj = a.objects[0]
    assert obj.yaw_rad != 0.0 and abs(obj.yaw_rad) < np.radians(20)
    assert 0.09 < obj.y_m <= 0.1 + 1e-9 and abs(obj.x_m) < 0.01


def test_world_grasp_of_a_tight_object_slips_sometimes() -> None:
    from clearcli.sim.physics import world_grasp
    from clearcli.sim.scene import Box, make_scene

    rng = np.random.default_rng(1)
    narrow = make_scene("narrow", [Box(0, 0.1, 0.04, 0.08, x_m=0.0, y_m=0.0)])
    assert all(world_grasp(narrow, 0, 0.07, rng)[1] == "removed" for _ in range(20))
    tight = make_scene("tight", [Box(0, 0.1, 0.065, 0.08, x_m=0.0, y_m=0.0)])
    outcomes = [world_grasp(tight, 0, 0.07, rng)[1] for _ in range(40)]
    assert 8 <= outcomes.count("slipped") <= 32 and "removed" in outcomes
    scene, outcome = next((s, o) for s, o in (world_grasp(tight, 0, 0.07, rng) for _ in range(50)) if o == "slipped")
    assert len(scene.objects) == 1 and scene.objects[0] != tight.objects[0]


def test_world_grasp_never_holds_an_object_too_wide_or_too_narrow() -> None:
    from clearcli.sim.physics import truly_ungraspable, world_grasp
    from clearcli.sim.scene import Box, Cylinder, make_scene

    rng = np.random.default_rng(2)
    wide = make_scene("wide", [Box(0, 0.1, 0.08, 0.08, x_m=0.0, y_m=0.0)])
    thin = make_scene("thin", [Cylinder(0, 0.012, 0.1, x_m=0.0, y_m=0.0)])
    for _ in range(10):
        assert world_grasp(wide, 0, 0.07, rng, closing_width_m=0.03) == (wide, "too wide")
        assert world_grasp(thin, 0, 0.07, rng, closing_width_m=0.03) == (thin, "too narrow")
    assert truly_ungraspable(wide.objects[0], 0.07, 0.03) and truly_ungraspable(thin.objects[0], 0.07, 0.03)
    # 6.9 cm across its narrow side: the gripper fits it (it may slip, never refuses)
    fits = make_scene("fits", [Box(0, 0.1, 0.069, 0.08, x_m=0.0, y_m=0.0)])
    assert not truly_ungraspable(fits.objects[0], 0.07, 0.03)
    assert {world_grasp(fits, 0, 0.07, rng, closing_width_m=0.03)[1] for _ in range(20)} <= {"removed", "slipped"}


def test_cleared_truly_is_the_worlds_judgment_not_the_planners() -> None:
    from clearcli.sim.episode import EpisodeResult

    base = EpisodeResult(scene="s", seed=0, n_objects=3, steps=(), end="no_plan", remaining=(1, 2), unreachable=(1, 2))
    # the planner called 1 too wide and 2 out of reach: the old criterion passes either way
    claimed = dataclasses.replace(base, claimed_ungraspable=(1,))
    assert claimed.cleared_reachable and not claimed.cleared_truly and claimed.false_ungraspable == (1,)
    # the world agrees that 1 is too wide, but its own arm reaches 2: not cleared
    truly = dataclasses.replace(claimed, truly_ungraspable=(1,))
    assert not truly.cleared_truly and truly.false_ungraspable == ()
    # ... and when the world's arm cannot reach 2 either: cleared
    world = dataclasses.replace(truly, world_unreachable=(2,))
    assert world.cleared_truly
    # the world's verdict alone counts: the planner's "unreachable" list is not needed
    assert dataclasses.replace(world, unreachable=()).cleared_truly
    # out of reach because the robot pushed it there: not excused
    assert not dataclasses.replace(world, moved=(2,)).cleared_truly
    # anything else left is never excused, nor is anything when the budget ran out
    assert not dataclasses.replace(world, remaining=(1, 2, 3)).cleared_truly
    assert not dataclasses.replace(world, end="budget").cleared_truly


def test_simulate_command_writes_a_replayable_log(tmp_path: Path, capsys, monkeypatch) -> None:
    from clearcli.io.mcap import read_summary

    out = tmp_path / "sim.mcap"
    code, stdout, err = _clear_inprocess(
        capsys, monkeypatch, "simulate", str(out), "--scene", "two_touching_boxes", "--truth-segmentation", "--json"
    )
    assert code == 0, err
    (payload,) = _lines(stdout)
    assert payload["schema"] == "clear.simulate" and payload["end"] == "cleared"
    assert payload["objects"] == 2 and payload["remaining"] == [] and payload["actions"] >= 2
    assert payload["frames"] == len(payload["steps"]) == payload["actions"] + 1
    summary = read_summary(out)
    assert summary.count("/camera/depth_registered/points") == payload["frames"]
    assert summary.count("/tf_static") == 1
    code, _, err = _clear_inprocess(capsys, monkeypatch, "simulate", str(out), "--scene", "isolated_box")
    assert code == 8 and "--force" in err
