"""Tests of clearcli/replay/memory.py."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers.plan_scenes import bare_object

from clearcli.perception.types import TablePlane
from clearcli.predicates.state import ObjectModel, PushModel, SymbolicState
from clearcli.replay.memory import (
    MemoryParams,
    PushMemory,
    PushRecord,
    apply_memory,
    expire,
    forget,
    push_costs,
    remember,
    undone_count,
)
from clearcli.replay.tracking import Observation, TrackerState, shape_signature, update

TABLE = TablePlane(normal=np.array([0.0, -1.0, 0.0]), offset=0.5)


def unit(angle_deg: float) -> np.ndarray:
    a = math.radians(angle_deg)
    return np.array([math.cos(a), 0.0, math.sin(a)])


def make_object(name: str, centroid: np.ndarray, first_axis_deg: float) -> ObjectModel:
    """An object whose dir1..dir4 are +a1, -a1, +a2, -a2 with a1 at ``first_axis_deg``
    on the table (x-z plane of the camera looking down)."""
    axes = {
        "dir1": first_axis_deg,
        "dir2": first_axis_deg + 180,
        "dir3": first_axis_deg + 90,
        "dir4": first_axis_deg - 90,
    }
    pushes = {
        d: PushModel(direction=d, unit_vector=unit(a), push_length_m=0.1, object_path=(), candidates=())
        for d, a in axes.items()
    }
    return bare_object(name, np.asarray(centroid, dtype=float), np.array([0.1, 0.08, 0.06]), pushes)


def make_state(objects: list[ObjectModel], costs: dict | None = None) -> SymbolicState:
    return SymbolicState(
        objects=tuple(objects),
        table=TABLE,
        table_polygon=np.zeros((0, 3)),
        facts=frozenset(),
        push_costs=costs or {},
    )


def test_undone_count_compares_unit_vectors() -> None:
    memory = remember(PushMemory(), PushRecord(5, (1.0, 0.0, 0.0), 0))
    assert undone_count(memory, 5, unit(180)) == 1
    assert undone_count(memory, 5, unit(180 + 50)) == 1  # within 60 degrees of the reverse
    assert undone_count(memory, 5, unit(180 + 70)) == 0
    assert undone_count(memory, 5, unit(0)) == 0
    assert undone_count(memory, 5, unit(90)) == 0
    assert undone_count(memory, 6, unit(180)) == 0  # another object
    # a non-unit record is normalised
    memory = remember(PushMemory(), PushRecord(5, (3.0, 0.0, 0.0), 0))
    assert memory.records[0].unit_vector == (1.0, 0.0, 0.0)


def test_reverse_of_last_push_costs_more_whatever_its_name() -> None:
    # last frame track 7 was pushed along +x; this frame its PCA axis flipped, so the
    # reverse (-x) is now called dir1
    memory = remember(PushMemory(), PushRecord(7, (1.0, 0.0, 0.0), 0))
    state = make_state([make_object("o0", np.zeros(3), 180.0), make_object("o1", np.ones(3), 180.0)])
    costs = push_costs(state, {"o0": 7, "o1": 8}, memory)
    assert costs == {("o0", "dir1"): 1 + MemoryParams().reverse_penalty}
    planned = apply_memory(state, {"o0": 7, "o1": 8}, memory)
    assert planned.push_costs[("o0", "dir1")] == 201
    assert ("o0", "dir2") not in planned.push_costs  # continuing the push stays cheap
    assert planned.facts == state.facts and planned.objects == state.objects
    assert state.push_costs == {}  # the input is unchanged


def test_penalty_adds_to_existing_cost_and_escalates() -> None:
    memory = PushMemory()
    for frame, u in enumerate([(1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (1.0, 0.0, 0.0)]):
        memory = remember(memory, PushRecord(2, u, frame))
    state = make_state([make_object("o3", np.zeros(3), 0.0)], {("o3", "dir1"): 4, ("o3", "dir2"): 1})
    costs = push_costs(state, {"o3": 2}, memory)
    assert costs[("o3", "dir1")] == 4 + 200 * 1  # undoes the one -x push
    assert costs[("o3", "dir2")] == 1 + 200 * 2  # undoes both +x pushes
    assert costs.get(("o3", "dir3"), 1) == 1


def test_memory_is_bounded() -> None:
    params = MemoryParams(per_object=2, max_objects=3)
    memory = PushMemory()
    for k in range(10):
        memory = remember(memory, PushRecord(k % 5, (1.0, 0.0, 0.0), k), params)
    assert len(memory.records) <= params.per_object * params.max_objects
    assert {r.track_id for r in memory.records} == {2, 3, 4}
    assert [r.frame_index for r in memory.of(4)] == [9]  # its push at 4 went with it when it was least recent
    assert forget(memory, {4}).of(4) == ()
    assert [r.frame_index for r in expire(memory, 40, MemoryParams(horizon_frames=32)).records] == [8, 9]


def _run_session(with_memory: bool, frames: int = 12) -> list[str]:
    position = np.zeros(3)
    tracker = TrackerState()
    memory = PushMemory()
    actions: list[str] = []
    last_motion: np.ndarray | None = None
    effect = None
    for frame in range(frames):
        if abs(position[0]) >= 0.2 - 1e-9:
            actions.append("grasp")
            break
        observation = Observation(tuple(position), shape_signature((0.1, 0.08, 0.06)))  # type: ignore[arg-type]
        tracker, assignment = update(tracker, [observation], frame, effect)
        track_id = assignment.ids[0]
        obj = make_object("o0", position, 0.0 if frame % 2 == 0 else 180.0)
        state = make_state([obj])
        if with_memory:
            state = apply_memory(state, {"o0": track_id}, memory)
        candidates = ["dir1", "dir2"]
        cost = {d: state.push_costs.get(("o0", d), 1) for d in candidates}
        best = min(cost.values())
        ties = [d for d in candidates if cost[d] == best]

        def backwards(d: str) -> float:
            return float(-(obj.pushes[d].unit_vector @ last_motion)) if last_motion is not None else 0.0  # noqa: B023 (used within the iteration)

        choice = max(ties, key=backwards)
        u = obj.pushes[choice].unit_vector
        actions.append("+x" if u[0] > 0 else "-x")
        memory = remember(memory, PushRecord(track_id, tuple(u), frame))  # type: ignore[arg-type]
        from clearcli.replay.tracking import ExpectedEffect

        effect = ExpectedEffect("push", track_id, tuple(position), "", tuple(u), 0.1, (0.1, 0.08, 0.06))  # type: ignore[arg-type]
        position = position + 0.1 * u
        last_motion = u
    return actions


def test_without_memory_the_thesis_loop_happens() -> None:
    actions = _run_session(with_memory=False)
    assert "grasp" not in actions
    assert actions[:4] == ["+x", "-x", "+x", "-x"]


def test_with_memory_the_loop_cannot_happen() -> None:
    actions = _run_session(with_memory=True)
    assert actions == ["+x", "+x", "grasp"]


@pytest.mark.parametrize("angle", [0.0, 37.0, 123.0, 270.0])
def test_reverse_is_penalised_for_any_axis_orientation(angle: float) -> None:
    memory = remember(PushMemory(), PushRecord(1, tuple(unit(angle)), 0))  # type: ignore[arg-type]
    state = make_state([make_object("o0", np.zeros(3), angle + 180.0 + 10.0)])
    costs = apply_memory(state, {"o0": 1}, memory).push_costs
    assert costs == {("o0", "dir1"): 201}
