"""The working resolution: an organized frame far denser than the voxel grid is segmented
on every k-th row and column, and its labels carried back to every pixel.

What the stages need. The voxel grid (``voxel_m``, 5 mm) is the finest scale any stage
after the table reads, and a surface fills its voxels and their adjacency once it holds
about two samples per voxel edge; more samples only make each voxel's mean a little
smoother. The pixel-grid stages (outlier filter, depth edges, occlusion's gap lines,
flat objects, the table's beyond-the-edge cells) count pixels, and their counts were
set on the 640x480 sensors' grids (Kinect 1.9 mrad, RealSense 1.6 mrad a pixel). The
rule: the working grid's pixel pitch is the coarsest whole multiple k of the sensor's
that still gives ``SAMPLES_PER_VOXEL`` (2) samples per voxel edge at ``REFERENCE_RANGE_M``
(1 m, the far side of a table scene):

    k = floor(voxel_m / (SAMPLES_PER_VOXEL * REFERENCE_RANGE_M) / pitch)

With the 5 mm voxel that is a pitch of at most 2.5 mrad: the 640x480 sensors (1.6-1.9
mrad) keep k = 1, every pixel (their outputs do not change); a RealSense at 1280x720
(1.09 mrad) takes k = 2, a 640x360 grid of 2.2 mrad, as fine as the grids the
pixel-count stages were set on, at a quarter of the points. The pitch is read from the
points (an organized cloud in the camera's optical frame is a pinhole's grid: x/z grows
by 1/fx from one column to the next, y/z by 1/fy from one row to the next), as the
median step over a sample of rows and columns; a grid whose steps do not agree (not a
pinhole's, e.g. an organized cloud moved into another frame) keeps every pixel. A
median of thousands of steps moves by nothing under a rounding-sized change of the
points, and the sensors above lie far from a boundary of k (ratios 1.3, 1.5, 2.3).
Unorganized clouds keep every point (SegmentSize grows the voxel for sparse ones;
dense ones are not thinned here).

Labels on the full grid (`WorkingGrid.to_full`). A pixel of the working grid is a
pixel of the frame: it keeps its label. Every other pixel lies between the working
pixels of its k x k block's corners (the block's own and the next row's and column's):
it takes the label (object, table, or none) of the nearest of them in 3D, when that one
is finite and within one voxel (``voxel_m``) of it; otherwise, or when it is not finite
itself, none. A point on an object takes that object's label, a point of the table the
table's, and a flying pixel far from both, none. The objects' boxes, centroids and axes
stay those of the working grid's points (the same surface, sampled every k-th pixel).
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from clearcli.io.frames import Frame
from clearcli.perception.types import Segmentation
from clearcli.settings.segment import SegmentSettings

# two samples per voxel edge (module docstring) ...
SAMPLES_PER_VOXEL = 2.0
# ... out to the far side of a table scene
REFERENCE_RANGE_M = 1.0
# every this many rows and columns are probed for the pixel pitch
_PROBE_STEP = 8
# a pinhole's steps agree: the quartiles within this share of the median
_PINHOLE_SPREAD = 0.05
# at least this many steps to judge the pitch by
_MIN_STEPS = 100


def _median_step(tan: np.ndarray, depth: np.ndarray) -> float | None:
    """The median step of ``tan`` (x/z or y/z) between neighbours along axis 1 of 2D
    arrays, or None when the steps are too few or do not agree (no pinhole's grid)."""
    ok = np.isfinite(tan) & (depth > 0)
    step = np.diff(tan, axis=1)[ok[:, 1:] & ok[:, :-1]]
    if step.size < _MIN_STEPS:
        return None
    q25, q50, q75 = np.percentile(step, (25, 50, 75))
    if not q50 > 0 or (q75 - q25) > _PINHOLE_SPREAD * q50:
        return None
    return float(q50)


def pixel_pitch(
    points: np.ndarray, shape: tuple[int, int], probe_step: int = _PROBE_STEP
) -> tuple[float, float] | None:
    """(rows' pitch, columns' pitch): the step of y/z from one row to the next (1/fy)
    and of x/z from one column to the next (1/fx), radians at the image centre; None when
    the frame is no pinhole's grid in its optical frame. ``probe_step``: every this many
    rows and columns are probed (a coarser probe only to tell a pinhole's grid, cheaply)."""
    h, w = shape
    if h < 2 or w < 2 or points.shape != (h * w, 3):
        return None
    grid = points.reshape(h, w, 3)
    with np.errstate(invalid="ignore", divide="ignore"):
        rows = grid[::probe_step].astype(np.float64)  # sampled rows, every column
        cols = grid[:, ::probe_step].astype(np.float64).transpose(1, 0, 2)  # sampled columns, every row
        across = _median_step(rows[..., 0] / rows[..., 2], rows[..., 2])
        down = _median_step(cols[..., 1] / cols[..., 2], cols[..., 2])
    if across is None or down is None:
        return None
    return down, across


def stride_for(pitch_rad: float, voxel_m: float) -> int:
    """k of the module docstring: every k-th pixel still gives SAMPLES_PER_VOXEL samples
    per voxel edge at REFERENCE_RANGE_M (at least 1)."""
    coarsest = voxel_m / (SAMPLES_PER_VOXEL * REFERENCE_RANGE_M)
    return max(1, int(np.floor(coarsest / pitch_rad)))


def choose_stride(frame: Frame, settings: SegmentSettings) -> int:
    """The working grid's stride for ``frame``: 1 (every pixel) unless it is an organized
    pinhole's grid finer than the rule of the module docstring asks."""
    shape = frame.grid
    if shape is None:
        return 1
    return stride_of_pitch(pixel_pitch(frame.points, shape), settings)


def stride_of_pitch(pitch: tuple[float, float] | None, settings: SegmentSettings) -> int:
    """`choose_stride` of an organized frame whose `pixel_pitch` is ``pitch`` (None: no
    pinhole's grid, every pixel)."""
    return 1 if pitch is None else stride_for(max(pitch), settings.voxel_m)


def _every_kth(values: np.ndarray, shape: tuple[int, int], k: int) -> np.ndarray:
    """Rows of ``values`` (N, ...) of every k-th row and column of the (h, w) grid."""
    h, w = shape
    grid = values.reshape(h, w, *values.shape[1:])
    sub = grid[::k, ::k]
    return np.ascontiguousarray(sub).reshape(-1, *values.shape[1:])


@dataclass(frozen=True, eq=False)
class WorkingGrid:
    """A frame and the grid it is segmented on: ``frame`` itself when ``stride`` is 1,
    else its every ``stride``-th row and column (``frame``'s fields with it)."""

    full: Frame
    frame: Frame
    stride: int
    made_s: float  # seconds it took to make

    @classmethod
    def of(cls, frame: Frame, settings: SegmentSettings, stride: int | None = None) -> WorkingGrid:
        """The working grid of ``frame``: ``stride`` (None: `choose_stride`'s rule)."""
        start = time.perf_counter()
        k = choose_stride(frame, settings) if stride is None else max(1, int(stride))
        shape = frame.shape
        if k == 1 or shape is None or shape[0] * shape[1] != frame.n_points:
            return cls(frame, frame, 1, time.perf_counter() - start)
        h, w = shape
        work = dataclasses.replace(
            frame,
            points=_every_kth(frame.points, shape, k),
            colors=None if frame.colors is None else _every_kth(frame.colors, shape, k),
            shape=(-(-h // k), -(-w // k)),
            fields={
                name: _every_kth(np.asarray(v), shape, k) if np.shape(v)[:1] == (frame.n_points,) else v
                for name, v in frame.fields.items()
            },
        )
        return cls(frame, work, k, time.perf_counter() - start)

    def full_index(self, working: np.ndarray) -> np.ndarray:
        """Frame index of each working-grid index (the working pixel itself)."""
        if self.stride == 1:
            return np.asarray(working, dtype=np.int64)
        assert self.full.shape is not None and self.frame.shape is not None  # a working grid is organized
        ww = self.frame.shape[1]
        w = self.full.shape[1]
        working = np.asarray(working, dtype=np.int64)
        return (working // ww) * self.stride * w + (working % ww) * self.stride

    def full_labels(self, working_labels: np.ndarray, voxel_m: float) -> np.ndarray:
        """(N,) labels of every pixel of the full frame from (n,) labels of the working
        grid's pixels (any integers, 0 = none): module docstring, "Labels on the full grid"."""
        if self.stride == 1:
            return np.asarray(working_labels).copy()
        assert self.full.shape is not None and self.frame.shape is not None  # a working grid is organized
        k = self.stride
        h, w = self.full.shape
        hw, ww = self.frame.shape
        # one contiguous (h, w) plane per coordinate: the strided views below then read
        # single floats, not (3,) rows
        full_xyz = np.ascontiguousarray(self.full.points.reshape(h, w, 3).transpose(2, 0, 1), dtype=np.float32)
        lab_w = np.asarray(working_labels).reshape(hw, ww)
        # the working grid padded by one row and column past its last: no pixel there
        # (label -1, NaN point: never the nearer), so every block has its four corners
        lab_p = np.full((hw + 1, ww + 1), -1, dtype=lab_w.dtype)
        lab_p[:hw, :ww] = lab_w
        xyz_p = np.full((3, hw + 1, ww + 1), np.nan, dtype=np.float32)
        xyz_p[:, :hw, :ww] = full_xyz[:, ::k, ::k]
        out = np.zeros((h, w), dtype=lab_w.dtype)
        out[::k, ::k] = lab_w
        far = np.float32(voxel_m) ** 2
        for r in range(k):
            for c in range(k):
                if r == 0 and c == 0:
                    continue
                target = full_xyz[:, r::k, c::k]  # (3, nr, nc): this offset in every block
                nr, nc = target.shape[1:]
                # the block's corners: its own working pixel, the next row's and column's
                corners = [(0, 0)] + ([(1, 0)] if r else []) + ([(0, 1)] if c else []) + ([(1, 1)] if r and c else [])
                labs = [lab_p[dr : dr + nr, dc : dc + nc] for dr, dc in corners]
                own = labs[0]
                agree = np.logical_and.reduce([lab == own for lab in labs])
                d2 = np.zeros((nr, nc), dtype=np.float32)
                for axis in range(3):
                    diff = target[axis] - xyz_p[axis, :nr, :nc]
                    d2 += diff * diff  # NaN where either is not finite
                # corners of one label, the own within a voxel: the nearest is of that
                # label and within a voxel too; corners all none: none whichever is nearest
                settled = agree & ((d2 <= far) | (own == 0))
                res = np.where(settled, own, 0)
                # the rest (corners of several labels, or the own beyond a voxel): the
                # nearest corner, the first of equals, within a voxel
                ri, ci = np.nonzero(~settled)
                best_d2 = np.full(ri.shape[0], np.inf, dtype=np.float32)
                best_lab = np.zeros(ri.shape[0], dtype=lab_w.dtype)
                # gathers by flat index from the contiguous planes (take: several times
                # faster than indexing by (row, column) pairs), the pixels' own once
                at_work = ri * (ww + 1) + ci
                own_xyz = [np.take(full_xyz[axis].reshape(-1), (ri * k + r) * w + (ci * k + c)) for axis in range(3)]
                for dr, dc in corners:
                    at = at_work + (dr * (ww + 1) + dc)
                    d2c = np.zeros(ri.shape[0], dtype=np.float32)
                    for axis in range(3):
                        diff = own_xyz[axis] - np.take(xyz_p[axis].reshape(-1), at)
                        d2c += diff * diff
                    nearer = d2c < best_d2  # NaN compares False
                    best_d2[nearer] = d2c[nearer]
                    best_lab[nearer] = np.take(lab_p.reshape(-1), at[nearer])
                res[ri, ci] = np.where(best_d2 <= far, best_lab, 0)
                out[r::k, c::k] = res
        return out.reshape(-1)

    def to_full_nominal(self, seg: Segmentation, settings: SegmentSettings) -> Segmentation:
        """`to_full` within the nominal voxel (the grid was chosen from it)."""
        return self.to_full(seg, settings.voxel_m)

    def to_full(self, seg: Segmentation, voxel_m: float) -> Segmentation:
        """``seg`` (of the working grid) with its indices on the full frame: the table's,
        every object's and every excluded segment's pixels by `full_labels`; boxes,
        planes and edges as they were.
        The time it took (and the grid's making) is added to the timings: making to
        "filter", carrying back to "objects", both to "total"."""
        if self.stride == 1:
            return seg
        start = time.perf_counter()
        n_work = self.frame.n_points
        # what else carries frame indices: the segments set aside as no objects (issue
        # 37's exclusion step), where the Segmentation has them
        excluded = tuple(getattr(seg, "excluded", ()))
        parts = [*seg.objects, *excluded]
        lab = np.zeros(n_work, dtype=np.int32)  # 0 none, 1 table, 2 + j part j
        lab[seg.table_indices] = 1
        for j, part in enumerate(parts):
            lab[part.indices] = 2 + j
        full = self.full_labels(lab, voxel_m)
        table = np.flatnonzero(full == 1)
        labelled = np.flatnonzero(full >= 2)  # the parts' pixels: a small share of the frame
        order = labelled[np.argsort(full[labelled], kind="stable")]
        bounds = np.searchsorted(full[order], np.arange(2, len(parts) + 3))
        members = [order[bounds[j] : bounds[j + 1]].astype(np.int64) for j in range(len(parts))]
        objects = tuple(dataclasses.replace(o, indices=members[j]) for j, o in enumerate(seg.objects))
        more: dict[str, Any] = {}
        if excluded:
            n_obj = len(seg.objects)
            more["excluded"] = tuple(dataclasses.replace(e, indices=members[n_obj + j]) for j, e in enumerate(excluded))
        timings = dict(seg.timings_s)
        mapped = time.perf_counter() - start
        if "filter" in timings:
            timings["filter"] += self.made_s
        if "objects" in timings:
            timings["objects"] += mapped
        if "total" in timings:
            timings["total"] += self.made_s + mapped
        return dataclasses.replace(
            seg, n_points=self.full.n_points, table_indices=table, objects=objects, timings_s=timings, **more
        )
