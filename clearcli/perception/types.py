"""Values produced by segmentation: the table and the objects on it."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from clearcli.io.frames import LABEL_TABLE, object_label


@dataclass(frozen=True, eq=False)
class TablePlane:
    """Plane n . p + d = 0 in the sensor frame; ``normal`` is unit and points up (away
    from the table, towards the side the objects and the camera are on)."""

    normal: np.ndarray  # (3,)
    offset: float  # d

    def height_of(self, points: np.ndarray) -> np.ndarray:
        """Signed height (m) of points above the plane."""
        h = points @ self.normal
        h += self.offset  # in place: the same sum, without a second (N,) array
        return h

    def project(self, points: np.ndarray) -> np.ndarray:
        """Orthogonal projection of points onto the plane."""
        return points - np.outer(self.height_of(points), self.normal)


@dataclass(frozen=True)
class PlaneVerdict:
    """One candidate plane: in the sensor frame (unit normal towards the camera side for
    a camera frame), its largest connected piece's area, the points standing on it inside
    its hull, and why it was taken or not."""

    normal: tuple[float, float, float]
    offset_m: float
    area_m2: float
    standing_points: int  # above minus below: objects stand on one side, noise on both
    chosen: bool
    why: str


@dataclass(frozen=True, eq=False)
class SegmentedObject:
    """One object: its points are ``frame.points[indices]``.

    principal_axes rows are unit PCA axes, largest variance first (right-handed).
    The oriented bounding box is centred at ``obb_center`` with axes ``obb_axes`` (rows)
    and full side lengths ``obb_extents`` (m) along them.
    """

    indices: np.ndarray  # (M,) int64 into the frame's points
    centroid: np.ndarray  # (3,)
    obb_center: np.ndarray  # (3,)
    obb_axes: np.ndarray  # (3, 3)
    obb_extents: np.ndarray  # (3,)
    principal_axes: np.ndarray  # (3, 3)

    @property
    def n_points(self) -> int:
        return int(self.indices.shape[0])


@dataclass(frozen=True, eq=False)
class Excluded:
    """A segment above the support that is no object (perception/exclude.py): its points
    are ``frame.points[indices]``; ``reason`` says why (it reaches in from beyond the
    support's outline, hangs above it, stands on something excluded)."""

    indices: np.ndarray  # (M,) int64 into the frame's points
    centroid: np.ndarray  # (3,)
    reason: str


@dataclass(frozen=True, eq=False)
class Segmentation:
    """Result of `segment`: everything later stages need, and the frame it came from.

    table_polygon: (K, 3) vertices of the table's 2D convex hull, on the plane, in order.
    table_indices: indices of the table's inlier points in the frame.
    objects: ordered as segmentation produced them (later stages rename them by position).
    timings_s: seconds per stage, by stage name.
    """

    n_points: int
    table: TablePlane
    table_polygon: np.ndarray
    table_indices: np.ndarray
    objects: tuple[SegmentedObject, ...]
    timings_s: Mapping[str, float] = field(default_factory=dict)
    # how the support was chosen: every candidate plane and its verdict, the area of the
    # plane dropped as lying beyond the table's edge (m^2); and whether colour was used
    support: tuple[PlaneVerdict, ...] = ()
    beyond_edge_m2: float = 0.0
    color_used: bool = False
    color_note: str = ""  # what read the colour, or why none did
    # per object (as ``objects``): its rim when it is an open container, or why not; the
    # table polygon's sides and whether each is seen to end (openings.py). Empty when
    # the segmentation came from elsewhere (labels): the predicates stage works them out.
    openings: tuple[Any, ...] = ()
    table_edges: tuple[Any, ...] = ()
    # segments above the support that are no objects, each with its reason (issue 37)
    excluded: tuple[Excluded, ...] = ()
    source: str = ""
    frame_id: str = ""
    stamp_s: float = 0.0

    def labels(self) -> np.ndarray:
        """(n_points,) int32 labels in the project convention (0 none, 1 table, 10(k+1))."""
        out = np.zeros(self.n_points, dtype=np.int32)
        out[self.table_indices] = LABEL_TABLE
        for k, obj in enumerate(self.objects):
            out[obj.indices] = object_label(k)
        return out
