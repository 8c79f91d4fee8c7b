"""The refinements after LCCP, as a list of stages with one signature.

Each stage is one function of its module, ``(segments, ctx) -> segments``: the segment
of every voxel (or of every supervoxel, for a stage flagged ``per_supervoxel``) and one
`RefineContext` (the frame, the voxels, the supervoxels, the table plane, the settings,
the frame's `SegmentSize`, and what several stages derive from them, worked out once).
`refine()` runs `STAGES` in order, times each, and skips a stage that is switched off,
or that needs the pixel grid on an unorganized cloud (so the result is the result with
that stage off). A new refinement is a module with such a function, one entry here and
its switch in settings/segment.py.

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

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from clearcli.io.frames import Frame
from clearcli.perception import colors, cuts, fragments, occlusion, rims, rings, stacks, steps, vessels
from clearcli.perception.clock import Clock
from clearcli.perception.size import SegmentSize
from clearcli.perception.supervoxels import Supervoxels, VoxelCloud
from clearcli.perception.types import TablePlane
from clearcli.settings.segment import SegmentSettings


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
        from clearcli.perception.table import plane_basis

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
        return self.frame.colors[self.point_index]

    @cached_property
    def voxel_lab(self) -> np.ndarray | None:
        """(V, 3) CIELAB of each voxel's mean colour, or None without usable colour."""
        if self.point_colors is None:
            return None
        return colors.group_lab(self.vox.point_voxel, self.point_colors, self.vox.centroids.shape[0])

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
    # sees one segment per supervoxel, and hands one back (the voxel labels are constant
    # within a supervoxel until the first voxel-level stage: these come first)
    per_supervoxel: bool = False
    needs_grid: bool = False  # the pixel grid of an organized frame


STAGES: tuple[Stage, ...] = (
    Stage("stacks", lambda s: s.stack_split, stacks.separate_stacks, per_supervoxel=True),
    Stage("cuts", lambda s: s.planar_cuts, cuts.planar_cuts, per_supervoxel=True),
    Stage("occlusion", lambda s: s.occlusion_merge, occlusion.merge_occluded, per_supervoxel=True, needs_grid=True),
    Stage("colors", lambda s: s.color_split, colors.split_by_colour, per_supervoxel=True),
    Stage("steps", lambda s: s.step_split, steps.step_splits),
    Stage("rims", lambda s: s.rim_merge, rims.join_rims),
    Stage("rings", lambda s: s.ring_merge, rings.merge_rings),
    Stage("vessels", lambda s: s.vessel_rebuild, vessels.rebuild_vessels),
    Stage("fragments", lambda s: s.fragment_join_m > 0, fragments.rejoin_fragments),
)


def refine(
    seg_of_voxel: np.ndarray,
    ctx: RefineContext,
    clock: Clock | None = None,
    stages: tuple[Stage, ...] = STAGES,
) -> np.ndarray:
    """Run the enabled stages in order; each one's seconds go to ``clock`` by its name."""
    clock = clock if clock is not None else Clock()
    for stage in stages:
        with clock(stage.name):
            if stage.enabled(ctx.settings) and (ctx.organized or not stage.needs_grid):
                if stage.per_supervoxel:
                    seg_of_sv = stage.run(seg_of_voxel[ctx.first_voxel], ctx)
                    seg_of_voxel = np.asarray(seg_of_sv)[ctx.sv.voxel_label]
                else:
                    seg_of_voxel = stage.run(seg_of_voxel, ctx)
    return seg_of_voxel
