"""The refinements after LCCP, as a list of stages with one signature.

Each stage is one function of its module, ``(segments, ctx) -> segments``: the segment
of every voxel (or of every supervoxel, for a stage flagged ``per_supervoxel``) and one
`RefineContext` (context.py: the frame, the voxels, the supervoxels, the table plane,
the settings, the frame's `SegmentSize`, and what several stages derive from them,
worked out once).
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
  seams      touching pieces across a smooth, convex seam (seams.py)     voxel level
  learned    touching pieces a trained model finds one object (learned.py) voxel level
  boundary   voxels on a boundary moved to the segment whose colour they have
             (boundary.py)                                               voxel level
Before the supervoxels, `edges.py` cuts the voxel adjacency at depth discontinuities
of the pixel grid (stage "edges", organized frames only): it changes the graph every
later step walks, so it runs on the voxels, not on segments.
Supervoxel-level stages see one segment per supervoxel (the voxel labels are constant
within a supervoxel until the first voxel-level stage; they come first).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from clearcli.perception import (
    boundary,
    colors,
    cuts,
    fragments,
    learned,
    occlusion,
    rims,
    rings,
    seams,
    stacks,
    steps,
    vessels,
)
from clearcli.perception.clock import Clock
from clearcli.perception.context import RefineContext
from clearcli.settings.segment import SegmentSettings

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
    Stage("seams", lambda s: s.seam_join, seams.join_smooth_seams),
    Stage("learned", lambda s: s.learned_join, learned.join_learned),
    Stage("boundary", lambda s: s.boundary_refine, boundary.move_boundary_voxels),
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
