"""What a replay reports: per frame (`FrameReport`: the objects with their stable ids,
the plan, whether the last action happened) and over the session (`Summary`), with their
lines of `clear replay --json` (schema documented in `clearcli/commands/replay.py`)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from clearcli.pipeline import FrameResult
from clearcli.replay.tracking import ExecutionReport

if TYPE_CHECKING:
    from clearcli.io.frames import Frame
    from clearcli.planning.types import Action

STAGES = ("read", "segment", "predicates", "plan", "total")


@dataclass(frozen=True)
class ObjectReport:
    track_id: int
    name: str  # the name in this frame's state ("" when predicates did not run)
    segment_index: int
    centroid_m: tuple[float, float, float]
    extents_m: tuple[float, float, float]
    new: bool


@dataclass(frozen=True, eq=False)
class FrameReport:
    index: int  # position of the frame on its topic (0-based), as the reader counts
    stamp_s: float
    time_s: float  # seconds from the start of the log
    result: FrameResult
    objects: tuple[ObjectReport, ...] = ()
    gone: tuple[int, ...] = ()
    execution: ExecutionReport | None = None
    undoes_push: bool = False  # the first action pushes an object back where it came from
    timings_s: Mapping[str, float] = field(default_factory=dict)
    frame: Frame | None = None  # the frame itself, for writers (not in the JSON)

    @property
    def status(self) -> str:
        return self.result.status

    @property
    def ids_by_name(self) -> dict[str, int]:
        return {o.name: o.track_id for o in self.objects if o.name}

    def first_action(self) -> Action | None:
        plan = self.result.plan
        if plan is None or not plan.actions:
            return None
        return plan.actions[0]

    def plan_json(self) -> dict[str, Any] | None:
        """The plan with track ids (the same dict goes to the annotated log)."""
        plan = self.result.plan
        if plan is None:
            return None
        ids = self.ids_by_name
        return {
            "frame": self.index,
            "actions": [action_json(a, ids) for a in plan.actions],
            "cost": int(plan.cost),
            "optimal": bool(plan.optimal),
            "replans": int(plan.replans),
            "unreachable": [ids.get(n, n) for n in plan.unreachable],
            "ungraspable": [ids.get(n, n) for n in getattr(plan, "ungraspable", ())],
            "stuck": [ids.get(n, n) for n in getattr(plan, "stuck", ())],
            # a probing push (planning/probe.py): the id of the object pushed to see whether
            # it is two merged ones, else null
            "probe": ids.get(plan.probe, plan.probe) if getattr(plan, "probe", "") else None,
        }

    def to_json(self) -> dict[str, Any]:
        """One `frame` line of `clear replay --json` (without the envelope)."""
        first = self.first_action()
        first_json = None
        if first is not None:
            first_json = action_json(first, self.ids_by_name)
            state = self.result.state
            if first.kind == "push" and state is not None and first.direction is not None:
                push = state.by_name(first.obj).pushes.get(first.direction)
                if push is not None:
                    first_json["unit_vector"] = [round(float(v), 6) for v in push.unit_vector]
                    first_json["push_length_m"] = round(float(push.push_length_m), 6)
        plan = self.result.plan
        return {
            "type": "frame",
            "index": self.index,
            "stamp_s": _finite(self.stamp_s),
            "time_s": _finite(self.time_s),
            "status": self.status,
            "objects": [
                {
                    "id": o.track_id,
                    "name": o.name,
                    "centroid_m": [round(v, 5) for v in o.centroid_m],
                    "extents_m": [round(v, 5) for v in o.extents_m],
                    "new": o.new,
                }
                for o in self.objects
            ],
            "gone": list(self.gone),
            "first_action": first_json,
            "plan_length": len(plan.actions) if plan is not None else 0,
            "plan": self.plan_json(),
            "execution": execution_json(self.execution),
            "undoes_push": self.undoes_push,
            "timings_s": {k: round(float(v), 6) for k, v in self.timings_s.items()},
            "error": self.result.error or None,
            "stage": self.result.stage or None,
        }


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def action_json(action: Action, ids_by_name: Mapping[str, int]) -> dict[str, Any]:
    out: dict[str, Any] = {"kind": action.kind, "id": ids_by_name.get(action.obj), "name": action.obj}
    if action.kind == "grasp":  # which grasp: "pinch", "rim", "slide"
        out["grasp_kind"] = action.grasp_kind
    if action.direction is not None:
        out["direction"] = action.direction
    return out


def execution_json(report: ExecutionReport | None) -> dict[str, Any] | None:
    if report is None:
        return None
    out: dict[str, Any] = {
        "action": report.action,
        "id": report.track_id,
        "outcome": report.outcome,
        "detail": report.detail,
    }
    if report.moved_along_m is not None:
        out["moved_along_m"] = round(report.moved_along_m, 5)
        out["moved_across_m"] = round(float(report.moved_across_m or 0.0), 5)
    return out


@dataclass
class Summary:
    """Counters over the whole replay (a fixed number of fields: bounded)."""

    frames_read: int = 0
    frames: int = 0  # processed
    ok: int = 0
    cleared: bool = False
    no_table: int = 0
    no_plan: int = 0
    failed: int = 0
    objects_seen: int = 0
    grasps: int = 0
    pushes: int = 0
    executions_done: int = 0
    executions_failed: int = 0
    back_and_forth: int = 0
    unreachable_ids: set[int] = field(default_factory=set)
    time_s: dict[str, float] = field(default_factory=lambda: {s: 0.0 for s in STAGES})
    stopped: str = ""  # why the log ended early (a partial log), "" when read whole
    wall_s: float = 0.0

    def to_json(self) -> dict[str, Any]:
        n = max(self.frames, 1)
        return {
            "type": "summary",
            "frames_read": self.frames_read,
            "frames": self.frames,
            "ok": self.ok,
            "cleared": self.cleared,
            "no_table": self.no_table,
            "no_plan": self.no_plan,
            "failed": self.failed,
            "objects_seen": self.objects_seen,
            "actions": self.grasps + self.pushes,
            "grasps": self.grasps,
            "pushes": self.pushes,
            "executions": {"done": self.executions_done, "failed": self.executions_failed},
            "back_and_forth": self.back_and_forth,
            "unreachable": sorted(self.unreachable_ids),
            "time_s": {k: round(v, 6) for k, v in self.time_s.items()},
            "mean_time_s": {k: round(v / n, 6) for k, v in self.time_s.items()},
            "frames_per_s": round(self.frames / self.wall_s, 4) if self.wall_s > 0 else None,
            "stopped": self.stopped or None,
        }
