"""Stage 3f' (ours, issue 37): join two pieces of one object across a smooth, convex seam.

On noisy depth (an Asus Xtion's, a RealSense's at a metre) a flat dark object (a spring
clamp's arm, a bracket lying on a board) comes out as two segments that continue each
other: a depth edge or a strip of lost pixels cut the voxel adjacency LCCP would have
joined them across (a spring clamp's arms: one supervoxel adjacency left across a seam
of 6 mm), or a later stage cut them apart and the seam holds no step. Such a
pair is joined when, across its seam (the voxels of both within `learned.GAP_M`):

- most supervoxel adjacencies across it are convex by LCCP's own criterion (at least
  ``seam_join_min_convex`` of them, and at least one: a pair with none has no seam to
  judge); two objects touching meet at a concave seam;
- it does not rise: the median of how far either patch reaches out of the other's plane
  (`cuts.seam_rise`) is under ``cut_min_rise_m``, what the planar cuts call a rising
  seam (one object lying on or against another rises out of its surface);
- their tops stand at one height (less than ``step_min_m`` apart, the step steps.py
  splits at): an object lying against a taller one's side meets it convexly at the
  taller one's edge;
- their colours differ by less than ``color_split_delta`` (the colour split's measure):
  two objects of one height side by side with a convex seam between them are told
  apart by colour, and colors.py keeps such pieces apart already.

On the training pairs it was chosen on (training/join_pairs.csv as extracted before this
stage existed, since re-extracted from today's stages: mOSD learn, the foreign choose
frames, renders of the choose seeds, each with two noisier copies) the rule takes 5 pairs, all
of one object (a spring clamp's two arms, a bracket's two halves, two faces of a render's
box: convex 0.73-1.0, rising 1.5-3.5 mm); the nearest pairs of two objects it leaves
have colours 28 dE apart, or a convex share of 0.65 (mOSD learn25 with 4 mm of extra
noise); on the foreign choose frames the only other pair with a convex seam, tops at
one height and one colour rises 17.8 mm (two objects in a heap, gqcnn_phoxi_dexnet4_0).
Never joined, as in learned.py: two segments the colour rule keeps apart, directly or
through a chain of joins.
"""

from __future__ import annotations

import numpy as np

from clearcli.perception.context import RefineContext
from clearcli.perception.lccp import join_pairs
from clearcli.perception.learned import FEATURES, PairFeatures, greedy_joins, pair_features

_CONVEX = FEATURES.index("convex_share")
_COLOUR = FEATURES.index("colour_de")
_TOP_STEP = FEATURES.index("top_step_mm")
_RISE = FEATURES.index("rise_mm")


def smooth_seams(
    feats: PairFeatures, min_convex: float, max_rise_m: float, max_step_m: float, max_colour_de: float
) -> np.ndarray:
    """(P,) bool: the pairs of ``feats`` whose seam is smooth and convex (module doc)."""
    x = feats.x
    n_adj = feats.seam_adjacencies if feats.seam_adjacencies is not None else np.zeros(x.shape[0], np.int64)
    return np.asarray(
        (x[:, _CONVEX] >= min_convex)
        & (n_adj >= 1)
        & (x[:, _RISE] < max_rise_m * 1000.0)
        & (x[:, _TOP_STEP] < max_step_m * 1000.0)
        & (x[:, _COLOUR] < max_colour_de)
        & ~feats.apart,
        dtype=bool,
    )


def seam_joins(feats: PairFeatures, chosen: np.ndarray, n_seg: int) -> list[tuple[int, int]]:
    """The chosen pairs to join, most convex first (ties by pair), never two segments
    apart, directly or through a chain of joins."""
    return greedy_joins(feats, feats.x[:, _CONVEX], chosen, n_seg)


def join_smooth_seams(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
    """The stage (voxel level): touching pairs across a smooth, convex seam joined."""
    seg = np.asarray(seg_of_voxel, dtype=np.int64)
    n_seg = int(seg.max()) + 1 if seg.size else 0
    feats = pair_features(seg, ctx)
    if feats.pairs.shape[0] == 0:
        return seg
    s = ctx.settings
    chosen = smooth_seams(feats, s.seam_join_min_convex, s.cut_min_rise_m, s.step_min_m, s.color_split_delta)
    pairs = seam_joins(feats, chosen, n_seg)
    if not pairs:
        return seg
    return join_pairs(seg, np.asarray(pairs, dtype=np.int64), n_seg)
