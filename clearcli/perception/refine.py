"""The refinements after LCCP, as a list of stages with one signature.

Each stage takes the segment of every voxel and a `RefineContext` (the frame, the
voxels, the supervoxels, the table plane, the settings) and returns the segment of
every voxel. `segment()` runs `STAGES` in order, times each, and skips a stage that is
switched off, or that needs the pixel grid on an unorganized cloud (so the result is
the result with that stage off). A new refinement is a module and one entry here.

The stages, in order:
  stacks     an object standing on another's top (stacks.py)             supervoxel level
  cuts       planar cuts through rising seams (cuts.py; after CPC)      supervoxel level
  occlusion  pieces of one object cut apart by a nearer one (occlusion.py) supervoxel level,
                                                                         pixel grid
  colors     colour splits a segment along a concave seam (colors.py)    supervoxel level
  steps      two tops at two heights on either side of a line (steps.py)  voxel level
  rims       a container's inner and outer walls (rims.py)                voxel level
  rings      ... and those that do not touch: two arcs of one rim (rings.py) voxel level
  vessels    a container rebuilt from its rim, its wall taken back from what
             stands in it or leans on it (vessels.py)                    voxel level
  fragments  strips of a face seen edge-on, apart from their object (fragments.py) voxel level
Before the supervoxels, `edges.py` cuts the voxel adjacency at depth discontinuities
of the pixel grid (stage "edges", organized frames only): it changes the graph every
later step walks, so it runs on the voxels, not on segments.
Supervoxel-level stages see one segment per supervoxel (the voxel labels are constant
within a supervoxel until the first voxel-level stage; they come first).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import cached_property
from typing import Callable

import numpy as np

from clearcli.io.frames import Frame
from clearcli.settings.segment import SegmentSettings
from clearcli.perception.supervoxels import Supervoxels, VoxelCloud
from clearcli.perception.types import TablePlane


@dataclass(frozen=True)
class RefineContext:
    frame: Frame  # the whole frame: stages on the pixel grid read it
    organized: bool  # the frame's pixel grid is usable
    vox: VoxelCloud  # voxels of the points above the table
    sv: Supervoxels
    plane: TablePlane
    settings: SegmentSettings  # as given
    scaled: SegmentSettings  # as the supervoxels used them (fitted to an unorganized cloud's density)
    point_index: np.ndarray | None = None  # (M,) frame index of each point above the table
    color_used: bool = False  # the frame's colour is usable (segment.color_state)

    @cached_property
    def voxel_height(self) -> np.ndarray:
        """(V,) height of each voxel centroid above the table."""
        return self.plane.height_of(self.vox.centroids)

    @cached_property
    def plane_basis(self) -> np.ndarray:
        """(2, 3) two unit axes of the table plane: voxels and normals in it are ``@ .T``."""
        from clearcli.perception.table import plane_basis

        return plane_basis(self.plane.normal / np.linalg.norm(self.plane.normal))

    @cached_property
    def sv_is_wall(self) -> np.ndarray:
        """(S,) supervoxels that are not a top face (tilted more than step_max_tilt_deg)."""
        up = self.plane.normal / np.linalg.norm(self.plane.normal)
        return np.abs(self.sv.normals @ up) < np.cos(np.radians(self.settings.step_max_tilt_deg))

    @property
    def min_object_voxels(self) -> int:
        """The smallest object's visible area in voxels."""
        return max(1, int(self.settings.min_object_area_m2 / self.scaled.voxel_m**2))

    @cached_property
    def voxel_lab(self) -> np.ndarray | None:
        """(V, 3) CIELAB of each voxel's mean colour, or None without usable colour."""
        from clearcli.perception.colors import group_lab

        if not self.color_used or self.point_index is None or self.frame.colors is None:
            return None
        return group_lab(self.vox.point_voxel, self.frame.colors[self.point_index], self.vox.centroids.shape[0])

    @cached_property
    def first_voxel(self) -> np.ndarray:
        """(S,) one voxel of each supervoxel (to read a supervoxel's segment)."""
        n_sv = self.sv.centroids.shape[0]
        first = np.zeros(n_sv, dtype=np.int64)
        order = np.arange(self.sv.voxel_label.size)[::-1]
        first[self.sv.voxel_label[::-1]] = order
        return first


Run = Callable[[np.ndarray, RefineContext], np.ndarray]


@dataclass(frozen=True)
class Stage:
    name: str  # its key in the timings
    enabled: Callable[[SegmentSettings], bool]
    run: Run
    needs_grid: bool = False  # the pixel grid of an organized frame


def _per_supervoxel(fn: Callable[[np.ndarray, RefineContext], np.ndarray]) -> Run:
    """A supervoxel-level stage as a voxel-level one."""

    def run(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
        seg_of_sv = fn(seg_of_voxel[ctx.first_voxel], ctx)
        return np.asarray(seg_of_sv)[ctx.sv.voxel_label]

    return run


def _stacks(seg_of_sv: np.ndarray, ctx: RefineContext) -> np.ndarray:
    from clearcli.perception.stacks import join_supports, stack_splits

    args = (ctx.sv, ctx.vox.centroids, ctx.voxel_height, ctx.vox.edges, ctx.plane.normal, ctx.scaled)
    seg_of_voxel = join_supports(stack_splits(seg_of_sv[ctx.sv.voxel_label], *args), *args)
    # back to supervoxels, each to the segment of most of its voxels: the patch at the
    # upper object's foot, mostly lower top, stays with the lower object
    n_seg = int(seg_of_voxel.max()) + 1
    votes = np.zeros((ctx.sv.centroids.shape[0], n_seg), dtype=np.int64)
    np.add.at(votes, (ctx.sv.voxel_label, seg_of_voxel), 1)
    return np.unique(votes.argmax(axis=1), return_inverse=True)[1]


def _cuts(seg_of_sv: np.ndarray, ctx: RefineContext) -> np.ndarray:
    from clearcli.perception.cuts import planar_cuts

    return planar_cuts(seg_of_sv, ctx.sv, ctx.vox.centroids, ctx.plane.normal, ctx.scaled)


def _occlusion(seg_of_sv: np.ndarray, ctx: RefineContext) -> np.ndarray:
    from clearcli.perception.occlusion import merge_occluded

    s = ctx.settings
    min_vox = max(1, int(s.min_object_area_m2 / s.voxel_m**2))
    sv = ctx.sv
    return merge_occluded(
        seg_of_sv, sv.centroids, sv.normals, sv.edges, sv.n_voxels, ctx.frame.points, ctx.frame.shape,
        s.occlusion_max_gap_m, s.voxel_m, min_vox, ctx.plane.height_of(sv.centroids),
    )


def _colors(seg_of_sv: np.ndarray, ctx: RefineContext) -> np.ndarray:
    from clearcli.perception.colors import color_splits, supervoxel_lab

    if not ctx.color_used or ctx.point_index is None or ctx.frame.colors is None:
        return seg_of_sv
    s = ctx.settings
    lab = supervoxel_lab(ctx.sv, ctx.vox.point_voxel, ctx.frame.colors[ctx.point_index])
    min_vox = max(1, int(s.min_object_area_m2 / ctx.scaled.voxel_m**2))
    return color_splits(seg_of_sv, ctx.sv, lab, s.color_split_delta, min_vox)


def _steps(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
    from clearcli.perception.steps import step_splits

    return step_splits(seg_of_voxel, ctx.sv, ctx.vox.centroids, ctx.voxel_height, ctx.vox.edges, ctx.plane.normal, ctx.scaled)


def _rims(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
    from clearcli.perception.rims import merge_rims

    s = ctx.settings
    top = np.abs(ctx.sv.normals @ ctx.plane.normal) >= np.cos(np.radians(s.step_max_tilt_deg))
    return merge_rims(
        seg_of_voxel, ctx.vox.centroids, ctx.voxel_height, s.rim_tolerance_m, s.rim_contact_m,
        voxel_is_top=top[ctx.sv.voxel_label],
    )


def _rings(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
    from clearcli.perception.rings import merge_rings

    s, basis = ctx.settings, ctx.plane_basis
    return merge_rings(
        seg_of_voxel, ctx.vox.centroids @ basis.T, ctx.voxel_height, ctx.sv.voxel_label,
        ctx.sv.normals @ basis.T, ctx.sv.centroids @ basis.T, ctx.sv_is_wall, s.rim_tolerance_m,
        s.ring_max_radius_m, s.ring_max_residual, s.ring_min_cover_deg, ctx.min_object_voxels, s.ring_max_off_share,
    )


def _vessels(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
    from clearcli.perception.vessels import rebuild_vessels

    s, basis = ctx.settings, ctx.plane_basis
    return rebuild_vessels(
        seg_of_voxel, ctx.vox.centroids @ basis.T, ctx.voxel_height, ctx.vox.edges, ctx.sv.voxel_label,
        ctx.sv.normals @ basis.T, ctx.sv.centroids @ basis.T, ctx.sv_is_wall, s.rim_tolerance_m, s.ring_max_radius_m,
        ctx.min_object_voxels, s.standing_max_m, ctx.scaled.voxel_m, ctx.voxel_lab,
    )


def _fragments(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
    from clearcli.perception.fragments import join_fragments

    s = ctx.scaled
    up = ctx.plane.normal / np.linalg.norm(ctx.plane.normal)
    top = np.abs(ctx.sv.normals @ up) >= np.cos(np.radians(s.step_max_tilt_deg))
    min_segment_voxels = int(s.min_segment_supervoxels * (s.seed_m / s.voxel_m) ** 2)
    return join_fragments(
        seg_of_voxel, ctx.vox.centroids, ctx.vox.edges, top[ctx.sv.voxel_label], min_segment_voxels,
        ctx.settings.fragment_join_m,
    )


STAGES: tuple[Stage, ...] = (
    Stage("stacks", lambda s: s.stack_split, _per_supervoxel(_stacks)),
    Stage("cuts", lambda s: s.planar_cuts, _per_supervoxel(_cuts)),
    Stage("occlusion", lambda s: s.occlusion_merge, _per_supervoxel(_occlusion), needs_grid=True),
    Stage("colors", lambda s: s.color_split, _per_supervoxel(_colors)),
    Stage("steps", lambda s: s.step_split, _steps),
    Stage("rims", lambda s: s.rim_merge, _rims),
    Stage("rings", lambda s: s.ring_merge, _rings),
    Stage("vessels", lambda s: s.vessel_rebuild, _vessels),
    Stage("fragments", lambda s: s.fragment_join_m > 0, _fragments),
)


def refine(
    seg_of_voxel: np.ndarray,
    ctx: RefineContext,
    timings: dict[str, float],
    stages: tuple[Stage, ...] = STAGES,
) -> np.ndarray:
    """Run the enabled stages in order; each one's seconds go to ``timings[name]``."""
    for stage in stages:
        t0 = time.perf_counter()
        if stage.enabled(ctx.settings) and (ctx.organized or not stage.needs_grid):
            seg_of_voxel = stage.run(seg_of_voxel, ctx)
        timings[stage.name] = time.perf_counter() - t0
    return seg_of_voxel
