"""What the simulated camera knows: its labels as a segmentation (`--truth-segmentation`),
and which world object a segment stands for."""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np

from clearcli.errors import SceneError
from clearcli.io.frames import Frame, object_ids, table_mask
from clearcli.perception.segment import make_object
from clearcli.perception.types import Segmentation, TablePlane


def truth_segment(frame: Frame, settings: Any = None) -> Segmentation:
    """A perfect segmentation from the camera's labels (for fast tests and as an oracle
    that separates the planner's behaviour from the segmenter's errors)."""
    from scipy.spatial import ConvexHull

    labels = np.asarray(frame.fields.get("label", np.zeros(frame.n_points)), dtype=np.int64)
    finite = frame.finite_mask
    table_idx = np.flatnonzero(finite & table_mask(labels))
    if table_idx.size < 3:
        raise SceneError(f"{frame.source or 'frame'}: no table points in the labels")
    pts = frame.points[table_idx].astype(np.float64)
    centre = pts.mean(axis=0)
    _, _, vt = np.linalg.svd(pts - centre, full_matrices=False)
    normal = vt[2]
    if normal @ (np.zeros(3) - centre) < 0:  # towards the camera (the origin)
        normal = -normal
    table = TablePlane(normal=normal, offset=float(-normal @ centre))
    u = vt[0]
    v = np.cross(normal, u)
    flat = table.project(pts)
    xy = np.stack([flat @ u, flat @ v], axis=1)
    polygon = flat[ConvexHull(xy).vertices]
    objects = []
    ids = object_ids(labels)
    obj_idx = np.flatnonzero(finite & (ids > 0))
    groups = ids[obj_idx]
    for g in np.unique(groups):
        members = obj_idx[groups == g]
        if members.size < 30:
            continue
        objects.append(make_object(members, frame.points[members].astype(np.float64), table, 0.02))
    return Segmentation(
        n_points=frame.n_points,
        table=table,
        table_polygon=polygon,
        table_indices=table_idx,
        objects=tuple(objects),
        source=frame.source,
        frame_id=frame.frame_id,
        stamp_s=frame.stamp_s,
    )


def world_object_of(frame: Frame, segmentation: Segmentation, segment_index: int) -> int | None:
    """The world's object id under a segment: the most common label among its points."""
    labels = frame.fields.get("label")
    if labels is None:
        return None
    own = object_ids(np.asarray(labels)[segmentation.objects[segment_index].indices])
    own = own[own > 0]
    if own.size == 0:
        return None
    return int(Counter((own - 1).tolist()).most_common(1)[0][0])  # the world's id: k


# --- the closed loop -------------------------------------------------------------------------
