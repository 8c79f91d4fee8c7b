"""The messages of the annotated log, built for Foxglove: `foxglove.SceneUpdate` of a
replayed frame (objects coloured by their stable ids, hulls, labels, push arrows, the
gripper at the next action's pose), the frame's facts and plan, a `foxglove.PointCloud`
of a PCD input, and the JSON schemas (jsonschema encoding) of the channels. The writer is
`clearcli.replay.annotate`."""

from __future__ import annotations

import base64
import colorsys
import json
from typing import TYPE_CHECKING, Any

import numpy as np

from clearcli.geometry.gripper import gripper_model
from clearcli.transforms import matrix_to_quat

if TYPE_CHECKING:
    from clearcli.io.frames import Frame
    from clearcli.replay.report import FrameReport
    from clearcli.settings import Settings

SCENE_TOPIC = "/clear/scene"
PLAN_TOPIC = "/clear/plan"
PREDICATES_TOPIC = "/clear/predicates"
SCENE_SCHEMA = "foxglove.SceneUpdate"
POINTCLOUD_SCHEMA = "foxglove.PointCloud"

# Compact JSON schemas, written for this project from the field lists Foxglove documents
# for its message types; the viewer picks its panels by the schema name.
_NUMBER = {"type": "number"}
_INT = {"type": "integer"}
_STRING = {"type": "string"}
_BOOL = {"type": "boolean"}


def _object(**properties: Any) -> dict[str, Any]:
    return {"type": "object", "properties": properties}


def _array(items: dict[str, Any]) -> dict[str, Any]:
    return {"type": "array", "items": items}


def _objects(**properties: Any) -> dict[str, Any]:
    """An array of objects of these properties."""
    return _array(_object(**properties))


_TIME = _object(sec=_INT, nsec=_INT)
_VEC3 = _object(x=_NUMBER, y=_NUMBER, z=_NUMBER)
_QUAT = _object(x=_NUMBER, y=_NUMBER, z=_NUMBER, w=_NUMBER)
_POSE = _object(position=_VEC3, orientation=_QUAT)
_COLOR = _object(r=_NUMBER, g=_NUMBER, b=_NUMBER, a=_NUMBER)

# what lines and triangles share: their points, one colour or a colour each, the indices
_POINTS = {"points": _array(_VEC3), "color": _COLOR, "colors": _array(_COLOR), "indices": _array(_INT)}
_PRIMITIVES = {
    "arrows": _objects(
        pose=_POSE,
        shaft_length=_NUMBER,
        shaft_diameter=_NUMBER,
        head_length=_NUMBER,
        head_diameter=_NUMBER,
        color=_COLOR,
    ),
    "cubes": _objects(pose=_POSE, size=_VEC3, color=_COLOR),
    "spheres": _objects(pose=_POSE, size=_VEC3, color=_COLOR),
    "cylinders": _objects(pose=_POSE, size=_VEC3, bottom_scale=_NUMBER, top_scale=_NUMBER, color=_COLOR),
    "lines": _objects(type=_INT, pose=_POSE, thickness=_NUMBER, scale_invariant=_BOOL, **_POINTS),
    "triangles": _objects(pose=_POSE, **_POINTS),
    "texts": _objects(
        pose=_POSE, billboard=_BOOL, font_size=_NUMBER, scale_invariant=_BOOL, color=_COLOR, text=_STRING
    ),
    "models": _array({"type": "object"}),
}

_METADATA = _objects(key=_STRING, value=_STRING)
_ENTITY = _object(
    timestamp=_TIME, frame_id=_STRING, id=_STRING, lifetime=_TIME, frame_locked=_BOOL, metadata=_METADATA, **_PRIMITIVES
)

SCENE_UPDATE_JSONSCHEMA: dict[str, Any] = {
    "title": SCENE_SCHEMA,
    "description": "An update to the entities of a 3D scene",
    **_object(deletions=_objects(timestamp=_TIME, type=_INT, id=_STRING), entities=_array(_ENTITY)),
}

POINTCLOUD_JSONSCHEMA: dict[str, Any] = {
    "title": POINTCLOUD_SCHEMA,
    **_object(
        timestamp=_TIME,
        frame_id=_STRING,
        pose=_POSE,
        point_stride=_INT,
        fields=_objects(name=_STRING, offset=_INT, type=_INT),
        data={"type": "string", "contentEncoding": "base64"},
    ),
}

PLAN_JSONSCHEMA: dict[str, Any] = {
    "title": "clear.Plan",
    **_object(
        frame=_INT,
        actions=_objects(kind=_STRING, id={"type": ["integer", "null"]}, name=_STRING, direction=_STRING),
        cost=_INT,
        optimal=_BOOL,
        replans=_INT,
        unreachable=_array({}),
        ungraspable=_array({}),
        stuck=_array({}),
    ),
}

PREDICATES_JSONSCHEMA: dict[str, Any] = {
    "title": "clear.Predicates",
    **_object(
        frame=_INT,
        objects=_array({"type": "object"}),
        facts=_array(_array(_STRING)),
        push_costs=_array({"type": "object"}),
    ),
}


# --- small geometry helpers -------------------------------------------------------------


def id_color(track_id: int, alpha: float = 1.0) -> dict[str, float]:
    """A colour per id: hues spaced by the golden angle, so neighbours in id differ."""
    hue = (track_id * 0.618033988749895) % 1.0
    r, g, b = colorsys.hsv_to_rgb(hue, 0.75, 0.95)
    return {"r": round(r, 4), "g": round(g, 4), "b": round(b, 4), "a": alpha}


def _time(stamp_s: float) -> dict[str, int]:
    total = int(round(max(stamp_s, 0.0) * 1e9))
    sec, nsec = divmod(total, 1_000_000_000)
    return {"sec": int(sec), "nsec": int(nsec)}


def _vec(v: Any) -> dict[str, float]:
    return {"x": float(v[0]), "y": float(v[1]), "z": float(v[2])}


def _quat_from_matrix(R: np.ndarray) -> dict[str, float]:
    x, y, z, w = matrix_to_quat(R)  # projected onto SO(3) first: PCA axes may be a hair off
    return {"x": x, "y": y, "z": z, "w": w}


def _pose(T: np.ndarray) -> dict[str, Any]:
    return {"position": _vec(T[:3, 3]), "orientation": _quat_from_matrix(T[:3, :3])}


IDENTITY_POSE = {"position": {"x": 0.0, "y": 0.0, "z": 0.0}, "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}


def _arrow(
    start: np.ndarray, direction: np.ndarray, up: np.ndarray, length: float, color: dict[str, float], thick: bool
) -> dict[str, Any]:
    """An arrow from ``start`` along ``direction`` (an ArrowPrimitive points along its
    pose's +x)."""
    x = np.asarray(direction, dtype=float)
    x = x / max(np.linalg.norm(x), 1e-12)
    z = np.asarray(up, dtype=float) - (np.asarray(up, dtype=float) @ x) * x
    if np.linalg.norm(z) < 1e-9:
        z = np.cross(x, [1.0, 0.0, 0.0]) if abs(x[0]) < 0.9 else np.cross(x, [0.0, 1.0, 0.0])
    z = z / np.linalg.norm(z)
    y = np.cross(z, x)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, y, z])
    T[:3, 3] = start
    head = min(0.3 * length, 0.03)
    return {
        "pose": _pose(T),
        "shaft_length": float(max(length - head, 1e-4)),
        "shaft_diameter": 0.008 if thick else 0.003,
        "head_length": float(head),
        "head_diameter": 0.02 if thick else 0.009,
        "color": color,
    }


def _entity(frame_id: str, stamp_s: float, entity_id: str, **primitives: Any) -> dict[str, Any]:
    entity: dict[str, Any] = {
        "timestamp": _time(stamp_s),
        "frame_id": frame_id,
        "id": entity_id,
        "lifetime": {"sec": 0, "nsec": 0},
        "frame_locked": False,
        "metadata": primitives.pop("metadata", []),
    }
    for key in _PRIMITIVES:
        entity[key] = primitives.get(key, [])
    return entity


def scene_update(report: FrameReport, frame_id: str, settings: Settings | None = None) -> dict[str, Any]:
    """The `foxglove.SceneUpdate` of one replayed frame: one entity per object (id
    ``object/<track id>``), plus ``gripper`` at the next action's pose when planned."""
    result = report.result
    seg = result.segmentation
    state = result.state
    stamp = report.stamp_s
    update: dict[str, Any] = {"deletions": [{"timestamp": _time(stamp), "type": 1, "id": ""}], "entities": []}
    if seg is None:
        return update
    models = {o.segment_index: o for o in state.objects} if state is not None else {}
    first = report.first_action()
    up = np.asarray(seg.table.normal, dtype=float)
    for obj in report.objects:
        segmented = seg.objects[obj.segment_index]
        color = id_color(obj.track_id, 0.7)
        model = models.get(obj.segment_index)
        triangles: list[dict[str, Any]] = []
        cubes: list[dict[str, Any]] = []
        arrows: list[dict[str, Any]] = []
        if model is not None and len(model.hull_faces):
            vertices = np.asarray(model.hull_vertices, dtype=float)
            triangles.append(
                {
                    "pose": IDENTITY_POSE,
                    "points": [_vec(v) for v in vertices],
                    "color": color,
                    "colors": [],
                    "indices": [int(i) for i in np.asarray(model.hull_faces).ravel()],
                }
            )
        else:
            T = np.eye(4)
            T[:3, :3] = np.asarray(segmented.obb_axes, dtype=float).T  # rows are the axes
            T[:3, 3] = segmented.obb_center
            cubes.append({"pose": _pose(T), "size": _vec(segmented.obb_extents), "color": color})
        centroid = np.asarray(model.centroid if model is not None else segmented.centroid, dtype=float)
        if model is not None:
            for direction, push in model.pushes.items():
                planned = (
                    first is not None
                    and first.kind == "push"
                    and first.obj == model.name
                    and first.direction == direction
                )
                arrows.append(
                    _arrow(
                        centroid,
                        np.asarray(push.unit_vector, dtype=float),
                        up,
                        float(push.push_length_m) if planned else 0.6 * float(push.push_length_m),
                        id_color(obj.track_id, 1.0 if planned else 0.35),
                        planned,
                    )
                )
        label_pose = np.eye(4)
        label_pose[:3, 3] = centroid + 0.05 * up
        label = f"#{obj.track_id}" + (f" {obj.name}" if obj.name else "")
        texts = [
            {
                "pose": _pose(label_pose),
                "billboard": True,
                "font_size": 14.0,
                "scale_invariant": True,
                "color": {"r": 1.0, "g": 1.0, "b": 1.0, "a": 1.0},
                "text": label,
            }
        ]
        metadata = [{"key": "id", "value": str(obj.track_id)}, {"key": "name", "value": obj.name}]
        update["entities"].append(
            _entity(
                frame_id,
                stamp,
                f"object/{obj.track_id}",
                triangles=triangles,
                cubes=cubes,
                arrows=arrows,
                texts=texts,
                metadata=metadata,
            )
        )
    gripper_pose = next_action_pose(report)
    if gripper_pose is not None:
        model_g = gripper_model(settings.gripper if settings is not None else None)
        closed = first is not None and first.kind == "push"
        boxes = model_g.boxes(closed=closed)
        cubes = []
        for center, half in zip(boxes.centers, boxes.half_extents):
            T = gripper_pose.copy()
            T[:3, 3] = gripper_pose[:3, :3] @ center + gripper_pose[:3, 3]
            cubes.append(
                {"pose": _pose(T), "size": _vec(2.0 * half), "color": {"r": 0.85, "g": 0.85, "b": 0.9, "a": 0.8}}
            )
        assert first is not None
        update["entities"].append(
            _entity(
                frame_id,
                stamp,
                "gripper",
                cubes=cubes,
                metadata=[{"key": "action", "value": first.pddl()}],
            )
        )
    return update


def next_action_pose(report: FrameReport) -> np.ndarray | None:
    """T_camera_gripper of the first action's working pose (the grasp, or the push's
    start), from the candidate the IK check accepted."""
    first = report.first_action()
    state = report.result.state
    plan = report.result.plan
    if first is None or state is None:
        return None
    try:
        obj = state.by_name(first.obj)
    except KeyError:
        return None
    index = int(getattr(plan.first, "candidate", 0) or 0) if plan is not None and plan.first is not None else 0
    if first.kind == "grasp":
        candidates = obj.grasp_candidates
    else:
        push = obj.pushes.get(first.direction or "")
        candidates = push.candidates if push is not None else ()
    if not candidates:
        return None
    sequence = candidates[min(index, len(candidates) - 1)]
    if not sequence:
        return None
    return np.asarray(sequence[min(1, len(sequence) - 1)], dtype=float)


def predicates_json(report: FrameReport) -> dict[str, Any] | None:
    state = report.result.state
    if state is None:
        return None
    ids = report.ids_by_name

    def name(token: str) -> str:
        return f"#{ids[token]}" if token in ids else token

    return {
        "frame": report.index,
        "objects": [{"id": ids.get(o.name), "name": o.name} for o in state.objects],
        "facts": sorted([fact[0], *(name(t) for t in fact[1:])] for fact in state.facts),
        "push_costs": [
            {"id": ids.get(n), "name": n, "direction": d, "cost": int(c)}
            for (n, d), c in sorted(state.push_costs.items())
        ],
    }


def pointcloud_json(frame: Frame) -> dict[str, Any]:
    """A frame as `foxglove.PointCloud` (finite points, x y z float32, rgb as 3 uint8)."""
    keep = frame.finite_mask
    points = np.ascontiguousarray(frame.points[keep], dtype="<f4")
    fields = [{"name": n, "offset": 4 * k, "type": 7} for k, n in enumerate("xyz")]
    if frame.colors is not None:
        record = np.dtype([("p", "<f4", 3), ("c", "u1", 3), ("pad", "u1")])
        blob = np.zeros(points.shape[0], dtype=record)
        blob["p"] = points
        blob["c"] = frame.colors[keep]
        fields += [{"name": n, "offset": 12 + k, "type": 1} for k, n in enumerate(("red", "green", "blue"))]
        data = blob.tobytes()
        stride = record.itemsize
    else:
        data = points.tobytes()
        stride = 12
    return {
        "timestamp": _time(frame.stamp_s),
        "frame_id": frame.frame_id or "camera",
        "pose": IDENTITY_POSE,
        "point_stride": stride,
        "fields": fields,
        "data": base64.b64encode(data).decode("ascii"),
    }


def dumps(doc: Any) -> bytes:
    return json.dumps(doc, separators=(",", ":"), allow_nan=False).encode("utf-8")
