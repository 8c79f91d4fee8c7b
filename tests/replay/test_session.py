"""Tests of clearcli/replay/session.py."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest
from helpers.clearing import _settings, _state
from helpers.plan_scenes import bare_object
from helpers.replay_session import sim_log  # noqa: F401  (fixtures)

from clearcli.errors import InputError
from clearcli.io.frames import Frame
from clearcli.perception.types import Segmentation, SegmentedObject, TablePlane
from clearcli.pipeline import Pipeline
from clearcli.planning.types import Action, Plan
from clearcli.predicates.state import PushModel, SymbolicState
from clearcli.replay.session import ReplayOptions, Session, replay
from clearcli.settings import Settings
from clearcli.sim import scene as S
from clearcli.sim import scene as scenes
from clearcli.sim.truth import truth_segment, world_object_of


def test_off_centre_first_tries_either_end_of_the_object_after_a_failed_grasp() -> None:
    """A 12 cm box (4 cm wide): its off-centre grasps (30 % of the length, 3.6 cm from
    the middle) come first, one end after an odd number of failures, the other after an
    even one; the centred grasps follow. A box too short to move the grasp by 1 cm keeps
    its order."""
    from clearcli.planning.probe import off_centre_first

    _, state = _state(S.make_scene("long", [S.Box(0, 0.12, 0.04, 0.06, x_m=0.0, y_m=0.05)]), _settings())
    obj = state.objects[0]
    pos = lambda seq: np.asarray(seq[1])[:3, 3]  # noqa: E731
    centre = pos(obj.grasp_candidates[0])
    ends = []
    for failures in (1, 2):
        moved = off_centre_first(state, obj.name, failures).by_name(obj.name).grasp_candidates
        assert len(moved) == len(obj.grasp_candidates)
        offset = pos(moved[0]) - centre
        assert float(np.linalg.norm(offset)) == pytest.approx(0.3 * 0.12, abs=2e-3)
        ends.append(offset)
        # the centred grasp is still there, after every off-centre one
        k = next(i for i, seq in enumerate(moved) if np.linalg.norm(pos(seq) - centre) < 1e-9)
        assert all(np.linalg.norm(pos(seq) - centre) >= 0.01 for seq in moved[:k])
    assert float(ends[0] @ ends[1]) < 0  # the two ends
    _, short = _state(S.make_scene("short", [S.Box(0, 0.04, 0.035, 0.06, x_m=0.0, y_m=0.05)]), _settings())
    o = short.objects[0]
    assert off_centre_first(short, o.name, 1).by_name(o.name).grasp_candidates == o.grasp_candidates


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_two_boxes_merged_end_to_end_are_taken_after_one_failed_grasp(seed: int) -> None:
    """Two boxes of one height (4.7 cm) touching end to end are one segment (no depth cue
    splits them): the centred grasp closes on both at their seam and takes nothing. The
    next grasp tries an end first ([plan] regrasp_off_centre) and takes one box: three
    actions. Without it the same grasp is retried until it counts as infeasible, then
    pushed and retried (7 or more actions, or the budget: on one seed a push parts the
    boxes after the first retries)."""
    from clearcli.pipeline import Pipeline
    from clearcli.replay.session import ReplayOptions, Session
    from clearcli.sim.episode import Episode

    world = S.make_scene(
        "end to end",
        [
            S.Box(0, 0.055, 0.044, 0.047, x_m=-0.0275, y_m=0.05),
            S.Box(1, 0.065, 0.044, 0.047, x_m=0.0325, y_m=0.05),
        ],
    )
    settings = Settings()
    results = {}
    for on in (True, False):
        plan = dataclasses.replace(settings.plan, regrasp_off_centre=on)
        episode = Episode(
            world,
            Session(Pipeline(dataclasses.replace(settings, plan=plan)), ReplayOptions(push_memory=True)),
            seed=seed,
            max_actions=12,
        )
        for _ in episode:
            pass
        assert episode.result is not None
        results[on] = episode.result
    on, off = results[True], results[False]
    assert "at once" in on.steps[0].outcome  # the segmenter merged them
    assert on.cleared_truly and on.actions == 3
    assert off.actions >= 7


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

    def state_fn(frame: Frame, seg: Segmentation, settings: Settings, avoid_faces: Any = None, /) -> SymbolicState:
        if frame.source == "bad":
            raise InputError("bad: the predicates cannot use this frame")
        return compute_state(frame, seg, settings, avoid_faces)

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
    session = Session(Pipeline(Settings(), segment_fn=segment_fn, state_fn=state_fn), ReplayOptions(fail_fast=True))
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


def _toy_state(frame: Frame, seg: Segmentation, settings: Any, avoid_faces: Any = None, /) -> SymbolicState:
    sign = 1.0 if frame.stamp_s % 2 == 0 else -1.0
    axis = np.array([sign, 0.0, 0.0])
    pushes = {
        "dir1": PushModel("dir1", axis, 0.1, (), ()),
        "dir2": PushModel("dir2", -axis, 0.1, (), ()),
    }
    model = bare_object("o0", seg.objects[0].centroid, np.array([0.1, 0.06, 0.08]), pushes)
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
