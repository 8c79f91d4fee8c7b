"""What every refinement stage after LCCP reads: one `RefineContext` a frame.

The stages (stacks.py, cuts.py, ... fragments.py, listed in refine.py) each take
``(segments, ctx)``; they import this module for its type, and refine.py imports them to
list them, so the context lives here, apart from both. segment.py makes it in LCCP's
step, which reads its voxel heights and supervoxel colours first (the same numbers:
worked out once a frame).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from clearcli.io.frames import Frame
from clearcli.perception.flat import cielab
from clearcli.perception.lccp import EdgeShape, edge_shape
from clearcli.perception.size import SegmentSize
from clearcli.perception.supervoxels import Supervoxels, VoxelCloud
from clearcli.perception.table import plane_basis
from clearcli.perception.types import TablePlane
from clearcli.settings.segment import SegmentSettings


def top_patches(seg: np.ndarray, ctx: RefineContext) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every top patch (a segment's top voxels in one supervoxel), ordered by segment,
    then by height: (its segment, its mean height, its top voxels) each, as `stacks` and
    `steps` work them out per segment (the same voxels added in the same index order, one
    bincount over every segment's top voxels). Empty under two top voxels."""
    tops = np.flatnonzero(ctx.voxel_is_top)
    if tops.size < 2:
        return np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0, dtype=np.int64)
    n_sv = ctx.sv.centroids.shape[0]
    key, patch = np.unique(seg[tops] * n_sv + ctx.sv.voxel_label[tops], return_inverse=True)
    n_vox = np.bincount(patch)
    h = np.bincount(patch, weights=ctx.voxel_height[tops]) / n_vox
    seg_of_patch = key // n_sv
    order = np.lexsort((h, seg_of_patch))  # by segment, then height
    return seg_of_patch[order], h[order], n_vox[order]


def by_label(labels: np.ndarray, n_labels: int) -> np.ndarray:
    """(N,) the indices ordered by their label (0..n_labels-1), each label's in index
    order: ``np.argsort(labels, kind="stable")``, of int16 labels when they fit (NumPy
    sorts those by radix, the same order in about half the time of int64's merge sort)."""
    if 0 < n_labels <= np.iinfo(np.int16).max:
        return np.argsort(labels.astype(np.int16), kind="stable")
    return np.argsort(labels, kind="stable")


def _mean_lab(sums: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """(G, 3) CIELAB of each group's mean colour from its RGB sums (G, 3) and point
    counts (G,): `flat.group_lab`'s arithmetic (an empty group counts one point)."""
    return cielab(np.clip(sums / np.maximum(counts, 1)[:, None], 0, 255).round().astype(np.uint8))


@dataclass(frozen=True)
class RefineContext:
    """Everything a refinement stage reads: what LCCP ran on, and what several stages
    derive from it (cached: worked out once, by the first stage that asks)."""

    frame: Frame  # the whole frame: stages on the pixel grid read it
    organized: bool  # the frame's pixel grid is usable
    vox: VoxelCloud  # voxels of the points above the table
    sv: Supervoxels
    plane: TablePlane
    settings: SegmentSettings  # as given: thresholds in metres and degrees
    size: SegmentSize  # the sizes in voxels (fitted to an unorganized cloud's density)
    point_index: np.ndarray | None = None  # (M,) frame index of each point above the table
    color_used: bool = False  # the frame's colour is usable (segment.color_state)

    @cached_property
    def up(self) -> np.ndarray:
        """(3,) the table's unit normal."""
        return self.plane.normal / np.linalg.norm(self.plane.normal)

    @cached_property
    def voxel_height(self) -> np.ndarray:
        """(V,) height of each voxel centroid above the table."""
        return self.plane.height_of(self.vox.centroids)

    @cached_property
    def sv_height(self) -> np.ndarray:
        """(S,) height of each supervoxel centroid above the table."""
        return self.plane.height_of(self.sv.centroids)

    @cached_property
    def plane_basis(self) -> np.ndarray:
        """(2, 3) two unit axes of the table plane: voxels and normals in it are ``@ .T``."""
        return plane_basis(self.up)

    @cached_property
    def voxel_xy(self) -> np.ndarray:
        """(V, 2) the voxels in the table plane."""
        return self.vox.centroids @ self.plane_basis.T

    @cached_property
    def sv_xy(self) -> np.ndarray:
        """(S, 2) the supervoxel centroids in the table plane."""
        return self.sv.centroids @ self.plane_basis.T

    @cached_property
    def sv_normals_xy(self) -> np.ndarray:
        """(S, 2) the supervoxel normals' part in the table plane."""
        return self.sv.normals @ self.plane_basis.T

    @cached_property
    def sv_is_top(self) -> np.ndarray:
        """(S,) top faces: supervoxels within step_max_tilt_deg of level."""
        return np.abs(self.sv.normals @ self.up) >= np.cos(np.radians(self.settings.step_max_tilt_deg))

    @cached_property
    def sv_is_wall(self) -> np.ndarray:
        """(S,) supervoxels that are not a top face (tilted more than step_max_tilt_deg)."""
        return np.abs(self.sv.normals @ self.up) < np.cos(np.radians(self.settings.step_max_tilt_deg))

    @cached_property
    def voxel_is_top(self) -> np.ndarray:
        """(V,) voxels of a top face (`sv_is_top`)."""
        return self.sv_is_top[self.sv.voxel_label]

    @cached_property
    def point_colors(self) -> np.ndarray | None:
        """(M, 3) RGB of the points above the table, or None without usable colour."""
        if not self.color_used or self.point_index is None or self.frame.colors is None:
            return None
        return np.take(self.frame.colors, self.point_index, axis=0)  # rows by index: take is faster than a[idx]

    @cached_property
    def voxel_rgb_sum(self) -> tuple[np.ndarray, np.ndarray] | None:
        """((V, 3) each voxel's points' RGB summed, (V,) its point count), or None without
        usable colour: one pass over the points for both `voxel_lab` and `sv_lab` (sums
        of integers, exact in float64 in any order: a supervoxel's sum over its voxels'
        sums is its sum over its points). The count is ``vox.counts``, voxelize's
        ``np.bincount`` of ``vox.point_voxel``: the same array, not counted again (issue
        39: 0.03-0.10 ms a frame, 2-4 % of LCCP's step)."""
        colors = self.point_colors
        if colors is None:
            return None
        n_vox = self.vox.centroids.shape[0]
        pv = self.vox.point_voxel
        sums = np.stack(
            [np.bincount(pv, weights=colors[:, c].astype(np.float64), minlength=n_vox) for c in range(3)], axis=1
        )
        return sums, self.vox.counts

    @cached_property
    def voxel_lab(self) -> np.ndarray | None:
        """(V, 3) CIELAB of each voxel's mean colour, or None without usable colour
        (`flat.group_lab` of the points by voxel: the same numbers)."""
        if self.voxel_rgb_sum is None:
            return None
        sums, counts = self.voxel_rgb_sum
        return _mean_lab(sums, counts)

    @cached_property
    def sv_lab(self) -> np.ndarray | None:
        """(S, 3) CIELAB of each supervoxel's mean colour, or None without usable colour
        (`flat.group_lab` of the points by supervoxel: the same numbers, from the voxels'
        exact sums instead of a second pass over the points). LCCP's colour cue reads it
        too (segment._lccp, in place of a group_lab pass of its own: issue 39, the colour
        splits 62.3 -> 15.2 ms summed over mOSD's 50 frames with `sv_edge_shape`, LCCP's
        step unchanged, by benchmarks/ab.py)."""
        if self.voxel_rgb_sum is None:
            return None
        sums, counts = self.voxel_rgb_sum
        n_sv, label = self.sv.centroids.shape[0], self.sv.voxel_label
        sv_sums = np.stack([np.bincount(label, weights=sums[:, c], minlength=n_sv) for c in range(3)], axis=1)
        return _mean_lab(sv_sums, np.bincount(label, weights=counts, minlength=n_sv))

    @cached_property
    def sv_edge_shape(self) -> EdgeShape:
        """`lccp.edge_shape` of the supervoxel adjacencies: the angles LCCP's convexity
        reads, and the planar cuts and the colour splits read again (the same ``sv``,
        settings and sizes: the same numbers; issue 39: the planar cuts 45.7 -> 24.6 ms
        summed over mOSD's 50 frames, by benchmarks/ab.py)."""
        return edge_shape(self.sv, self.settings, self.size)

    @cached_property
    def voxels_by_sv(self) -> np.ndarray:
        """(V,) the voxels ordered by supervoxel, each one's in index order (a stable
        argsort of ``sv.voxel_label``; `cuts.seam_rise` of three stages reads it)."""
        return by_label(self.sv.voxel_label, self.sv.centroids.shape[0])

    @cached_property
    def first_voxel(self) -> np.ndarray:
        """(S,) one voxel of each supervoxel (to read a supervoxel's segment)."""
        n_sv = self.sv.centroids.shape[0]
        first = np.zeros(n_sv, dtype=np.int64)
        order = np.arange(self.sv.voxel_label.size)[::-1]
        first[self.sv.voxel_label[::-1]] = order
        return first
