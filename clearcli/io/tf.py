"""Where the robot stands, from a log: the transforms on its /tf_static and /tf (read by
the log's format: `clearcli.io.mcap.read_mcap_transforms`,
`clearcli.io.rosbag.read_bag_transforms`), and the chain of them from the robot's base
frame to the camera's."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from clearcli.errors import ClearError
from clearcli.io.formats import format_of

# Names the robot base frame goes by in WAM setups (IRI's and the ROS WAM packages), and
# the generic ROS one last; replay puts the robot profile's own base frame first
# (panda_link0 for a Panda), and `--base-frame` picks another.
BASE_FRAMES = ("wam_base", "wam_link_base", "iri_wam_link_base", "estirabot_link_base", "link_base", "base_link")


def read_transforms(path: Any, max_messages: int = 1000) -> dict[tuple[str, str], np.ndarray]:
    """T_parent_child of every (parent, child) pair on the log's /tf_static and /tf
    (the first seen of each; a session's camera does not move). Reads at most
    ``max_messages`` transform messages, so a long /tf costs little. A file that holds
    none (a PCD, a depth image), cannot be read, or whose transforms cannot be decoded
    gives {}. Each format reads its own (`transforms` of clearcli/io/formats/)."""
    try:
        return format_of(Path(path)).transforms(Path(path), max_messages)
    except ClearError:
        return {}


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
