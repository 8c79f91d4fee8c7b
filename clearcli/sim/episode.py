"""Self-made clearing sessions: plan, act with the world's own imperfections, look again.

An `Episode` renders a `Scene` with the virtual Kinect, runs the replay `Session` on the
frame (segment, predicates, plan, with tracking and push memory, exactly as `clear
replay` would), and carries out the plan's first action on the scene, not on the
planner's model of it:

* a push moves what the fingers meet as they advance from the push's start pose (for a
  segment that is two objects, the nearer one, or both when the fingers straddle their
  seam), along the push direction in small steps, heading and yaw drifting with seeded
  noise; an object it runs into is shoved along with it, and the push stops early when
  that one is blocked in turn or the pushed object would leave the table (then it
  falls off and is gone);
* a grasp is what its kind's `simulate` makes of it (clearcli/predicates/grasps), on
  the world's rules (`clearcli.sim.physics`): the pinch takes the object between the
  fingers away, unless another object lies under or between the open fingers by more
  than ``GRASP_TOLERANCE_M`` (nothing is taken), or the object is wider than the gripper
  was opened; a grasp across a width close to the gripper's opening slips now and then
  (the object stays, slightly moved); a rim grasp and a slide follow their own rules.

What is left at the end is judged by the world too (`clearcli.sim.reach`).

Then the next frame is rendered, until the table is clear, no plan exists, or the
action budget runs out. The frames go to a ROS 2 PointCloud2 MCAP (with the labels the
camera knows, and the robot's place on /tf_static), which `clear replay` reads back.
"""

from __future__ import annotations

import dataclasses
import math
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np

from clearcli.geometry.gripper import push_contact_halves, push_tool_model
from clearcli.predicates.grasps import kind as grasp_kind
from clearcli.settings.profiles import tools_of
from clearcli.settings.sim import WorldParams
from clearcli.sim import camera, physics
from clearcli.sim.physics import push_contacts, truly_ungraspable_by, world_push
from clearcli.sim.reach import T_base_table_of, WorldReach
from clearcli.sim.scene import Scene, without_object
from clearcli.sim.truth import world_object_of

if TYPE_CHECKING:
    from clearcli.io.frames import Frame
    from clearcli.replay.report import FrameReport
    from clearcli.replay.session import Session

# An object whose centre ends farther than this from where it started was moved by the
# robot (a slipped grasp displaces it by ~4 mm, so this only counts pushes and shoves).
MOVED_M = 0.01


@dataclass(frozen=True)
class StepRecord:
    """One frame of the episode and what the world did with its first action."""

    frame_index: int
    status: str
    n_objects: int  # objects in the world when the frame was taken
    action: str = ""  # "(push 3 dir1)" with the world's object id
    object_id: int | None = None
    outcome: str = ""  # "removed", "slipped", "pushed 0.083 m", "shoved 2", "fell off", ...
    undoes_push: bool = False
    unreachable: tuple[int, ...] = ()  # world ids the planner cannot clear: out of reach or ungraspable
    ungraspable: tuple[int, ...] = ()
    stuck: tuple[int, ...] = ()  # world ids the planner found blocked by objects it cannot move
    seen: tuple[int, ...] = ()  # world ids that are the bulk of some segment (the rest: merged or missed)
    # (world id, why) of every object the frame's plan left: the plan's reason and its
    # detail (per kind tried, why it failed)
    left_why: tuple[tuple[int, str], ...] = ()


@dataclass(frozen=True)
class EpisodeResult:
    scene: str
    seed: int
    n_objects: int
    steps: tuple[StepRecord, ...]
    end: str  # "cleared" | "no_plan" | "budget" | "failed"
    remaining: tuple[int, ...]  # world ids still on the table
    unreachable: tuple[int, ...]  # of those, the ones the last plan said it cannot reach or grasp
    actions_per_object: dict[int, int] = field(default_factory=dict)
    stuck: tuple[int, ...] = ()  # of those, the ones blocked by objects it cannot move
    reason: str = ""  # the last frame's error, when the episode ended without clearing
    unseen: tuple[int, ...] = ()  # of those, the ones no segment stood for (merged or missed)
    # Of those, the ones the planner called too wide or narrow for the gripper (part of
    # ``unreachable``), and the ones the world's gripper truly cannot hold.
    claimed_ungraspable: tuple[int, ...] = ()
    truly_ungraspable: tuple[int, ...] = ()
    # Of those, the ones the robot moved (pushed, or shoved with another): when such an
    # object ends out of reach, the robot put it there.
    moved: tuple[int, ...] = ()
    # Of those, the ones the world's own arm cannot reach on their true pose
    # (`clearcli.sim.reach`), whatever the planner said of them.
    world_unreachable: tuple[int, ...] = ()
    # Per object left, why: the last plan's reason (``planner_why``: "ungraspable: ...
    # suction grasp: too heavy for the cup ...") and the world's verdict (``world_why``:
    # "" when the world's robot could take it where it stands).
    planner_why: dict[int, str] = field(default_factory=dict)
    world_why: dict[int, str] = field(default_factory=dict)

    @property
    def actions(self) -> int:
        return sum(1 for s in self.steps if s.action)

    @property
    def back_and_forth(self) -> int:
        return sum(1 for s in self.steps if s.undoes_push)

    @property
    def cleared_reachable(self) -> bool:
        """Every object left is one the planner showed it cannot reach or grasp (or none
        is left)."""
        return self.end != "budget" and set(self.remaining) <= set(self.unreachable)

    @property
    def cleared_truly(self) -> bool:
        """Judged by the world alone: every object left is one the robot truly cannot
        take, because its gripper cannot hold it (true width beyond the opening or under
        the closing width) or its arm has no motion to a top-down grasp of it where it
        truly stands (`clearcli.sim.reach`), unless the robot pushed it there. What the
        planner called unreachable or too wide excuses nothing: a planner cannot look
        better by giving up. ``cleared_reachable`` is the older, planner-trusting figure."""
        excused = set(self.truly_ungraspable) | (set(self.world_unreachable) - set(self.moved))
        return self.end != "budget" and set(self.remaining) <= excused

    @property
    def false_ungraspable(self) -> tuple[int, ...]:
        """Objects left that the planner called too wide or narrow but the gripper fits."""
        return tuple(sorted(set(self.claimed_ungraspable) - set(self.truly_ungraspable)))

    @property
    def cleared_unblocked(self) -> bool:
        """Every object left cannot be reached or grasped, or is blocked by such objects."""
        return self.end != "budget" and set(self.remaining) <= set(self.unreachable) | set(self.stuck)


# --- the world's actions ------------------------------------------------------------------


class Episode:
    """Iterate it for the frames (each rendered after the previous frame's action); then
    read ``result``. ``session`` is the replay session that plans (its options decide
    push memory); ``render_seed`` seeds the camera noise, ``seed`` the world's."""

    def __init__(
        self,
        scene: Scene,
        session: Session,
        seed: int = 0,
        max_actions: int = 40,
        params: WorldParams | None = None,
        start_s: float = 0.0,
    ) -> None:
        self.scene = scene
        self.session = session
        self.seed = seed
        self.max_actions = max_actions
        # None: the session's settings' [world] (its one home)
        self.params = params if params is not None else session.pipeline.settings.world
        self.start_s = start_s
        self.rng = np.random.default_rng(seed)
        self.steps: list[StepRecord] = []
        self.result: EpisodeResult | None = None
        self.reports: list[dict[str, Any]] = []  # the JSON of every frame, for callers

    def render(self, index: int) -> Frame:
        # the camera and its noise as the settings say ([camera], [depth_noise])
        settings = self.session.pipeline.settings
        frame = camera.render(
            self.scene,
            seed=self.seed * 1000 + index,
            stamp_s=self.start_s + index * self.params.frame_interval_s,
            noise=settings.depth_noise,
            camera=settings.camera,
        )
        return dataclasses.replace(frame, source=f"{self.scene.name}#{index}")

    def robot_placement(self, frame: Frame) -> np.ndarray:
        """T_base_camera fixed for the whole episode (the robot does not move), by the
        plan stage's rule on the first frame, unless the settings give one."""
        pipeline = self.session.pipeline
        if pipeline.T_base_camera is not None:
            return np.asarray(pipeline.T_base_camera)
        robot = pipeline.robot
        segmentation = pipeline.segment(frame)
        state = pipeline.state(frame, segmentation) if segmentation.objects else None
        if state is None:
            T, _ = robot.place(None) if robot.settings.camera_pose else (np.eye(4), "")
        else:
            T, _ = robot.place(state)
        pipeline.T_base_camera = T
        return T

    def __iter__(self) -> Iterator[Frame]:
        ids_at_start = tuple(o.object_id for o in self.scene.objects)
        start_xy = {o.object_id: (o.x_m, o.y_m) for o in self.scene.objects}
        actions = 0
        end = "budget"
        last_unreachable: tuple[int, ...] = ()
        last_ungraspable: tuple[int, ...] = ()
        last_stuck: tuple[int, ...] = ()
        last_seen: tuple[int, ...] = ()
        last_left_why: tuple[tuple[int, str], ...] = ()
        reason = ""
        per_object: Counter[int] = Counter()
        index = 0
        while True:
            frame = self.render(index)
            if index == 0:
                self.robot_placement(frame)
            yield frame
            report = self.session.step(frame, index, time_s=index * self.params.frame_interval_s)
            self.reports.append(report.to_json())
            record, unreachable = self._act(frame, report, index)
            last_unreachable = unreachable
            last_ungraspable = record.ungraspable
            last_stuck = record.stuck
            last_seen = record.seen
            last_left_why = record.left_why
            reason = report.result.error
            self.steps.append(record)
            if record.object_id is not None and record.action:
                per_object[record.object_id] += 1
            if report.status == "cleared":
                end = "cleared"
                break
            if report.status in ("no_plan", "no_table"):
                end = "no_plan"
                break
            if report.status == "failed":
                end = "failed"
                break
            if record.action:
                actions += 1
            if actions >= self.max_actions:
                # the last frame shows where the budget left the table (the last action
                # may have cleared it)
                end = "budget" if self.scene.objects else "cleared"
                index += 1
                yield self.render(index)
                break
            index += 1
        remaining = tuple(o.object_id for o in self.scene.objects)
        gripper = self.session.pipeline.settings.gripper
        # the world's verdict, with the grasp kinds the planner was given: a bowl is no
        # excuse when the rim grasp was allowed and the world's fingers close on its wall
        kinds = tuple(k.strip() for k in str(self.session.pipeline.settings.plan.grasps).split(","))
        # the robot's own cup tool, when it has one (its body must clear the table on a side)
        settings = self.session.pipeline.settings
        cup = settings.suction if "cup" in tools_of(settings.robot.name) else None
        too_wide_or_narrow = tuple(
            sorted(o.object_id for o in self.scene.objects if truly_ungraspable_by(o, gripper, kinds, cup))
        )
        world_why = self._world_verdicts(too_wide_or_narrow)
        self.result = EpisodeResult(
            scene=self.scene.name.split(".")[0],
            seed=self.seed,
            n_objects=len(ids_at_start),
            steps=tuple(self.steps),
            end=end,
            remaining=remaining,
            unreachable=tuple(sorted(set(last_unreachable) & set(remaining))),
            actions_per_object=dict(per_object),
            stuck=tuple(sorted(set(last_stuck) & set(remaining))),
            reason=reason if end != "cleared" else "",
            unseen=tuple(sorted(set(remaining) - set(last_seen))),
            claimed_ungraspable=tuple(sorted(set(last_ungraspable) & set(remaining))),
            truly_ungraspable=too_wide_or_narrow,
            moved=tuple(
                sorted(
                    o.object_id
                    for o in self.scene.objects
                    if math.dist((o.x_m, o.y_m), start_xy[o.object_id]) > MOVED_M
                )
            ),
            world_unreachable=tuple(sorted(k for k, why in world_why.items() if why and k not in too_wide_or_narrow)),
            planner_why={k: why for k, why in last_left_why if k in remaining},
            world_why=world_why,
        )

    def _world_verdicts(self, ungraspable: tuple[int, ...]) -> dict[int, str]:
        """Per object left, the world's verdict: why its robot cannot take it ("" when it
        can): no grasp kind the robot was given holds it (``ungraspable``), or its own arm
        reaches no pose to take it (`WorldReach.why_not`; a kind other than the pinch
        taking what the fingers cannot close across, the arm's pose over it)."""
        out = {k: "no grasp kind the robot has takes it (the world's rules)" for k in ungraspable}
        left = [o for o in self.scene.objects if o.object_id not in ungraspable]
        T_base_camera = self.session.pipeline.T_base_camera
        if not left or T_base_camera is None:
            return out
        settings = self.session.pipeline.settings
        reach = WorldReach(
            T_base_table_of(T_base_camera, self.scene),
            settings.gripper,
            settings.push,
            params=settings.world_reach,
            table=self.scene.table,
            robot=self.session.pipeline.robot,
        )
        # ``left`` holds only what some kind the robot has takes: the fingers not closing
        # across it is then no excuse (the cup's or the slide's, not the pinch's, object)
        out.update((o.object_id, reach.why_not(o, other_kind=True)) for o in left)
        return out

    def _push_contacts(
        self, report: FrameReport, push: Any, direction_table: np.ndarray, T_table_camera: np.ndarray
    ) -> list[int] | None:
        """The objects the fingers meet (`push_contacts`), None when the push has no pose."""
        T_camera_start = _chosen_pose_camera(report, push.candidates)
        if T_camera_start is None:
            return None
        T_table_start = T_table_camera @ T_camera_start
        d = np.asarray(direction_table[:2], dtype=float)
        d /= max(float(np.linalg.norm(d)), 1e-12)
        # what the robot pushes with: its fingers, or a tool with a cup alone its cup
        settings = self.session.pipeline.settings
        pusher = push_tool_model(settings.gripper, settings.suction, tools_of(settings.robot.name))
        front, half_width = push_contact_halves(pusher, T_table_start[:2, 0], d)
        start = T_table_start[:2, 3] + front * d
        reach = float(push.push_length_m) + 0.1
        return push_contacts(self.scene, start, d, half_width, reach)

    def _act(self, frame: Frame, report: FrameReport, index: int) -> tuple[StepRecord, tuple[int, ...]]:
        result = report.result
        n = len(self.scene.objects)
        unreachable: tuple[int, ...] = ()
        ungraspable: tuple[int, ...] = ()
        stuck: tuple[int, ...] = ()
        seg, state, plan = result.segmentation, result.state, result.plan
        seen: tuple[int, ...] = ()
        left_why: list[tuple[int, str]] = []
        if seg is not None:
            seen = tuple(
                sorted({w for k in range(len(seg.objects)) if (w := world_object_of(frame, seg, k)) is not None})
            )
        if seg is not None and state is not None and plan is not None:

            def world_ids(names: Any) -> tuple[int, ...]:
                out = []
                for name in names:
                    try:
                        wid = world_object_of(frame, seg, state.by_name(name).segment_index)
                    except KeyError:
                        continue
                    if wid is not None:
                        out.append(wid)
                return tuple(sorted(set(out)))

            for left in getattr(plan, "left", ()):
                ids = world_ids((left.name,))
                if ids:
                    left_why.append((ids[0], f"{left.reason}: {left.detail}"))
            ungraspable = world_ids(getattr(plan, "ungraspable", ()))
            unreachable = tuple(sorted(set(world_ids(plan.unreachable)) | set(ungraspable)))
            stuck = world_ids(getattr(plan, "stuck", ()))
        first = report.first_action()
        if first is None or seg is None or state is None:
            record = StepRecord(
                index,
                report.status,
                n,
                unreachable=unreachable,
                ungraspable=ungraspable,
                stuck=stuck,
                seen=seen,
                left_why=tuple(left_why),
            )
            return record, unreachable
        model = state.by_name(first.obj)
        wid = world_object_of(frame, seg, model.segment_index)
        k = next((i for i, o in enumerate(self.scene.objects) if o.object_id == wid), None)
        label = f"({first.kind} {wid}{' ' + first.direction if first.direction else ''})"
        if k is None:
            outcome = "missed: no object there"
        elif first.kind == "grasp":
            # the kind says what the world does with it, on the world's own rules
            # (clearcli/predicates/grasps: each kind's simulate)
            hand = _Hand(self, report, model, k)
            outcome = grasp_kind(first.grasp_kind).simulate(hand)
            self.scene, wid = hand.scene, hand.object_id
            label = f"({first.pddl_name} {wid})"
        else:
            push = model.pushes[first.direction or ""]
            T_table_camera = np.linalg.inv(self.scene.T_camera_table)
            direction = T_table_camera[:3, :3] @ np.asarray(push.unit_vector, dtype=float)
            # The world moves what the gripper's fingers meet, not what the planner meant:
            # for a segment that is two objects merged, the one nearer the fingers (or
            # both, when the fingers straddle them).
            contacts = self._push_contacts(report, push, direction, T_table_camera)
            if contacts is None:
                contacts = [k]
            if not contacts:
                outcome = "missed: the fingers met nothing"
            else:
                k = contacts[0]
                wid = self.scene.objects[k].object_id
                label = f"(push {wid} {first.direction})"
                straddled = [self.scene.objects[i].object_id for i in contacts[1:]]
                self.scene, outcome = world_push(
                    self.scene, contacts, direction, float(push.push_length_m), self.rng, self.params
                )
                if straddled:
                    outcome += ", with " + ", ".join(map(str, straddled)) + " under the fingers too"
        record = StepRecord(
            frame_index=index,
            status=report.status,
            n_objects=n,
            action=label,
            object_id=wid,
            outcome=outcome,
            undoes_push=report.undoes_push,
            unreachable=unreachable,
            ungraspable=ungraspable,
            stuck=stuck,
            seen=seen,
            left_why=tuple(left_why),
        )
        return record, unreachable


class _Hand:
    """What the world lends a grasp kind's `simulate` (clearcli/predicates/grasps/base.py
    `SimWorld`): the scene as it truly is, the world's rules (`clearcli.sim.physics`), the
    first action's object and how the arm went there."""

    def __init__(self, episode: Episode, report: FrameReport, model: Any, k: int) -> None:
        settings = episode.session.pipeline.settings
        self.scene = episode.scene
        self.k = k
        self.object_id = episode.scene.objects[k].object_id
        self.model = model
        self.settings = settings
        self.gripper = settings.gripper
        self.rng = episode.rng
        self.params = episode.params
        self.rules: ModuleType = physics
        self.T_table_camera = np.linalg.inv(episode.scene.T_camera_table)
        self._report = report

    def aim(self, k: int) -> None:
        self.k = k
        self.object_id = self.scene.objects[k].object_id

    def take(self) -> None:
        self.scene = without_object(self.scene, self.k)

    def chosen_pose(self, candidates: Any, pose: int = 1, candidate: int = 0) -> np.ndarray | None:
        return _chosen_pose_camera(self._report, candidates, pose=pose, candidate=candidate)

    def chosen_candidate(self) -> int | None:
        plan = self._report.result.plan
        return plan.first.candidate if plan is not None and plan.first is not None else None


def _chosen_pose_camera(report: FrameReport, candidates: Any, pose: int = 1, candidate: int = 0) -> np.ndarray | None:
    """A pose (camera frame) of the first action's sequence, the ``pose``-th (the grasp
    or push start by default; -2 a slide's pinch at the edge): of the candidate the IK
    check chose, else of the model's ``candidate``-th of ``candidates``; None without
    either."""
    plan = report.result.plan
    checked = plan.first if plan is not None else None
    if (
        checked is not None
        and plan is not None
        and plan.T_base_camera is not None
        and -len(checked.T_base_gripper) <= pose < len(checked.T_base_gripper)
    ):
        return np.linalg.inv(np.asarray(plan.T_base_camera, dtype=float)) @ np.asarray(checked.T_base_gripper[pose])
    if not candidates:
        return None
    return np.asarray(candidates[min(candidate, len(candidates) - 1)][pose], dtype=float)
