"""Where the robot stands, from a log: the transforms on its /tf_static and /tf (MCAP
here; ROS bags through `clearcli.io.rosbag.read_bag_transforms`), and the chain of them
from the robot's base frame to the camera's."""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from clearcli.errors import ClearError

# Names the robot base frame goes by in WAM setups (IRI's and the ROS WAM packages), and
# the generic ROS one last; replay puts the robot profile's own base frame first
# (panda_link0 for a Panda), and `--base-frame` picks another.
BASE_FRAMES = ("wam_base", "wam_link_base", "iri_wam_link_base", "estirabot_link_base", "link_base", "base_link")
TF_TOPICS = ("/tf_static", "/tf")


def _field(msg: Any, *names: str) -> Any:
    from clearcli.io.messages import message_field

    return message_field(msg, *names)


def _transform_matrix(translation: Any, rotation: Any) -> np.ndarray:
    from clearcli.transforms import pose_to_matrix

    q = [float(_field(rotation, k) or 0.0) for k in ("x", "y", "z", "w")]
    return pose_to_matrix([float(_field(translation, k) or 0.0) for k in ("x", "y", "z")], q)


def read_transforms(path: Any, max_messages: int = 1000) -> dict[tuple[str, str], np.ndarray]:
    """T_parent_child of every (parent, child) pair on the log's /tf_static and /tf
    (the first seen of each; a session's camera does not move). Reads at most
    ``max_messages`` transform messages, so a long /tf costs little. A log without them,
    or whose transforms cannot be decoded, gives {}. ROS bags: `io.rosbag.read_bag_transforms`."""
    from clearcli.io.mcap import read_summary
    from clearcli.io.messages import MessageDecoders
    from clearcli.io.read import sniff

    try:
        if sniff(path) in ("rosbag1", "rosbag2"):
            from clearcli.io.rosbag import read_bag_transforms

            return read_bag_transforms(path, max_messages)
        summary = read_summary(path)
    except ClearError:
        return {}
    topics = [t for t, _ in summary.topics() if t in TF_TOPICS]
    if not topics:
        return {}
    from mcap.reader import NonSeekingReader, SeekingReader

    found: dict[tuple[str, str], np.ndarray] = {}
    decoders = MessageDecoders()
    try:
        with open(path, "rb") as fp:
            reader: Any = SeekingReader(fp) if summary.indexed else NonSeekingReader(fp)
            for count, (schema, channel, message) in enumerate(reader.iter_messages(topics=topics)):
                if count >= max_messages:
                    break
                try:
                    msg = decoders.decode(schema, channel, message.data)
                except Exception:
                    continue
                items = _field(msg, "transforms")
                for tf in items if items is not None else [msg]:
                    try:
                        header = _field(tf, "header")
                        parent = _field(header, "frame_id") if header is not None else _field(tf, "parent_frame_id")
                        child = _field(tf, "child_frame_id")
                        inner = _field(tf, "transform") or tf
                        T = _transform_matrix(_field(inner, "translation"), _field(inner, "rotation"))
                    except Exception:
                        continue
                    if parent and child:
                        found.setdefault((str(parent).lstrip("/"), str(child).lstrip("/")), T)
    except Exception:  # a damaged log: whatever was read before the damage
        pass
    return found


def lookup_transform(transforms: Mapping[tuple[str, str], np.ndarray], target: str, source: str) -> np.ndarray | None:
    """T_target_source by chaining the transforms (either way along each edge); None when
    the two frames are not connected."""
    target, source = target.lstrip("/"), source.lstrip("/")
    if target == source:
        return np.eye(4)
    edges: dict[str, list[tuple[str, np.ndarray]]] = {}
    for (parent, child), T in transforms.items():
        edges.setdefault(parent, []).append((child, T))  # T_parent_child
        edges.setdefault(child, []).append((parent, np.linalg.inv(T)))  # T_child_parent
    # breadth first from the target: T_target_node accumulates along the way
    best: dict[str, np.ndarray] = {target: np.eye(4)}
    queue = [target]
    while queue:
        node = queue.pop(0)
        for nxt, T_node_next in edges.get(node, []):
            if nxt not in best:
                best[nxt] = best[node] @ T_node_next
                if nxt == source:
                    return best[nxt]
                queue.append(nxt)
    return None


def base_camera_from_log(
    path: Any, frame_id: str, base_frames: tuple[str, ...] = BASE_FRAMES
) -> tuple[np.ndarray | None, str]:
    """(T_base_camera, the base frame's name) from the log's transforms, or (None, "")."""
    if not frame_id:
        return None, ""
    transforms = read_transforms(path)
    if not transforms:
        return None, ""
    for base in base_frames:
        T = lookup_transform(transforms, base, frame_id)
        if T is not None:
            return T, base
    return None, ""
