"""The one-frame pipeline: frame -> segmentation -> symbolic state -> plan.

`Pipeline` holds what is worth keeping between frames (settings, the robot -- its
profile and kinematics model, clearcli/robot/arm.py -- and its placement, the stage
functions, resolved once) and runs the stages one by one, timing each, so that a replay
can step in between them (tracking needs the segmentation before the state is planned
on, push memory changes the state's costs). `Pipeline.run` chains them for one frame.
The stages themselves are the stage modules' pure functions: segmentation imported with
this module, predicates, planning and the arm where first called (`clear segment` runs
neither); their heavy libraries (SciPy, Pinocchio, FCL) are imported by the stages when first
used. What the stages build per call is cheap once those libraries are imported (an IK
search on the arm's model, the gripper boxes: microseconds), so nothing else is cached:
the first frame pays the imports (about 2 s), later frames only their own work.
"""

from __future__ import annotations

import functools
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from clearcli import startup
from clearcli.errors import ClearError, InputError, NoPlanError, SceneError
from clearcli.io.frames import Frame
from clearcli.io.read import read_frame
from clearcli.perception.segment import segment
from clearcli.perception.types import Segmentation
from clearcli.settings import Settings
from clearcli.status import FrameStatus

if TYPE_CHECKING:
    # The predicates and planning stages (and the arm) are imported where they are first
    # called: `clear segment` runs neither, and their modules were 0.1-0.2 s of its cold
    # start (issue 39).
    from clearcli.planning.types import Plan
    from clearcli.predicates.state import SymbolicState
    from clearcli.robot.arm import Arm

SegmentFn = Callable[[Frame, Any], Segmentation]


class StateFn(Protocol):
    """The predicates stage: (frame, segmentation, settings, avoid_faces) -> state.
    ``avoid_faces`` (segment index -> faces a kind with faces must not use there: a
    closed loop's memory of a cup that did not seal) is part of the stage's contract, so
    that a replaced stage receives it too instead of being bypassed."""

    def __call__(
        self,
        frame: Frame,
        segmentation: Segmentation,
        settings: Settings,
        avoid_faces: Mapping[int, frozenset[str]] | None = None,
        /,
    ) -> SymbolicState: ...


PlanFn = Callable[..., "Plan"]  # a string: Plan is imported for type checking only

# Statuses of one frame (clearcli/status.py), by their short names.
OK, CLEARED, NO_TABLE = FrameStatus.OK, FrameStatus.CLEARED, FrameStatus.NO_TABLE
NO_PLAN, FAILED = FrameStatus.NO_PLAN, FrameStatus.FAILED


@dataclass(frozen=True, eq=False)
class FrameResult:
    """Everything the pipeline made of one frame (None for stages not reached)."""

    status: str
    segmentation: Segmentation | None = None
    state: SymbolicState | None = None  # the state planned on (after any adjustment)
    plan: Plan | None = None
    timings_s: Mapping[str, float] = field(default_factory=dict)
    error: str = ""
    stage: str = ""  # the stage that failed, when status is failed/no_table/no_plan
    exception: BaseException | None = None  # what the stage raised, if anything


def _default_segment() -> SegmentFn:
    return segment


def _default_state() -> StateFn:
    from clearcli.predicates.state_builder import compute_state  # noqa: PLC0415  (not for segment: see the top)

    return compute_state


def _default_plan(robot: Arm) -> PlanFn:
    from clearcli.planning.backtrack import make_plan  # noqa: PLC0415  (not for segment: see the top)

    return functools.partial(make_plan, robot=robot)


class Pipeline:
    """Runs the stages on frame after frame, reusing what can be reused.

    ``T_base_camera`` (4x4, robot base <- points' frame) is passed to the planner when
    known (a log's /tf_static); None lets the plan stage place the robot by its rules.
    ``robot``: the arm, resolved once (clearcli/robot/arm.py; from the settings when
    None, on first use). The stage functions can be replaced (tests, the simulator's
    fakes).
    """

    def __init__(
        self,
        settings: Settings,
        T_base_camera: np.ndarray | None = None,
        segment_fn: SegmentFn | None = None,
        state_fn: StateFn | None = None,
        plan_fn: PlanFn | None = None,
        robot: Arm | None = None,
    ) -> None:
        self.settings = settings
        self.T_base_camera = T_base_camera
        self._segment_fn = segment_fn
        self._state_fn = state_fn
        self._plan_fn = plan_fn
        self._robot = robot

    def with_settings(self, settings: Settings) -> Pipeline:
        """The same stages, arm and placement under other settings (a replay planning
        one frame once more with a setting relaxed)."""
        return Pipeline(
            settings,
            T_base_camera=self.T_base_camera,
            segment_fn=self._segment_fn,
            state_fn=self._state_fn,
            plan_fn=self._plan_fn,
            robot=self.robot,
        )

    @property
    def robot(self) -> Arm:
        """The arm every stage and the simulated world use, resolved once."""
        if self._robot is None:
            from clearcli.robot.arm import resolve_arm  # noqa: PLC0415  (not for segment: see the top)

            self._robot = resolve_arm(self.settings)
        return self._robot

    # --- the stages, each timed ---------------------------------------------------------

    def segment(self, frame: Frame) -> Segmentation:
        if self._segment_fn is None:
            self._segment_fn = _default_segment()
        return self._segment_fn(frame, self.settings.segment)

    def state(
        self, frame: Frame, segmentation: Segmentation, avoid_faces: Mapping[int, frozenset[str]] | None = None
    ) -> SymbolicState:
        if self._state_fn is None:
            self._state_fn = _default_state()
        # the closed loop's memory goes to whichever stage is in place (a replaced stage
        # is never bypassed); None when there is none
        return self._state_fn(frame, segmentation, self.settings, avoid_faces or None)

    def plan(self, state: SymbolicState) -> Plan:
        if self._plan_fn is None:
            self._plan_fn = _default_plan(self.robot)
        # A replay acts on the first action and plans again from the next frame: it
        # checks what [plan] replay_check says (the first action, by default).
        return self._plan_fn(
            state, self.settings, T_base_camera=self.T_base_camera, check=self.settings.plan.replay_check
        )

    def run(
        self,
        frame: Frame,
        adjust: Callable[[Segmentation, SymbolicState], SymbolicState] | None = None,
        on_segmentation: Callable[[Segmentation], None] | None = None,
        catch_internal: bool = False,
        avoid_faces: Callable[[Segmentation], Mapping[int, frozenset[str]]] | None = None,
    ) -> FrameResult:
        """All stages on one frame. ``on_segmentation`` sees the segmentation as soon as
        it exists (tracking); ``adjust`` may change the state before planning (push
        memory). Errors a user's data can cause become the result's status; other
        exceptions (bugs) raise, unless ``catch_internal`` (a replay goes on past them;
        CLEAR_DEBUG=1 still raises). ``avoid_faces`` gives, once the segmentation exists,
        the faces per segment a kind with faces must not use (a replay's memory)."""
        timings: dict[str, float] = {}
        t_start = time.perf_counter()
        catch = catch_internal and not os.environ.get("CLEAR_DEBUG")

        def done(status: str, **kw: Any) -> FrameResult:
            timings["total"] = time.perf_counter() - t_start
            return FrameResult(status=status, timings_s=dict(timings), **kw)

        def failed(stage: str, exc: BaseException, **kw: Any) -> FrameResult:
            if isinstance(exc, ClearError):
                status = NO_TABLE if isinstance(exc, SceneError) and stage == "segment" else FAILED
                if isinstance(exc, NoPlanError):
                    status = NO_PLAN
                    # the plan stage attaches what it found (unreachable, stuck objects)
                    attached = getattr(exc, "plan", None)
                    if kw.get("plan") is None and attached is not None:
                        kw["plan"] = attached
                return done(status, error=str(exc), stage=stage, exception=exc, **kw)
            message = f"internal error in {stage}: {type(exc).__name__}: {exc}"
            return done(FAILED, error=message, stage=stage, exception=exc, **kw)

        caught: tuple[type[BaseException], ...] = (Exception,) if catch else (ClearError,)

        t0 = time.perf_counter()
        try:
            segmentation = self.segment(frame)
        except caught as exc:
            timings["segment"] = time.perf_counter() - t0
            return failed("segment", exc)
        timings["segment"] = time.perf_counter() - t0
        if on_segmentation is not None:
            on_segmentation(segmentation)
        if not segmentation.objects:
            return done(CLEARED, segmentation=segmentation)

        t0 = time.perf_counter()
        try:
            state = self.state(frame, segmentation, avoid_faces(segmentation) if avoid_faces is not None else None)
        except caught as exc:
            timings["predicates"] = time.perf_counter() - t0
            return failed("predicates", exc, segmentation=segmentation)
        timings["predicates"] = time.perf_counter() - t0
        if adjust is not None:
            state = adjust(segmentation, state)

        t0 = time.perf_counter()
        try:
            plan = self.plan(state)
        except caught as exc:
            timings["plan"] = time.perf_counter() - t0
            return failed("plan", exc, segmentation=segmentation, state=state)
        timings["plan"] = time.perf_counter() - t0
        if not plan.actions:
            left = ", ".join(plan.unreachable) or ", ".join(state.names())
            return done(
                NO_PLAN,
                segmentation=segmentation,
                state=state,
                plan=plan,
                error=f"no action can be taken on the objects left ({left})",
                stage="plan",
            )
        return done(OK, segmentation=segmentation, state=state, plan=plan)


# --- one frame from a file, stage by stage: what the tasks (clearcli/tasks/) call -------
# Only this module chains the stages; a task picks how far to go and serialises.


def read(
    path: Any, topic: str | None = None, index: int = 0, settings: Settings | None = None, color: Any = None
) -> Frame:
    """Frame ``index`` of ``path``; ``settings`` ([images]) and ``color`` serve depth images."""
    startup.resume_collection()  # the libraries are loaded: the collector on for the work
    return read_frame(path, topic, index, settings.images if settings is not None else None, color)


def segmented(frame: Frame, settings: Settings) -> Segmentation:
    return segment(frame, settings.segment)


def truth_segmentation(frame: Frame, path: Any) -> Segmentation:
    """The segmentation the frame's own 'label' field gives (mOSD ground truth)."""
    if "label" not in frame.fields:
        raise InputError(f"{path}: --ground-truth needs a 'label' field, and this frame has none")
    from clearcli.predicates.synthetic import segmentation_from_labels  # noqa: PLC0415  (see the top)

    return segmentation_from_labels(frame)


def stated(
    frame: Frame,
    segmentation: Segmentation,
    settings: Settings,
    avoid_faces: Mapping[int, frozenset[str]] | None = None,
) -> SymbolicState:
    from clearcli.predicates.state_builder import compute_state  # noqa: PLC0415  (not for segment: see the top)

    return compute_state(frame, segmentation, settings, avoid_faces)


@dataclass(frozen=True, eq=False)
class Planned:
    """A frame planned: the plan (also when nothing can be done: then ``no_plan`` holds
    the error that says why), the robot's placement and where it came from."""

    plan: Plan
    T_base_camera: np.ndarray | None
    pose_source: str
    no_plan: NoPlanError | None = None


def planned(
    state: SymbolicState, settings: Settings, robot: Arm, camera_pose: str | None, check: str | None
) -> Planned:
    """Place ``robot`` (``camera_pose`` as given on the command line, else [robot]'s
    rules), then plan with every action IK-checked against it (``check``: None for
    [plan] check)."""
    from clearcli.planning.backtrack import make_plan  # noqa: PLC0415  (not for segment: see the top)

    T_base_camera, pose_source = robot.place(state, camera_pose)
    try:
        plan = make_plan(state, settings, T_base_camera, check=check, robot=robot)
    except NoPlanError as err:
        attached = getattr(err, "plan", None)  # the plan stage attaches what it found
        if attached is None:
            raise
        return Planned(attached, T_base_camera, pose_source, err)
    return Planned(plan, T_base_camera, pose_source)
