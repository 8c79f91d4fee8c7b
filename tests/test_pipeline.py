"""Tests of clearcli/pipeline.py: the one-frame pipeline (`Pipeline`, built once and run
frame after frame) and the stage-by-stage functions the tasks call.

Stages that fail are made with the stage functions a `Pipeline` takes (its public
constructor arguments: what the simulator's fakes use), so that each status is seen on
its own."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from helpers import FIXTURES

from clearcli import pipeline
from clearcli.errors import InputError, NoPlanError, SceneError
from clearcli.pipeline import CLEARED, FAILED, NO_PLAN, NO_TABLE, OK, Pipeline
from clearcli.settings import Settings, settings_from_dict

FRAMES = ("two_touching_boxes", "box_on_box", "isolated_box")


@pytest.fixture(scope="module")
def frames() -> dict[str, Any]:
    return {name: pipeline.read(FIXTURES / f"{name}.pcd") for name in FRAMES}


def _same(a: pipeline.FrameResult, b: pipeline.FrameResult) -> None:
    assert a.status == b.status == OK
    assert np.array_equal(a.segmentation.labels(), b.segmentation.labels())
    assert a.state.facts == b.state.facts and a.state.names() == b.state.names()
    assert [x.pddl() for x in a.plan.actions] == [x.pddl() for x in b.plan.actions]
    assert a.plan.cost == b.plan.cost


def test_a_pipeline_reused_across_frames_gives_what_fresh_ones_give(frames: dict[str, Any]) -> None:
    settings = Settings()
    reused = Pipeline(settings)
    order = ["two_touching_boxes", "box_on_box", "two_touching_boxes"]
    results = [reused.run(frames[name]) for name in order]
    robot = reused.robot
    assert reused.robot is robot  # resolved once
    _same(results[0], results[2])  # the same frame again, after another one
    for name, result in zip(order[:2], results[:2]):
        _same(result, Pipeline(settings).run(frames[name]))
    # what the frames are: two boxes side by side, a stack of two
    assert [len(r.plan.goal) for r in results] == [2, 2, 2]
    assert [f[0] for f in results[1].state.facts] == ["on"] and not any(f[0] == "on" for f in results[0].state.facts)


def test_each_stage_is_timed(frames: dict[str, Any]) -> None:
    result = Pipeline(Settings()).run(frames["isolated_box"])
    assert result.status == OK and result.error == "" and result.stage == ""
    t = result.timings_s
    assert set(t) == {"segment", "predicates", "plan", "total"}
    assert all(v >= 0 for v in t.values())
    assert t["total"] >= t["segment"] + t["predicates"] + t["plan"]


def test_the_plan_stage_checks_what_replay_check_says_with_the_known_camera(frames: dict[str, Any]) -> None:
    seen: dict[str, Any] = {}

    def plan_fn(state: Any, settings: Any, **kw: Any) -> Any:
        seen.update(kw, settings=settings)
        return SimpleNamespace(actions=(), unreachable=(), cost=0)

    T = np.eye(4)
    settings = settings_from_dict({"plan": {"replay_check": "whole"}})
    result = Pipeline(settings, T_base_camera=T, plan_fn=plan_fn).run(frames["isolated_box"])
    assert seen["check"] == "whole" and seen["T_base_camera"] is T and seen["settings"] is settings
    # a plan of no actions: nothing can be done, the objects named
    assert result.status == NO_PLAN and result.stage == "plan" and "o0" in result.error


def test_adjust_changes_the_state_the_planner_gets_and_on_segmentation_sees_it_first(frames: dict[str, Any]) -> None:
    calls: list[str] = []
    planned_on: list[Any] = []

    def adjust(seg: Any, state: Any) -> Any:
        calls.append("adjust")
        return dataclasses.replace(state, source="adjusted")

    def plan_fn(state: Any, settings: Any, **kw: Any) -> Any:
        planned_on.append(state)
        return SimpleNamespace(actions=("a",), unreachable=())

    result = Pipeline(Settings(), plan_fn=plan_fn).run(
        frames["isolated_box"], adjust=adjust, on_segmentation=lambda seg: calls.append(f"seen {len(seg.objects)}")
    )
    assert calls == ["seen 1", "adjust"]
    assert planned_on[0].source == "adjusted" and result.state.source == "adjusted"
    assert result.status == OK


@pytest.mark.parametrize(
    ("error", "status"),
    [(SceneError("no table here"), NO_TABLE), (InputError("bad frame"), FAILED)],
)
def test_a_user_error_in_segmentation_is_the_frames_status(
    error: Exception, status: str, frames: dict[str, Any]
) -> None:
    def segment_fn(frame: Any, settings: Any) -> Any:
        raise error

    result = Pipeline(Settings(), segment_fn=segment_fn).run(frames["isolated_box"])
    assert (result.status, result.stage, result.error) == (status, "segment", str(error))
    assert result.exception is error and result.segmentation is None
    assert "segment" in result.timings_s and "predicates" not in result.timings_s


def test_a_table_with_no_object_is_cleared(frames: dict[str, Any]) -> None:
    real = pipeline.segmented(frames["isolated_box"], Settings())
    empty = dataclasses.replace(real, objects=())
    result = Pipeline(Settings(), segment_fn=lambda frame, s: empty).run(frames["isolated_box"])
    assert result.status == CLEARED and result.segmentation is empty and result.state is None


def test_no_plan_from_the_planner_is_its_status_with_its_plan(frames: dict[str, Any]) -> None:
    error = NoPlanError("nothing can be removed")
    error.plan = SimpleNamespace(actions=(), unreachable=("o0",))  # type: ignore[attr-defined]

    def plan_fn(*a: Any, **kw: Any) -> Any:
        raise error

    result = Pipeline(Settings(), plan_fn=plan_fn).run(frames["isolated_box"])
    assert (result.status, result.stage) == (NO_PLAN, "plan")
    assert result.plan is error.plan and result.state is not None  # type: ignore[attr-defined]


def test_an_internal_error_raises_unless_caught_and_then_says_where(
    frames: dict[str, Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    def state_fn(*a: Any) -> Any:
        raise RuntimeError("boom")

    p = Pipeline(Settings(), state_fn=state_fn)
    with pytest.raises(RuntimeError, match="boom"):
        p.run(frames["isolated_box"])
    monkeypatch.delenv("CLEAR_DEBUG", raising=False)
    result = p.run(frames["isolated_box"], catch_internal=True)
    assert (result.status, result.stage) == (FAILED, "predicates")
    assert result.error == "internal error in predicates: RuntimeError: boom"
    assert result.segmentation is not None
    monkeypatch.setenv("CLEAR_DEBUG", "1")  # a developer wants the traceback
    with pytest.raises(RuntimeError):
        p.run(frames["isolated_box"], catch_internal=True)


def test_the_stage_functions_one_by_one(frames: dict[str, Any]) -> None:
    settings = Settings()
    frame = pipeline.read(FIXTURES / "session.mcap", None, 3, settings)
    assert frame.frame_id == "camera_rgb_optical_frame"
    assert frame.stamp_s == pytest.approx(1_763_683_200.0 + 1.5)  # fixtures/README.md: frame 3
    # the frame's own labels: 8 objects left in frame 3 (fixtures/README.md)
    truth = pipeline.truth_segmentation(frame, "session.mcap")
    assert len(truth.objects) == 8
    state = pipeline.stated(frame, truth, settings)
    assert len(state.objects) == 8
    from clearcli.robot.arm import resolve_arm

    done = pipeline.planned(state, settings, resolve_arm(settings), None, None)
    assert done.no_plan is None and done.T_base_camera.shape == (4, 4)
    assert done.pose_source == "default from table"
    assert sorted(done.plan.goal) == sorted(state.names())


def test_truth_segmentation_needs_a_label_field(frames: dict[str, Any]) -> None:
    frame = frames["isolated_box"]
    bare = dataclasses.replace(frame, fields={k: v for k, v in frame.fields.items() if k != "label"})
    with pytest.raises(InputError, match="'label' field"):
        pipeline.truth_segmentation(bare, "bare.pcd")


def test_a_replaced_predicates_stage_receives_the_faces_to_avoid() -> None:
    # the closed loop's memory of a cup that did not seal reached only the default
    # stage: a replaced stage was bypassed whenever there was something to avoid
    calls: list[Any] = []
    sentinel: Any = object()

    def state_fn(frame: Any, seg: Any, settings: Any, avoid_faces: Any = None, /) -> Any:
        calls.append(avoid_faces)
        return sentinel

    p = Pipeline(Settings(), state_fn=state_fn)
    frame: Any = object()
    seg: Any = object()
    avoid = {0: frozenset({"top"})}
    assert p.state(frame, seg, avoid) is sentinel
    assert p.state(frame, seg) is sentinel
    assert p.state(frame, seg, {}) is sentinel
    assert calls == [avoid, None, None]
