"""Push memory: the planner must not undo a push it just made.

The thesis (section 7.2) replans every frame from scratch; when an object can be pushed
both ways along an axis at the same cost, it may push it one way, then back, forever.
Here the session remembers the last few pushes of each tracked object (by track id, not
by the frame's o-names, and by unit vector, not by dir1..dir4, since both change between
frames) and makes any push that would undo one of them more expensive, by raising
`SymbolicState.push_costs` before planning. The planner then takes a reverse push only
when no plan without one is cheaper; every push it makes is remembered too, so each
further swing of a back-and-forth costs more than the one before.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from clearcli.predicates.state import SymbolicState
from clearcli.replay.tracking import Vec3, vec3
from clearcli.settings.replay import MemoryParams  # [memory]: defaults and ranges


@dataclass(frozen=True)
class PushRecord:
    track_id: int
    unit_vector: Vec3  # sensor frame, on the table plane
    frame_index: int
    # False once monitoring saw that the push did not move the object (jammed): then
    # the same push again is what would loop, not its reverse.
    moved: bool = True


@dataclass(frozen=True)
class PushMemory:
    records: tuple[PushRecord, ...] = ()

    def of(self, track_id: int) -> tuple[PushRecord, ...]:
        return tuple(r for r in self.records if r.track_id == track_id)


def remember(memory: PushMemory, record: PushRecord, params: MemoryParams = MemoryParams()) -> PushMemory:
    """Memory with ``record`` added, keeping at most ``per_object`` per object and
    ``max_objects`` objects (the least recently pushed are dropped)."""
    u = np.asarray(record.unit_vector, dtype=float)
    norm = float(np.linalg.norm(u))
    if norm > 0:
        record = dataclasses.replace(record, unit_vector=vec3(u / norm))
    records = memory.records + (record,)
    own = [r for r in records if r.track_id == record.track_id]
    if len(own) > params.per_object:
        drop = set(map(id, own[: len(own) - params.per_object]))
        records = tuple(r for r in records if id(r) not in drop)
    last_push: dict[int, int] = {}
    for k, r in enumerate(records):
        last_push[r.track_id] = k
    if len(last_push) > params.max_objects:
        keep = set(sorted(last_push, key=last_push.__getitem__)[-params.max_objects :])
        records = tuple(r for r in records if r.track_id in keep)
    return PushMemory(records=records)


def forget(memory: PushMemory, track_ids: set[int] | frozenset[int]) -> PushMemory:
    """Memory without the given objects (grasped, or gone for good)."""
    return PushMemory(records=tuple(r for r in memory.records if r.track_id not in track_ids))


def expire(memory: PushMemory, frame_index: int, params: MemoryParams = MemoryParams()) -> PushMemory:
    """Memory without pushes older than the horizon."""
    return PushMemory(records=tuple(r for r in memory.records if frame_index - r.frame_index <= params.horizon_frames))


def mark_failed(memory: PushMemory, track_id: int) -> PushMemory:
    """Memory with the last push of ``track_id`` marked as not having moved it."""
    own = memory.of(track_id)
    if not own:
        return memory
    last = own[-1]
    return PushMemory(records=tuple(dataclasses.replace(r, moved=False) if r is last else r for r in memory.records))


def undone_count(
    memory: PushMemory, track_id: int, unit_vector: np.ndarray, params: MemoryParams = MemoryParams()
) -> int:
    """How many remembered pushes of this object a push along ``unit_vector`` would undo
    (a push that moved it, in reverse) or repeat in vain (a push that did not, again)."""
    u = np.asarray(unit_vector, dtype=float)
    norm = float(np.linalg.norm(u))
    if norm == 0.0:
        return 0
    u = u / norm
    limit = math.cos(math.radians(params.reverse_angle_deg))
    count = 0
    for r in memory.of(track_id):
        cos = float(np.dot(u, r.unit_vector))
        if (r.moved and cos <= -limit) or (not r.moved and cos >= limit):
            count += 1
    return count


def reverses_last(
    memory: PushMemory, track_id: int, unit_vector: np.ndarray, params: MemoryParams = MemoryParams()
) -> bool:
    """Does a push along ``unit_vector`` go back along the last push that moved the object?
    (The thesis's back-and-forth, counted by replays and the benchmark.)"""
    moved = [r for r in memory.of(track_id) if r.moved]
    if not moved:
        return False
    u = np.asarray(unit_vector, dtype=float)
    norm = float(np.linalg.norm(u))
    if norm == 0.0:
        return False
    limit = math.cos(math.radians(params.reverse_angle_deg))
    return float(np.dot(u / norm, moved[-1].unit_vector)) <= -limit


def push_costs(
    state: SymbolicState,
    ids_by_name: Mapping[str, int],
    memory: PushMemory,
    params: MemoryParams = MemoryParams(),
) -> dict[tuple[str, str], int]:
    """The state's push costs with every undoing push made dearer."""
    costs: dict[tuple[str, str], int] = dict(state.push_costs)
    for obj in state.objects:
        track_id = ids_by_name.get(obj.name)
        if track_id is None or not memory.of(track_id):
            continue
        for direction, push in obj.pushes.items():
            undone = undone_count(memory, track_id, push.unit_vector, params)
            if undone:
                base = int(costs.get((obj.name, direction), 1))
                costs[(obj.name, direction)] = base + params.reverse_penalty * undone
    return costs


def apply_memory(
    state: SymbolicState,
    ids_by_name: Mapping[str, int],
    memory: PushMemory,
    params: MemoryParams = MemoryParams(),
) -> SymbolicState:
    """The state to plan on: the same facts, with undoing pushes costing more."""
    if not memory.records:
        return state
    costs = push_costs(state, ids_by_name, memory, params)
    if costs == dict(state.push_costs):
        return state
    return dataclasses.replace(state, push_costs=costs)
