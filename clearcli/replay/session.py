"""The replay loop: frame after frame through the pipeline, with identity, monitoring and
push memory carried from one frame to the next, and nothing else kept.

`Session.step` takes one frame and returns a `FrameReport`; `replay` drives a session
over an iterator of frames (--every, --from/--to, the end of a cleared table, a log cut
short). The state kept between frames is bounded: the tracker's tracks (objects seen in
the last few frames), the push memory (a few pushes per object), the previous frame's
expected effect, and the summary's counters.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from clearcli.errors import ClearError, PartialLogError
from clearcli.pipeline import CLEARED, FAILED, NO_PLAN, NO_TABLE, OK, FrameResult, Pipeline
from clearcli.planning.probe import AXES, off_centre_first, off_seam, probe_push
from clearcli.predicates.grasps import kind as grasp_kind
from clearcli.predicates.grasps import kinds as grasp_kinds
from clearcli.predicates.state import DIRECTIONS
from clearcli.replay import memory as push_memory
from clearcli.replay.memory import PushMemory, PushRecord
from clearcli.replay.report import FrameReport, ObjectReport, Summary
from clearcli.replay.tracking import (
    Assignment,
    ExpectedEffect,
    Observation,
    TrackerState,
    check_execution,
    shape_signature,
    update,
    vec3,
)
from clearcli.settings.replay import MemoryParams, TrackingParams
from clearcli.settings.weigh import lightest_plausible

if TYPE_CHECKING:
    from clearcli.io.frames import Frame
    from clearcli.perception.types import Segmentation
    from clearcli.planning.types import Action
    from clearcli.predicates.state import SymbolicState

# a failed grasp whose object's centroid moved less than this (m): it stayed where it was
_STAYED_M = 0.01


@dataclass(frozen=True)
class ReplayOptions:
    every: int = 1  # process every N-th frame of the log (1 = all)
    from_s: float | None = None  # seconds from the start of the log
    to_s: float | None = None
    fail_fast: bool = False  # a failed frame ends the replay (raises)
    push_memory: bool = True  # False: the thesis's behaviour, for control runs
    stop_when_cleared: bool = True  # a frame with an empty table ends the session
    # None: the pipeline's settings' [tracking] and [memory] (their one home)
    tracking: TrackingParams | None = None
    memory: MemoryParams | None = None


def observations_of(segmentation: Segmentation) -> list[Observation]:
    return [
        Observation(centroid=vec3(o.centroid), extents_m=shape_signature(o.obb_extents)) for o in segmentation.objects
    ]


def expected_effect(
    action: Action, state: SymbolicState, ids_by_name: Mapping[str, int], observations: list[Observation]
) -> ExpectedEffect | None:
    """What ``action`` (the first of this frame's plan) should do, for the next frame."""
    track_id = ids_by_name.get(action.obj)
    if track_id is None:
        return None
    obj = state.by_name(action.obj)
    seen = observations[obj.segment_index] if 0 <= obj.segment_index < len(observations) else None
    start = seen.centroid if seen is not None else vec3(obj.centroid)
    extents = seen.extents_m if seen is not None else shape_signature(obj.extents_m)
    label = f"({action.pddl_name} #{track_id}{' ' + action.direction if action.direction else ''})"
    if action.kind == "push" and action.direction is not None:
        push = obj.pushes[action.direction]
        return ExpectedEffect(
            kind="push",
            track_id=track_id,
            start_centroid=start,
            action=label,
            unit_vector=vec3(push.unit_vector),
            push_length_m=float(push.push_length_m),
            extents_m=extents,
        )
    return ExpectedEffect(
        kind="grasp",
        track_id=track_id,
        start_centroid=start,
        action=label,
        extents_m=extents,
        grasp_kind=action.grasp_kind,
        grasp_face=str(obj.kind_details.get(action.grasp_kind or "", {}).get("face", "")),
    )


class Session:
    """Carries identity, expectations and push memory from frame to frame."""

    def __init__(self, pipeline: Pipeline, options: ReplayOptions = ReplayOptions()) -> None:
        self.pipeline = pipeline
        settings = pipeline.settings
        self.options = dataclasses.replace(
            options,
            tracking=options.tracking if options.tracking is not None else settings.tracking,
            memory=options.memory if options.memory is not None else settings.memory,
        )
        self.tracker = TrackerState()
        self.memory = PushMemory()
        self.effect: ExpectedEffect | None = None
        self.frame_count = 0  # frames processed: the tracker's clock
        self.summary = Summary()
        # track id -> grasps in a row that did not take it
        self.failed_grasps: dict[int, int] = {}
        self.failed_kinds: dict[int, set[str]] = {}  # per track: the grasp kinds that failed
        # per track: (kind, face) tries of a kind with faces that failed; kept across a
        # push (a porous top is porous wherever the object stands)
        self.failed_faces: dict[int, set[tuple[str, str]]] = {}
        # track id -> push axes tried on it to see whether it comes apart (probe.py)
        self.probed: dict[int, frozenset[str]] = {}

    def _params(self) -> tuple[TrackingParams, MemoryParams]:
        """The session's [tracking] and [memory]: the options', filled in by __init__."""
        tracking, memory = self.options.tracking, self.options.memory
        assert tracking is not None and memory is not None  # __init__ put the settings' in
        return tracking, memory

    def step(self, frame: Frame, index: int, time_s: float = 0.0, read_s: float = 0.0) -> FrameReport:
        clock = self.frame_count
        self.frame_count += 1
        options = self.options
        tracking_params, memory_params = self._params()
        self.memory = push_memory.expire(self.memory, clock, memory_params)
        found: dict[str, Any] = {}

        def on_segmentation(segmentation: Segmentation) -> None:
            observations = observations_of(segmentation)
            self.tracker, assignment = update(self.tracker, observations, clock, self.effect, tracking_params)
            found["observations"] = observations
            found["assignment"] = assignment
            if self.effect is not None:
                execution = check_execution(self.effect, observations, assignment, tracking_params)
                found["execution"] = execution
                # what the last action did changes what this frame may plan
                if execution.outcome == "done" and self.effect.kind == "grasp":
                    self.memory = push_memory.forget(self.memory, {self.effect.track_id})
                kind = grasp_kind(self.effect.grasp_kind) if self.effect.kind == "grasp" else None
                other_faces = (
                    set(kind.faces)
                    - {f for k, f in self.failed_faces.get(self.effect.track_id, set()) if k == kind.name}
                    if kind is not None and self.effect.grasp_face in kind.faces
                    else set()
                )
                if kind is not None and execution.outcome != "done" and other_faces - {self.effect.grasp_face}:
                    # a kind with faces that failed on one: the next plan tries another
                    # face (the predicates leave this one out), the kind is not given up
                    tid = self.effect.track_id
                    self.failed_faces.setdefault(tid, set()).add((kind.name, self.effect.grasp_face))
                elif self.effect.kind == "grasp" and execution.outcome != "done":
                    tid = self.effect.track_id
                    if kind is not None and self.effect.grasp_face in kind.faces:
                        # its last face failed too: remembered with the others, so that
                        # a push (which gives the kind back) does not bring the same
                        # try back (a cup retried on the same side after each push)
                        self.failed_faces.setdefault(tid, set()).add((kind.name, self.effect.grasp_face))
                    self.failed_grasps[tid] = self.failed_grasps.get(tid, 0) + 1
                    self.failed_kinds.setdefault(tid, set()).add(self.effect.grasp_kind)
                    stayed = execution.moved_m is not None and execution.moved_m < _STAYED_M
                    if grasp_kind(self.effect.grasp_kind).give_up_unmoved and stayed:
                        # a try of that kind that did not move the object (a slide's) met
                        # something the model did not: the same try would meet it again,
                        # so it is given up at once (a pinch that slips may hold the next time)
                        self.failed_grasps[tid] = max(
                            self.failed_grasps[tid], self.pipeline.settings.plan.max_failed_grasps
                        )
                elif self.effect.kind == "push" and execution.outcome == "done":
                    self.failed_grasps.pop(self.effect.track_id, None)  # it stands elsewhere now
                    self.failed_kinds.pop(self.effect.track_id, None)
                elif execution.outcome != "done" and self.effect.kind == "push":
                    self.memory = push_memory.mark_failed(self.memory, self.effect.track_id)

        def adjust(segmentation: Segmentation, state: SymbolicState) -> SymbolicState:
            assignment: Assignment = found["assignment"]
            ids = {o.name: assignment.ids[o.segment_index] for o in state.objects}
            found["ids_by_name"] = ids
            limit = self.pipeline.settings.plan.max_failed_grasps
            # the kinds of grasp that kept failing on it (the pinch's fact as before; a rim
            # grasp's or a slide's their own)
            thesis = grasp_kinds()[0].name
            failed = {
                (grasp_kind(k).facts.ik, n)
                for n, tid in ids.items()
                if limit > 0 and self.failed_grasps.get(tid, 0) >= limit
                for k in sorted(self.failed_kinds.get(tid, {thesis}))
            }
            if failed - state.facts:
                state = dataclasses.replace(state, facts=state.facts | failed)
                # a grasp that keeps taking nothing may be closing on two objects the
                # segmentation merged: push such an object with the fingers off the
                # middle of its face, where they meet one of the two
                for _, name in sorted(f for f in failed if f[0] == "ik_unfeasible_grasp"):
                    for d in DIRECTIONS:
                        state = off_seam(state, name, d, self.pipeline.settings.gripper)
            if self.pipeline.settings.plan.regrasp_off_centre:
                for name, tid in sorted(ids.items()):
                    failures = self.failed_grasps.get(tid, 0)
                    if 0 < failures and ("ik_unfeasible_grasp", name) not in state.facts:
                        state = off_centre_first(state, name, failures)
            if not options.push_memory:
                return state
            return push_memory.apply_memory(state, ids, self.memory, memory_params)

        def avoid_faces(segmentation: Segmentation) -> dict[int, frozenset[str]]:
            """Segment index -> the faces that failed on its track (kinds with faces)."""
            ids = found["assignment"].ids if "assignment" in found else ()
            return {
                index: frozenset(f for _k, f in self.failed_faces[tid])
                for index, tid in enumerate(ids)
                if tid in self.failed_faces
            }

        result = self.pipeline.run(
            frame,
            adjust=adjust,
            on_segmentation=on_segmentation,
            catch_internal=not options.fail_fast,
            avoid_faces=avoid_faces,
        )
        if result.status == NO_PLAN:
            result = self._weigh_on_lift(frame, result, adjust, avoid_faces)
        if result.status == NO_PLAN:
            result = self._probe(result, found)
        report = self._report(frame, index, time_s, read_s, result, found)
        self._account(report, found)
        return report

    def _weigh_on_lift(
        self,
        frame: Frame,
        result: FrameResult,
        adjust: Callable[[Segmentation, SymbolicState], SymbolicState],
        avoid_faces: Callable[[Segmentation], Mapping[int, frozenset[str]]],
    ) -> FrameResult:
        """Nothing to do while a cup's load was judged on a mass estimated from the
        volume at [suction] density_kg_m3 (the median household object's: a big light box
        of 5 l is estimated at 3.5 kg, and may truly weigh 0.2) and with the safety
        factor: plan this frame once more as if the object were as light as a household
        object plausibly is (clearcli/settings/weigh.py), against the cup's own hold
        (factor 1). What only the estimate refused is then tried rather than given up:
        the cup seals and the arm lifts, which weighs it (a vacuum that does not hold
        lets it down where it stood), and a cup that did not hold is given up on that
        object (the kind's ``give_up_unmoved``), so each such object costs one try, as
        the Amazon Robotics Challenge systems tried suction first and checked the
        vacuum. Else ``result``."""
        seg = result.segmentation
        relaxed = lightest_plausible(self.pipeline.settings)  # shared with the plan task
        if seg is None or result.state is None or relaxed is None:
            return result
        pipeline = self.pipeline.with_settings(relaxed)
        t0 = time.perf_counter()
        timings = dict(result.timings_s)
        try:
            state = adjust(seg, pipeline.state(frame, seg, avoid_faces(seg)))
            plan = pipeline.plan(state)
        except ClearError:
            plan = None
        timings["plan"] = timings.get("plan", 0.0) + time.perf_counter() - t0
        if plan is None or not plan.actions:
            return dataclasses.replace(result, timings_s=timings)
        return dataclasses.replace(
            result, status=OK, state=state, plan=plan, error="", stage="", exception=None, timings_s=timings
        )

    def _probe(self, result: FrameResult, found: dict[str, Any]) -> FrameResult:
        """Nothing to do: push once an object too wide for the gripper that may be two
        merged ones (clearcli/planning/probe.py), if there is one; else ``result``."""
        settings = self.pipeline.settings
        state, plan = result.state, result.plan
        ids: dict[str, int] = found.get("ids_by_name", {})
        if (
            settings.plan.probe_max_width_m <= 0
            or state is None
            or plan is None
            or not (plan.ungraspable or plan.unreachable)
        ):
            return result
        T_base_camera = plan.T_base_camera if plan.T_base_camera is not None else self.pipeline.T_base_camera
        if T_base_camera is None:
            return result
        t0 = time.perf_counter()
        tried = {name: self.probed[tid] for name, tid in ids.items() if tid in self.probed}
        limit = settings.plan.max_failed_grasps
        failed = {name for name, tid in ids.items() if self.failed_grasps.get(tid, 0) >= limit}
        probe = probe_push(state, plan, settings, T_base_camera, tried=tried, failed=failed, robot=self.pipeline.robot)
        timings = dict(result.timings_s)
        timings["plan"] = timings.get("plan", 0.0) + time.perf_counter() - t0
        if probe is None:
            return dataclasses.replace(result, timings_s=timings)
        if probe.probe in ids:
            tid = ids[probe.probe]
            self.probed[tid] = self.probed.get(tid, frozenset()) | {AXES[str(probe.actions[0].direction)]}
        return dataclasses.replace(result, status=OK, plan=probe, error="", stage="", exception=None, timings_s=timings)

    def _report(
        self,
        frame: Frame,
        index: int,
        time_s: float,
        read_s: float,
        result: FrameResult,
        found: dict[str, Any],
    ) -> FrameReport:
        objects: tuple[ObjectReport, ...] = ()
        gone: tuple[int, ...] = ()
        assignment: Assignment | None = found.get("assignment")
        if assignment is not None:
            names: dict[int, str] = {}
            if result.state is not None:
                names = {o.segment_index: o.name for o in result.state.objects}
            observations: list[Observation] = found["observations"]
            objects = tuple(
                ObjectReport(
                    track_id=tid,
                    name=names.get(k, ""),
                    segment_index=k,
                    centroid_m=observations[k].centroid,
                    extents_m=observations[k].extents_m,
                    new=tid in assignment.new,
                )
                for k, tid in enumerate(assignment.ids)
            )
            gone = assignment.gone
        timings = {"read": read_s, **result.timings_s}
        timings["total"] = read_s + result.timings_s.get("total", 0.0)
        undoes = False
        if result.status == OK and result.plan is not None and result.state is not None:
            first = result.plan.actions[0]
            ids = found.get("ids_by_name", {})
            if first.kind == "push" and first.direction is not None and first.obj in ids:
                u = result.state.by_name(first.obj).pushes[first.direction].unit_vector
                undoes = push_memory.reverses_last(self.memory, ids[first.obj], u, self._params()[1])
        return FrameReport(
            index=index,
            stamp_s=frame.stamp_s,
            time_s=time_s,
            result=result,
            objects=objects,
            gone=gone,
            execution=found.get("execution"),
            undoes_push=undoes,
            timings_s=timings,
            frame=frame,
        )

    def _account(self, report: FrameReport, found: dict[str, Any]) -> None:
        """Update the summary and what the next frame is compared with."""
        s = self.summary
        result = report.result
        s.frames += 1
        for stage, seconds in report.timings_s.items():
            s.time_s[stage] = s.time_s.get(stage, 0.0) + float(seconds)
        s.objects_seen = self.tracker.next_id
        if report.execution is not None:
            if report.execution.outcome == "done":
                s.executions_done += 1
            else:
                s.executions_failed += 1
        if "assignment" in found:
            # the expectation has been checked against a segmented frame: it is spent
            self.effect = None
        status = result.status
        if status == OK:
            s.ok += 1
        elif status == CLEARED:
            s.cleared = True
        elif status == NO_TABLE:
            s.no_table += 1
        elif status == NO_PLAN:
            s.no_plan += 1
        elif status == FAILED:
            s.failed += 1
        plan = result.plan
        ids = report.ids_by_name
        if plan is not None:
            s.unreachable_ids.update(ids[n] for n in plan.unreachable if n in ids)
        if status != OK or plan is None or result.state is None:
            return
        first = plan.actions[0]
        if first.kind == "grasp":
            s.grasps += 1
        else:
            s.pushes += 1
        if report.undoes_push:
            s.back_and_forth += 1
        observations: list[Observation] = found["observations"]
        self.effect = expected_effect(first, result.state, ids, observations)
        if self.effect is not None and self.effect.kind == "push" and self.effect.unit_vector is not None:
            self.memory = push_memory.remember(
                self.memory,
                PushRecord(self.effect.track_id, self.effect.unit_vector, self.frame_count - 1),
                self._params()[1],
            )


def replay(
    frames: Iterable[Frame],
    session: Session,
    log_start_s: float | None = None,
) -> Iterator[FrameReport]:
    """Run ``session`` over ``frames``; yields one report per processed frame.

    Stops after a frame with an empty table (when the options say so), at --to, or when
    the frames end. A log that ends in a corrupt or truncated part raises
    `PartialLogError` from the reader: that is recorded in ``session.summary.stopped``
    and re-raised after every complete frame has been reported. A frame whose stage
    fails is reported and the replay goes on, unless ``fail_fast``.
    """
    options = session.options
    every = max(1, int(options.every))
    summary = session.summary
    started = time.perf_counter()
    iterator = iter(frames)
    start_s = log_start_s
    index = -1
    try:
        while True:
            t_read = time.perf_counter()
            try:
                frame = next(iterator)
            except StopIteration:
                break
            except PartialLogError as exc:
                summary.stopped = str(exc)
                raise
            read_s = time.perf_counter() - t_read
            index += 1
            summary.frames_read += 1
            if start_s is None:
                start_s = frame.stamp_s
            time_s = frame.stamp_s - start_s
            if options.to_s is not None and time_s > options.to_s + 1e-9:
                break
            if options.from_s is not None and time_s < options.from_s - 1e-9:
                continue
            if index % every:
                continue
            report = session.step(frame, index, time_s, read_s)
            summary.wall_s = time.perf_counter() - started
            yield report
            if report.status == FAILED and options.fail_fast:
                error = report.result.exception
                message = (
                    f"{frame.source or 'frame'}: {report.result.stage} failed on frame {index}: "
                    f"{report.result.error} (stopped by --fail-fast)"
                )
                if isinstance(error, ClearError):
                    raise type(error)(message) from None
                raise ClearError(message)
            if report.status == CLEARED and options.stop_when_cleared:
                break
    finally:
        summary.wall_s = time.perf_counter() - started
        close = getattr(iterator, "close", None)
        if close is not None:
            close()
