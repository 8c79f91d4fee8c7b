"""Stage 3g (ours, issue 37): voxels on a segment's boundary move to the neighbouring
segment whose colour they have, onto a surface they continue.

Where two objects touch, the segments' boundary often runs a voxel or two off the
objects' (a strip of a toy left with the toy beside it): the supervoxels that straddle
the seam went whole to one side, and a Kinect's or a PrimeSense's colour is registered to
its depth to within a few pixels, so the colour cues of the stages before (colour
splits, LCCP's colour-aware tolerance) work on supervoxels, not on the voxels of the
seam. Each segment's colour is known well from all of its voxels; a voxel on the
boundary whose colour is clearly that of the neighbouring segment, and not its own's,
belongs there:

- the segments' colour models: each segment's mean CIELAB over its voxels (weighted by
  their points), taken once from the segments as they come (a model does not drift with
  the voxels it wins);
- a voxel adjacent (26-neighbourhood) to a voxel of another segment moves to the
  neighbouring segment whose mean is nearest its colour, when that one is nearer than
  its own segment's mean by more than ``boundary_color_margin_de`` (10 dE: twice the
  median colour step between adjacent voxels of one segment, 4.6 dE on the foreign
  choose frames and every 5th mOSD learn frame, so a voxel's own noise does not move it),
  across an adjacency whose two supervoxel normals are at most
  ``boundary_max_turn_deg`` (45, halfway to a face at right angles) apart: a voxel goes
  onto a surface it continues, not from a printed box's top onto the side of the box
  standing on it (mOSD learn17: the white patches of the lower box's print went to the
  white box on it, object IoU 0.890 -> 0.834, without this);
- ``boundary_rounds`` (2) rounds, all moves of a round at once: the boundary moves by
  at most two voxels (1 cm), the width of a seam's straddling supervoxels and of the
  colour's misregistration at a metre; with 4 rounds a spurious segment appeared on the
  choose part.

A frame without usable colour keeps its segments. The stage reads colour only when
another stage does (segment.color_state: the colour splits, on by default).

Chosen on the foreign choose frames and mOSD learn (issue 37): choose 59 -> 60 of 89
objects exactly right (gqcnn_primesense_4's dark grey toy; merged 6, spurious 0 either
way); margins 10-15 dE give 60, 8 dE 61; a turn of 30 degrees 59, 60 degrees 61 (learn17
0.890 / 0.973 -> 0.871 / 0.956 per object), none 61-62 (learn17 as above). mOSD all-50
F1 0.991 either way, per frame.

Tried before and not kept (the choose part stayed at 58-59 of 89): whole supervoxels
moved by LCCP's convexity (the pieces left in a neighbour's segment are convex to it and
concave to their own object's: 30 of 38 such supervoxels at a boundary; convexity
without the sanity criterion takes 5 of them and 1 of the 191 boundary supervoxels that
are right, all 5 on uois frames already right); a voxel judged by the colour of its
adjacent voxels on either side instead of the segments' means (inside a misplaced strip
its own side's neighbours are the strip itself, of its colour: little moves); only a
voxel farther from its own segment's mean than that segment's RMS colour spread (59:
what this stage mends lies within it); LCCP's small pieces sent to the neighbour they
share the most (convex) adjacencies with instead of the largest; pieces with no convex,
colour-close link to their segment's core moved to the neighbour they have one with.
"""

from __future__ import annotations

import numpy as np

from clearcli.perception.context import RefineContext
from clearcli.perception.graph import dense_labels


def segment_colours(seg: np.ndarray, lab: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """(G, 3) each segment's mean CIELAB over its voxels, weighted by ``weight`` (their
    points); a segment of no weight (not in ``seg``) is 0."""
    n_seg = int(seg.max()) + 1
    total = np.bincount(seg, weights=weight, minlength=n_seg)
    sums = np.stack([np.bincount(seg, weights=lab[:, c] * weight, minlength=n_seg) for c in range(3)], axis=1)
    return np.asarray(sums / np.maximum(total, 1e-12)[:, None])


def move_boundary_voxels(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
    """The stage (voxel level): (V,) segment of every voxel, 0..G-1, with the voxels on a
    boundary moved to the neighbouring segment whose colour they have (module docstring)."""
    seg = np.asarray(seg_of_voxel, dtype=np.int64).copy()
    lab = ctx.voxel_lab
    edges = ctx.vox.edges
    if lab is None or seg.size == 0 or edges.shape[0] == 0:
        return seg
    settings = ctx.settings
    mean = segment_colours(seg, lab, ctx.vox.counts.astype(np.float64))
    normal = ctx.sv.normals[ctx.sv.voxel_label]  # each voxel's supervoxel's normal
    min_cos = np.cos(np.radians(settings.boundary_max_turn_deg))
    # both directions of every voxel adjacency: (voxel, its neighbour)
    here = np.concatenate([edges[:, 0], edges[:, 1]])
    there = np.concatenate([edges[:, 1], edges[:, 0]])
    for _ in range(settings.boundary_rounds):
        across = seg[here] != seg[there]
        v, u = here[across], there[across]
        s = seg[u]
        if v.size == 0:
            break
        d_there = np.linalg.norm(lab[v] - mean[s], axis=1)
        d_home = np.linalg.norm(lab[v] - mean[seg[v]], axis=1)
        # nearer the neighbour's colour by the margin, and onto a surface the voxel
        # continues (a box's top does not go to the side of the box standing on it)
        turn_ok = np.einsum("ij,ij->i", normal[v], normal[u]) >= min_cos
        wins = (d_there + settings.boundary_color_margin_de < d_home) & turn_ok
        if not wins.any():
            break
        v, s, d_there = v[wins], s[wins], d_there[wins]
        # per voxel, the nearest neighbouring segment (ties: the lower one)
        order = np.lexsort((s, d_there, v))
        v, s = v[order], s[order]
        first = np.r_[True, v[1:] != v[:-1]]
        seg[v[first]] = s[first]
    return dense_labels(seg)
