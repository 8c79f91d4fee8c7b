"""The Python API of `clear`: what the command line does, from Python.

    from clearcli import api

    settings = api.Settings.default().with_(**{"segment.voxel_m": 0.005})
    seg = api.segment("fixtures/clutter10.pcd", settings=settings)
    seg.labels            # (N,) label per point: 0 none, 1 table, 10 (k + 1) object k
    seg.objects[0].indices  # the points of object 0: seg.points[seg.objects[0].indices]
    plan = api.plan("fixtures/clutter10.pcd", settings=settings)
    plan.status, plan.steps[0].T_base_gripper  # "complete", (P, 4, 4)
    plan.to_json()        # the document `clear plan --json` prints for the same frame

Every function calls the task the command and the batch call (clearcli/tasks/), so a
result's ``to_json()`` is the command's ``--json`` document for the same input and
settings; its other attributes are that document's content, typed, and the arrays a
Python user wants (NumPy, read-only). Bad input raises the `ClearError` subclass the
command maps to its exit code, with the command's message (`clearcli.errors`); a setting
of the wrong type or out of its range raises `SettingsError` when `Settings.with_`
builds it, naming the key and its range, before any frame is read.

The API is the names in ``__all__``; everything else here is private by name, and the
rest of the package is not part of it. tests/api/surface.json records the surface
(names and signatures) per package version: a change without a new version fails
tests/api/test_surface.py.

Importing this module is cheap (the standard library and clearcli.errors): NumPy, the
settings tree and the stages load on first use.
"""

from __future__ import annotations

import json
import os
import queue
import threading
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from clearcli.errors import (
    ClearError,
    InputError,
    NoPlanError,
    OutputError,
    PartialLogError,
    PlannerError,
    SceneError,
    SettingsError,
)

if TYPE_CHECKING:
    import numpy as np

    from clearcli.settings.tree import Settings as _Tree
    from clearcli.tasks.base import Outcome as _Outcome

__all__ = [
    "ClearError",
    "Document",
    "Evaluation",
    "Frame",
    "Info",
    "InputError",
    "ModelledObject",
    "NoPlanError",
    "OutputError",
    "PartialLogError",
    "Plan",
    "PlanStep",
    "PlannerError",
    "Predicates",
    "Replay",
    "ReplayFrame",
    "ReplayObject",
    "SceneError",
    "SegmentedObject",
    "Segmentation",
    "Settings",
    "SettingsError",
    "evaluate",
    "info",
    "plan",
    "predicates",
    "read_frame",
    "replay",
    "segment",
]

PathLike = str | os.PathLike[str]


# --- settings ----------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Settings:
    """The settings tree (`clear settings` prints it): defaults, a robot profile, a TOML
    file, and values set by key. Immutable: `with_` gives a new one. Every value is
    checked as it is set (type and range, as `--set` checks it)."""

    _tree: Any = field(repr=False)

    @classmethod
    def default(cls, robot: str | None = None) -> Settings:
        """The defaults; with ``robot``, that profile's [robot], [gripper], [suction] and
        [plan] grasps (as `--robot NAME`; `clear robots` lists them)."""
        tree = _settings_module()
        base = tree.Settings()
        return cls(base if robot is None else tree.with_profile(base, robot))

    @classmethod
    def from_file(cls, path: PathLike) -> Settings:
        """The defaults, then a TOML file's values (as `--settings FILE`)."""
        return cls(_settings_module().load_settings(Path(path)))

    def with_(self, **values: Any) -> Settings:
        """These settings with values replaced: ``"section.key"`` names one key
        (``with_(**{"segment.voxel_m": 0.005})``), a section's name takes a mapping
        (``with_(segment={"voxel_m": 0.005})``). ``robot.name`` first resets the robot's
        sections to that profile, as `--set robot.name=NAME` does. SettingsError for an
        unknown key, a wrong type or a value out of range, naming the key and its range."""
        data: dict[str, dict[str, Any]] = {}
        for name, value in values.items():
            section, dot, key = name.partition(".")
            if dot:
                data.setdefault(section, {})[key] = value
            elif isinstance(value, Mapping):
                data.setdefault(section, {}).update(value)
            else:
                raise SettingsError(
                    f"settings: {name} = {value!r}: give SECTION.KEY (e.g. segment.voxel_m) "
                    "or a section with a mapping of its keys"
                )
        return Settings(_settings_module().settings_from_dict(data, base=self._tree))

    def get(self, key: str) -> Any:
        """The value of ``"section.key"``."""
        section, _, name = key.partition(".")
        try:
            return getattr(getattr(self._tree, section), name)
        except AttributeError:
            raise SettingsError(f"settings: no key {key!r}; `clear settings` lists them") from None

    def to_toml(self) -> str:
        """The whole tree as TOML that `--settings FILE` and `Settings.from_file` read back."""
        return str(_settings_module().settings_to_toml(self._tree))


def _settings_module() -> Any:
    from clearcli.settings import tree  # noqa: PLC0415  (~50 ms: not at import)

    return tree


def _checked(settings: Settings | None, intrinsics: str | None = None, depth_scale_m: float | None = None) -> _Tree:
    """The settings tree a task runs with, checked as the commands check it before any
    frame: the grasp kinds against the robot's tool, a user's URDF, the depth-image
    options (--intrinsics, --depth-scale) applied."""
    tree = _settings_module()
    resolved = (settings or Settings.default())._tree
    tree.check_tools(resolved)
    if resolved.robot.urdf:
        from clearcli.tasks.robots import check_robot  # noqa: PLC0415  (a URDF only)

        check_robot(resolved.robot)
    if intrinsics is not None and intrinsics.strip() and Path(intrinsics).exists():
        intrinsics = str(Path(intrinsics).resolve())  # as the commands record it
    if intrinsics:
        from clearcli.tasks.sources import check_intrinsics  # noqa: PLC0415

        check_intrinsics(intrinsics)
    return tree.override(resolved, "images", intrinsics=intrinsics, depth_scale_m=depth_scale_m)


# --- documents ---------------------------------------------------------------------------


def _document(schema: str, version: int, payload: Mapping[str, Any], settings: Any, command: str) -> str:
    """The command's --json document as its text (the envelope with its provenance)."""
    from clearcli.provenance import dumps, envelope, stamp  # noqa: PLC0415  (the settings tree)

    return dumps(envelope(schema, version, payload, stamp(settings, command)))


def _array(value: Any, dtype: str = "float64") -> np.ndarray:
    import numpy as np  # noqa: PLC0415  (~60 ms: not at import)

    out = np.array(value, dtype=dtype)
    out.setflags(write=False)
    return out


def _frozen(array: Any) -> np.ndarray:
    import numpy as np  # noqa: PLC0415

    out = np.array(array)  # a copy: the result owns it
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class Document:
    _text: str = field(repr=False)

    def to_json(self) -> dict[str, Any]:
        """The document the command prints with --json (a new dict on every call)."""
        result: dict[str, Any] = json.loads(self._text)
        return result


def _source(path: PathLike) -> str:
    return str(Path(path))  # as the commands name it (a Path from the argument, as text)


def _task_source(path: PathLike, frame: int, topic: str | None, color: PathLike | None) -> Any:
    if isinstance(frame, bool) or not isinstance(frame, int) or frame < 0:
        raise InputError(f"frame = {frame!r}: must be an integer >= 0 (the frame's index on its topic, from 0)")
    from clearcli.tasks.base import Source  # noqa: PLC0415

    return Source(_source(path), frame, topic, color=str(color) if color is not None else None)


# --- a frame -----------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Frame:
    """One point cloud as `clear` reads it, in the sensor frame (metres; an optical
    frame: z forward, y down). ``points`` (N, 3) with NaN rows for pixels that saw
    nothing (kept, so an organized frame keeps its ``shape``); ``colors`` (N, 3) uint8
    or None; ``fields`` any other per-point field (e.g. ``label``)."""

    source: str
    points: np.ndarray
    colors: np.ndarray | None
    shape: tuple[int, int] | None
    fields: Mapping[str, np.ndarray]
    stamp_s: float
    frame_id: str


def read_frame(
    source: PathLike,
    *,
    frame: int = 0,
    topic: str | None = None,
    color: PathLike | None = None,
    intrinsics: str | None = None,
    depth_scale_m: float | None = None,
    settings: Settings | None = None,
) -> Frame:
    """Frame ``frame`` of ``source``: a PCD, an MCAP log, a ROS 1 bag, a rosbag2 folder
    or a depth image (.png, .tif, .npy; ``intrinsics`` a file or "fx fy cx cy", ``color``
    its colour image, ``depth_scale_m`` metres per unit), as the commands read it."""
    resolved = _checked(settings, intrinsics, depth_scale_m)
    src = _task_source(source, frame, topic, color)
    from clearcli import pipeline  # noqa: PLC0415  (the tasks' reader; NumPy and the formats)

    got = pipeline.read(src.path, src.topic, src.index, resolved, src.color)
    return Frame(
        source=got.source,
        points=_frozen(got.points),
        colors=None if got.colors is None else _frozen(got.colors),
        shape=got.shape,
        fields={k: _frozen(v) for k, v in got.fields.items()},
        stamp_s=float(got.stamp_s),
        frame_id=got.frame_id,
    )


@dataclass(frozen=True, eq=False)
class Info(Document):
    """What a file holds (`clear info FILE --json`): its ``format`` (pcd, mcap, bag,
    rosbag2, image), points, fields, topics; ``exit_code`` 9 when a log breaks after
    some frames, else 0."""

    format: str
    exit_code: int


def info(
    source: PathLike,
    *,
    frame: int = 0,
    topic: str | None = None,
    color: PathLike | None = None,
    intrinsics: str | None = None,
    depth_scale_m: float | None = None,
    settings: Settings | None = None,
) -> Info:
    """`clear info`: what ``source`` holds, without segmenting it."""
    resolved = _checked(settings, intrinsics, depth_scale_m)
    src = _task_source(source, frame, topic, color)
    from clearcli.tasks import info as task  # noqa: PLC0415

    outcome = task.run(task.Request(settings=resolved), src)
    text = _document(outcome.schema, outcome.version, outcome.payload, resolved, "info")
    return Info(text, format=str(outcome.payload["format"]), exit_code=outcome.exit_code)


# --- segment -----------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class SegmentedObject:
    """One object on the table: its points are ``Segmentation.points[indices]``; its
    box and axes in the sensor frame (metres), as in the document."""

    id: int
    label: int
    indices: np.ndarray  # (M,) int64 into the frame's points
    centroid_m: np.ndarray  # (3,)
    obb_center_m: np.ndarray  # (3,)
    obb_axes: np.ndarray  # (3, 3) rows; the third the table's normal
    obb_extents_m: np.ndarray  # (3,) full side lengths along the axes
    principal_axes: np.ndarray  # (3, 3) rows, largest variance first


@dataclass(frozen=True, eq=False)
class Segmentation(Document):
    """`clear segment --json`, plus the frame's ``points`` (N, 3), the ``labels`` (N,)
    (0 none, 1 table, 10 (k + 1) object k, as `clear segment -o` writes them) and the
    table's plane n . p + d = 0 (``table_normal``, ``table_offset_m``)."""

    source: str
    points: np.ndarray
    labels: np.ndarray
    table_indices: np.ndarray
    table_normal: np.ndarray
    table_offset_m: float
    objects: tuple[SegmentedObject, ...]


def segment(
    source: PathLike,
    *,
    frame: int = 0,
    topic: str | None = None,
    color: PathLike | None = None,
    intrinsics: str | None = None,
    depth_scale_m: float | None = None,
    settings: Settings | None = None,
) -> Segmentation:
    """`clear segment`: the table and the objects on it."""
    resolved = _checked(settings, intrinsics, depth_scale_m)
    src = _task_source(source, frame, topic, color)
    from clearcli.tasks import segment as task  # noqa: PLC0415  (the stages: ~1 s cold)

    outcome = task.run(task.Request(resolved, keep=True), src)
    return _segmentation(outcome, _document(outcome.schema, outcome.version, outcome.payload, resolved, "segment"))


def _segmentation(outcome: _Outcome, text: str) -> Segmentation:
    doc, frame, seg = outcome.payload, outcome.kept["frame"], outcome.kept["segmentation"]
    objects = tuple(
        SegmentedObject(
            id=int(o["id"]),
            label=int(o["label"]),
            indices=_frozen(seg.objects[k].indices),
            centroid_m=_array(o["centroid"]),
            obb_center_m=_array(o["obb"]["center"]),
            obb_axes=_array(o["obb"]["axes"]),
            obb_extents_m=_array(o["obb"]["extents"]),
            principal_axes=_array(o["principal_axes"]),
        )
        for k, o in enumerate(doc["objects"])
    )
    return Segmentation(
        text,
        source=str(doc["source"]),
        points=_frozen(frame.points),
        labels=_frozen(seg.labels()),
        table_indices=_frozen(seg.table_indices),
        table_normal=_array(doc["table"]["normal"]),
        table_offset_m=float(doc["table"]["offset"]),
        objects=objects,
    )


# --- predicates --------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class ModelledObject:
    """One object as the predicates model it (sensor frame, metres): ``grasp_poses``
    (K, 4, 4) T_camera_gripper, the pinch's poses first; ``indices`` its points."""

    name: str
    segment_index: int
    indices: np.ndarray
    centroid_m: np.ndarray
    extents_m: np.ndarray
    principal_axes: np.ndarray
    height_m: float
    grasp_width_m: float
    grasp_poses: np.ndarray


@dataclass(frozen=True, eq=False)
class Predicates(Document):
    """`clear predicates --json`: the objects modelled, the facts (PDDL atoms, sorted),
    plus the frame's ``labels`` (N,) of the segmentation the objects came from."""

    source: str
    labels: np.ndarray
    objects: tuple[ModelledObject, ...]
    facts: tuple[str, ...]


def predicates(
    source: PathLike,
    *,
    frame: int = 0,
    topic: str | None = None,
    color: PathLike | None = None,
    intrinsics: str | None = None,
    depth_scale_m: float | None = None,
    ground_truth: bool = False,
    settings: Settings | None = None,
) -> Predicates:
    """`clear predicates`: object models, grasp and push poses, the symbolic facts;
    ``ground_truth``: the frame's own ``label`` field instead of segmenting it."""
    resolved = _checked(settings, intrinsics, depth_scale_m)
    src = _task_source(source, frame, topic, color)
    from clearcli.tasks import predicates as task  # noqa: PLC0415  (the stages)

    outcome = task.run(task.Request(resolved, ground_truth=bool(ground_truth), keep=True), src)
    doc, seg = outcome.payload, outcome.kept["segmentation"]
    text = _document(outcome.schema, outcome.version, doc, resolved, "predicates")
    objects = tuple(
        ModelledObject(
            name=str(o["name"]),
            segment_index=int(o["segment_index"]),
            indices=_frozen(seg.objects[int(o["segment_index"])].indices),
            centroid_m=_array(o["centroid"]),
            extents_m=_array(o["extents_m"]),
            principal_axes=_array(o["principal_axes"]),
            height_m=float(o["height_m"]),
            grasp_width_m=float(o["grasp_width_m"]),
            grasp_poses=_array(o["grasp_poses"]).reshape(-1, 4, 4),
        )
        for o in doc["objects"]
    )
    return Predicates(
        text,
        source=str(doc["source"]),
        labels=_frozen(seg.labels()),
        objects=objects,
        facts=tuple(doc["facts"]),
    )


# --- plan --------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class PlanStep:
    """One action of a plan: ``kind`` grasp or push, ``grasp_kind`` (pinch, rim, slide,
    suction; None for a push), the object, a push's direction; when IK-checked, the
    joint vectors (P, n) in the order of `Plan.joint_names` and the gripper poses they
    were solved for, (P, 4, 4) T_base_gripper."""

    action: str
    kind: str
    grasp_kind: str | None
    object: str
    direction: str | None
    checked: bool
    joints_rad: np.ndarray | None
    T_base_gripper: np.ndarray | None


@dataclass(frozen=True, eq=False)
class Plan(Document):
    """`clear plan --json`: ``status`` complete, partial or no_plan, and ``exit_code``
    the command's (0, 10, 5); the steps; ``T_base_camera`` (4, 4), the robot's
    placement; ``left`` the objects not removed; ``labels`` (N,) of the segmentation."""

    source: str
    status: str
    exit_code: int
    steps: tuple[PlanStep, ...]
    left: tuple[str, ...]
    joint_names: tuple[str, ...]
    T_base_camera: np.ndarray
    labels: np.ndarray


def plan(
    source: PathLike,
    *,
    frame: int = 0,
    topic: str | None = None,
    color: PathLike | None = None,
    intrinsics: str | None = None,
    depth_scale_m: float | None = None,
    camera_pose: str | None = None,
    first_only: bool = False,
    settings: Settings | None = None,
) -> Plan:
    """`clear plan`: segment, predicates and a plan, every action IK-checked (only the
    first with ``first_only``); ``camera_pose`` as --camera-pose. A plan that removes
    nothing is a result (status no_plan, exit_code 5, the document's no_plan_reason),
    as the command prints its document then."""
    resolved = _checked(settings, intrinsics, depth_scale_m)
    src = _task_source(source, frame, topic, color)
    from clearcli.tasks import plan as task  # noqa: PLC0415  (the stages and the planner)

    request = task.Request(resolved, camera_pose=camera_pose, first_only=bool(first_only), keep=True)
    outcome = task.run(request, src)
    doc = outcome.payload
    text = _document(outcome.schema, outcome.version, doc, resolved, "plan")
    steps = tuple(
        PlanStep(
            action=str(action),
            kind=str(s["kind"]),
            grasp_kind=s.get("grasp_kind"),
            object=str(s["object"]),
            direction=s.get("direction"),
            checked=bool(s["checked"]),
            joints_rad=None if s.get("joints_rad") is None else _array(s["joints_rad"]),
            T_base_gripper=None if s.get("T_base_gripper") is None else _array(s["T_base_gripper"]),
        )
        for action, s in zip(doc["actions"], doc["steps"])
    )
    return Plan(
        text,
        source=str(doc["source"]),
        status=str(doc["status"]),
        exit_code=outcome.exit_code,
        steps=steps,
        left=tuple(str(x["object"]) for x in doc["left"]),
        joint_names=tuple(doc["robot"]["joint_names"]),
        T_base_camera=_array(doc["T_base_camera"]),
        labels=_frozen(outcome.kept["segmentation"].labels()),
    )


# --- replay ------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class ReplayObject:
    """An object of a replayed frame, by its id stable across frames (sensor frame)."""

    id: int
    name: str
    new: bool
    centroid_m: np.ndarray
    extents_m: np.ndarray
    indices: np.ndarray | None  # its points in this frame (None when not segmented)


@dataclass(frozen=True, eq=False)
class ReplayFrame(Document):
    """One `frame` line of `clear replay --json`: the frame's ``status`` (ok, cleared,
    no_table, no_plan, failed), its objects by stable id, the next action; ``labels``
    (N,) of its segmentation (None when it was not segmented) and ``points`` (N, 3)."""

    index: int
    stamp_s: float | None
    status: str
    objects: tuple[ReplayObject, ...]
    labels: np.ndarray | None
    points: np.ndarray | None


@dataclass(frozen=True, eq=False)
class _Done:
    summary: str
    error: BaseException | None


@dataclass(frozen=True, eq=False)
class _Failed:
    error: BaseException


class _Stopped(Exception):
    """The caller stopped the replay."""


class _Channel:
    """Between the replay's thread and the caller's: one frame in hand at a time. The
    thread holds only this (not the `Replay`), so a `Replay` dropped unfinished is
    collected, and its ``__del__`` stops the thread."""

    def __init__(self) -> None:
        self.queue: queue.Queue[Any] = queue.Queue(maxsize=1)
        self.stop = threading.Event()

    def put(self, item: Any) -> None:
        while not self.stop.is_set():
            try:
                self.queue.put(item, timeout=0.1)
                return
            except queue.Full:
                continue
        raise _Stopped

    def work(self, run: Any) -> None:
        try:
            summary, error = run(self.put)
            self.put(_Done(summary, error))
        except _Stopped:
            pass
        except BaseException as exc:  # handed to the caller's thread, raised there
            try:
                self.put(_Failed(exc))
            except _Stopped:
                pass


class Replay:
    """`clear replay`, frame by frame: iterate for `ReplayFrame` s; once done,
    ``summary`` is the `summary` line. A damaged log raises PartialLogError and a log
    with no usable table SceneError after its last frame (the command's exit 9 and 4),
    ``summary`` set first. ``close()`` (or dropping the iterator) stops the replay after
    the frame in hand; the replay runs in a thread, at most one frame ahead."""

    def __init__(self, run: Any) -> None:
        self._run = run
        self._channel = _Channel()
        self._thread: threading.Thread | None = None
        self._finished = False
        self.summary: Document | None = None

    def __iter__(self) -> Iterator[ReplayFrame]:
        return self

    def __next__(self) -> ReplayFrame:
        if self._finished:
            raise StopIteration
        if self._thread is None:
            self._thread = threading.Thread(
                target=self._channel.work, args=(self._run,), name="clear-replay", daemon=True
            )
            self._thread.start()
        item = self._channel.queue.get()
        if isinstance(item, ReplayFrame):
            return item
        self._finished = True
        self._thread.join()
        if isinstance(item, _Failed):
            raise item.error
        self.summary = Document(item.summary)
        if item.error is not None:
            raise item.error
        raise StopIteration

    def close(self) -> None:
        """Stop the replay (the frame in hand is its last)."""
        self._finished = True
        self._channel.stop.set()
        if self._thread is not None:
            while self._thread.is_alive():
                try:  # free a worker blocked on the full queue
                    self._channel.queue.get(timeout=0.05)
                except queue.Empty:
                    pass

    def __del__(self) -> None:
        self._channel.stop.set()


def replay(
    log: PathLike,
    *,
    topic: str | None = None,
    every: int = 1,
    from_s: float | None = None,
    to_s: float | None = None,
    fail_fast: bool = False,
    push_memory: bool | None = None,
    base_frame: str | None = None,
    settings: Settings | None = None,
) -> Replay:
    """`clear replay`: the whole pipeline over a recorded session (an MCAP log, a bag, a
    PCD as one frame), object ids stable across frames, a check of whether each planned
    action happened; ``push_memory`` False is --no-push-memory."""
    resolved = _checked(settings)
    if push_memory is not None:
        resolved = _settings_module().override(resolved, "replay", push_memory=bool(push_memory))
    if isinstance(every, bool) or not isinstance(every, int) or every < 1:
        raise InputError(f"every = {every!r}: must be an integer >= 1")
    if from_s is not None and to_s is not None and to_s < from_s:
        raise SettingsError(f"--to {to_s} is before --from {from_s}")
    path = Path(log)
    from clearcli.tasks import replay as task  # noqa: PLC0415  (the stages)

    request = task.Request(
        resolved, every=every, from_s=from_s, to_s=to_s, fail_fast=bool(fail_fast), base_frame=base_frame
    )

    def run(put: Any) -> tuple[str, BaseException | None]:
        def on_report(report: Any, frames_read: int, total: int | None) -> None:
            put(_replay_frame(report, _document(task.SCHEMA, task.VERSION, report.to_json(), resolved, "replay")))

        result, partial = task.run(request, path, topic, on_report, lambda text: None)
        text = _document(task.SCHEMA, task.VERSION, result.to_json(), resolved, "replay")
        error: BaseException | None = partial
        if error is None and result.frames > 0 and result.no_table + result.failed == result.frames:
            error = SceneError(
                f"{path}: none of the {result.frames} frame(s) replayed held a usable table "
                f"({result.no_table} without a table, {result.failed} failed)"
            )
        return text, error

    return Replay(run)


def _replay_frame(report: Any, text: str) -> ReplayFrame:
    seg = report.result.segmentation
    frame = report.frame
    objects = tuple(
        ReplayObject(
            id=int(o.track_id),
            name=str(o.name),
            new=bool(o.new),
            centroid_m=_array(o.centroid_m),
            extents_m=_array(o.extents_m),
            indices=None if seg is None else _frozen(seg.objects[o.segment_index].indices),
        )
        for o in report.objects
    )
    doc = json.loads(text)
    return ReplayFrame(
        text,
        index=int(report.index),
        stamp_s=doc["stamp_s"],
        status=str(report.status),
        objects=objects,
        labels=None if seg is None else _frozen(seg.labels()),
        points=None if frame is None else _frozen(frame.points),
    )


# --- evaluate ----------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Evaluation(Document):
    """`clear evaluate segmentation --json`: predicted labels scored against ground
    truth (one-to-one IoU matching; the OSD/OCID overlap and boundary measures)."""

    n_true: int
    n_pred: int
    precision: float
    recall: float
    f1: float
    mean_best_iou: float


def evaluate(prediction: PathLike, truth: PathLike) -> Evaluation:
    """`clear evaluate segmentation PRED TRUTH`: ``prediction`` a labels PCD (as
    `clear segment -o` writes it), ``truth`` a labelled PCD of the same frame."""
    from clearcli.tasks import evaluate as task  # noqa: PLC0415  (the stages)

    doc = task.score_files(Path(prediction), Path(truth))
    return Evaluation(
        _document("evaluate.segmentation", 1, doc, None, "evaluate"),
        n_true=int(doc["n_true"]),
        n_pred=int(doc["n_pred"]),
        precision=float(doc["precision"]),
        recall=float(doc["recall"]),
        f1=float(doc["f1"]),
        mean_best_iou=float(doc["mean_best_iou"]),
    )
