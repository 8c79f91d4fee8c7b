"""`Frame`: one recorded point cloud, as every reader yields it and every stage takes it."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

# The one label convention of the whole project (the mOSD one):
# 0 none/invalid, 1 table (mOSD ground truth uses 1..9), 10*(k+1) object k.
LABEL_NONE = 0
LABEL_TABLE = 1


def object_label(k: int) -> int:
    """Label of object k (k counts from 0)."""
    return 10 * (k + 1)


def labels_to_write(frame: Frame, labels: np.ndarray | None) -> np.ndarray | None:
    """The (N,) labels a writer stores with ``frame``: ``labels`` when given, else the
    frame's own ``label`` field, else None; ValueError for a wrong shape."""
    if labels is None and "label" in frame.fields:
        labels = frame.fields["label"]
    if labels is None:
        return None
    labels = np.asarray(labels)
    if labels.shape != (frame.n_points,):
        raise ValueError(f"labels must have shape ({frame.n_points},), got {labels.shape}")
    return labels


def table_mask(labels: np.ndarray) -> np.ndarray:
    """(N,) bool: the table's labels (ours 1, mOSD ground truth 1..9)."""
    lab = np.asarray(labels).astype(np.int64).ravel()
    return (lab >= LABEL_TABLE) & (lab <= 9)


def object_ids(labels: np.ndarray) -> np.ndarray:
    """(N,) int64 object id per label: ``label // 10`` for objects (labels >= 10: object
    k has id k + 1), 0 for no label and the table (mOSD's 1..9 included)."""
    lab = np.asarray(labels).astype(np.int64).ravel()
    return np.where(lab >= 10, lab // 10, 0)


@dataclass(frozen=True, eq=False)
class Frame:
    """A point cloud in the sensor frame (metres; optical frame: z forward, y down).

    points:  (N, 3) float32; NaN rows are invalid pixels and are kept in place so that an
             organized cloud keeps its (height, width) order.
    colors:  (N, 3) uint8 RGB, or None.
    shape:   (height, width) when organized, else None. N == height * width then.
    fields:  any other per-point field by name, (N,) or (N, k) arrays, e.g. "label".
    stamp_s: time stamp in seconds (log time for MCAP, 0.0 when unknown).
    frame_id: the sensor frame's name ("" when unknown).
    source:  where it came from, for messages ("scene.pcd", "log.mcap#3 /topic").
    color_note: why a colour offered with the frame was left out ("" when none was, or
             when it is in ``colors``): a colour image of another size than the depth.
    """

    points: np.ndarray
    colors: np.ndarray | None = None
    shape: tuple[int, int] | None = None
    fields: Mapping[str, np.ndarray] = field(default_factory=dict)
    stamp_s: float = 0.0
    frame_id: str = ""
    source: str = ""
    color_note: str = ""

    @property
    def n_points(self) -> int:
        return int(self.points.shape[0])

    @property
    def finite_mask(self) -> np.ndarray:
        """(N,) bool: rows whose x, y and z are all finite."""
        return np.isfinite(self.points).all(axis=1)

    @property
    def is_organized(self) -> bool:
        return self.shape is not None and self.shape[0] > 1

    @property
    def grid(self) -> tuple[int, int] | None:
        """(rows, columns) of the pixel grid the points lie on, one point per pixel in row
        order: what every step that reads neighbours on the image needs; None for an
        unorganized cloud, a single row (PCL's unorganized layout) or a shape that does
        not hold the points (a hand-made frame)."""
        shape = self.shape
        if shape is None or shape[0] <= 1 or shape[0] * shape[1] != self.points.shape[0]:
            return None
        return shape
