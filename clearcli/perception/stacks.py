"""Stage 3b''' (ours, not in the thesis): split off an object standing on another's top.

A small box or can standing on a tray or a flat box meets the lower top in a concave
seam that LCCP should keep apart. It does not always: a supervoxel at the foot of the
small object holds some of its side and some of the lower top, its normal and centroid
a blend of both, and its adjacency to the side face then passes as convex; one such
adjacency joins the two objects. The tops tell them apart: a horizontal face standing
centimetres above a larger horizontal face of the same segment, and lying inside it
(the lower top spreads around the foot of the upper object). The steps stage cannot
see this (no line separates a top from the top around it), nor can the planar cuts
(the seam closes around the small object).

Per segment:
1. its top patches (supervoxels whose normal is within ``step_max_tilt_deg`` of the
   table's, at their mean height), grouped into levels wherever consecutive heights
   differ by at least ``step_min_m``;
2. for a lower level L of at least ``min_object_area_m2`` and a higher level U: the
   candidate upper object is every voxel of the segment more than half a step above L,
   connected over the voxel adjacency (through such voxels) to U's top voxels;
3. accepted when at least ``_MIN_INSIDE`` of the candidate lies within the convex hull
   of L's top voxels in the table plane (a voxel's width of slack), and both the
   candidate and the rest hold at least ``cut_min_side_m2``. One object's two levels
   do not pass: a bowl's or a mug's inside bottom lies inside its walls, not the walls
   inside the bottom; a box beside a lower box stands outside the lower top (the steps
   stage's case);
4. the candidate becomes a segment of its own; repeated while some level splits off.

The other way round, LCCP sometimes cuts the LOWER object in two around the upper one's
foot (the top on either side of a can standing at a box's edge, joined only through
blended patches at the can's foot). Two touching segments that both hold a top at the
height the upper object stands at (within ``step_min_m``), and that the upper object
stands on (its foot inside the hull of their tops), are one object: `join_supports`.

It runs first of the refinements, on LCCP's segments (the planar cuts would otherwise
cut the lower object in two along the upper one's side), and like them hands back whole
supervoxels: each goes to the side holding most of its voxels, so the patch at the
upper object's foot, mostly lower top, stays with the lower object.
"""

from __future__ import annotations

import numpy as np

from clearcli.perception.context import RefineContext, top_patches
from clearcli.perception.graph import components, dense_labels
from clearcli.perception.lccp import join_pairs

# share of the candidate upper object that must stand within the lower top's hull
_MIN_INSIDE = 0.9
# a stack of one diameter (its lower top a crescent): the share of the candidate within
# the hull of the lower object's body, and of the crescent outside the candidate's hull.
# Chosen on uois_image_0002's soup can on a tin (0.895 and 1.0: the can's side
# overhangs the tin's by a few millimetres in places); a mug's or a bowl's floor lies
# all within its walls (0 outside)
_MIN_IN_BODY = 0.8
_MIN_OUTSIDE = 0.9
# ... and the crescent hugs the upper object: that share of it within _HUG_M of the
# upper object's hull (a stack of about one diameter; a lying torch's handle, a lower
# top beside a taller part of one object, reaches farther: 0.44 within 5 cm on
# gqcnn_primesense_0, the tin's crescent 0.97 within 3 cm, all within 5)
_HUG_M = 0.04
# ... and the lower top is a crescent, not a whole face: its voxels' area at most this
# share of the lower body's hull (0.26 for the tin; a lower box beside a taller one
# shows its whole top, 0.76 in fixtures/two_touching_boxes.pcd; the rule above takes a
# true stack on a whole lower top)
_MAX_CRESCENT = 0.4


def _levels(h: np.ndarray, min_step_m: float) -> np.ndarray:
    """Level index of each height: sorted heights split where consecutive ones differ by
    at least ``min_step_m``."""
    order = np.argsort(h)
    breaks = np.concatenate([[0], (np.diff(h[order]) >= min_step_m).astype(np.int64)])
    level = np.empty(h.size, dtype=np.int64)
    level[order] = np.cumsum(breaks)
    return level


def _inside_hull(xy: np.ndarray, hull_xy: np.ndarray, slack_m: float) -> np.ndarray:
    """(N,) are the points ``xy`` within ``slack_m`` of the convex hull of ``hull_xy``?"""
    from scipy.spatial import ConvexHull, QhullError

    try:
        hull = ConvexHull(hull_xy)
    except (QhullError, ValueError):
        return np.zeros(xy.shape[0], dtype=bool)
    # hull.equations rows (a, b, c): a x + b y + c <= 0 inside, (a, b) a unit normal
    signed = xy @ hull.equations[:, :2].T + hull.equations[:, 2]
    return (signed <= slack_m).all(axis=1)


def _hull_area(xy: np.ndarray) -> float:
    """The area of the convex hull of ``xy`` (N, 2) in m^2, 0 when there is none."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        return float(ConvexHull(xy).volume)  # a 2D hull's "volume" is its area
    except (QhullError, ValueError):
        return 0.0


class _Reach:
    """The connected components of the ``allowed`` voxels (V,) over ``edges`` (both ends
    allowed), numbered over those voxels alone: worked out once for every seed that
    grows through the same voxels (not once per seed over all the frame's voxels)."""

    def __init__(self, allowed: np.ndarray, edges: np.ndarray) -> None:
        self.nodes = np.flatnonzero(allowed)
        self.local = np.full(allowed.size, -1, dtype=np.int64)
        self.local[self.nodes] = np.arange(self.nodes.size)
        keep = allowed[edges[:, 0]] & allowed[edges[:, 1]]
        self.comp = components(self.nodes.size, self.local[np.compress(keep, edges, axis=0)])
        self.size = allowed.size

    def component(self, seeds: np.ndarray) -> np.ndarray:
        """(V,) the allowed voxels reachable from the voxels ``seeds`` (indices) through
        allowed voxels."""
        at = self.local[seeds]
        reached = np.isin(self.comp, np.unique(self.comp[at[at >= 0]]))
        out = np.zeros(self.size, dtype=bool)
        out[self.nodes[reached]] = True
        return out


def separate_stacks(seg_of_sv: np.ndarray, ctx: RefineContext) -> np.ndarray:
    """The stage (supervoxel level): (S,) segment of every supervoxel after the objects
    standing on a lower top are split off (`stack_splits`) and the tops they stand on
    joined (`join_supports`), 0..G-1."""
    sv = ctx.sv
    seg_of_voxel = join_supports(stack_splits(seg_of_sv[sv.voxel_label], ctx), ctx)
    # back to supervoxels, each to the segment of most of its voxels: the patch at the
    # upper object's foot, mostly lower top, stays with the lower object
    n_seg = int(seg_of_voxel.max()) + 1
    n_sv = sv.centroids.shape[0]
    # the (supervoxel, segment) counts by one bincount of a joint key, not np.add.at
    votes = np.bincount(sv.voxel_label * n_seg + seg_of_voxel, minlength=n_sv * n_seg).reshape(n_sv, n_seg)
    return dense_labels(votes.argmax(axis=1))


def _may_split(seg: np.ndarray, ctx: RefineContext) -> np.ndarray:
    """(G,) bool: segments whose top patches lie at two levels or more (`_levels`), for
    all segments at once: the others cannot split. Each patch's mean height is the sum
    `stack_splits` works out (`context.top_patches`), so the test is its own, exactly."""
    n_seg = int(seg.max()) + 1
    s_sorted, h_sorted, _ = top_patches(seg, ctx)
    step = (s_sorted[1:] == s_sorted[:-1]) & (np.diff(h_sorted) >= ctx.settings.step_min_m)
    out = np.zeros(n_seg, dtype=bool)
    out[s_sorted[1:][step]] = True
    return out


def stack_splits(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
    """(V,) segment of every voxel after splitting off objects standing on a lower top
    of their segment, 0..G-1."""
    settings, sv, voxel_height, voxel_edges = ctx.settings, ctx.sv, ctx.voxel_height, ctx.vox.edges
    seg = np.asarray(seg_of_voxel, dtype=np.int64).copy()
    if seg.size == 0 or voxel_edges.shape[0] == 0:
        return seg
    xy = ctx.voxel_xy
    top = ctx.voxel_is_top
    min_level_vox = ctx.size.min_object_voxels_unrounded
    min_side_vox = ctx.size.min_side_voxels_stacks
    # only segments with two top levels can split: edges within a segment, once
    same = seg[voxel_edges[:, 0]] == seg[voxel_edges[:, 1]]
    # rows by a mask with np.compress: several times faster than boolean indexing of rows
    edges_in = np.compress(same, voxel_edges, axis=0)
    next_label = int(seg.max()) + 1
    pending = np.unique(seg).tolist()
    # a segment with one level of tops is never split, nor changed by another's split
    # (a split relabels voxels of the segment split): those are skipped without a pass
    # over the frame's voxels each, most of a cluttered table's segments
    may_split = _may_split(seg, ctx)
    while pending:
        s = pending.pop()
        if s < may_split.size and not may_split[s]:
            continue
        members = seg == s
        tops = np.flatnonzero(members & top)
        if tops.size < 2:
            continue
        patch = dense_labels(sv.voxel_label[tops])
        n_vox = np.bincount(patch)
        h_patch = np.bincount(patch, weights=voxel_height[tops]) / n_vox
        level_of_patch = _levels(h_patch, settings.step_min_m)
        n_levels = int(level_of_patch.max()) + 1
        if n_levels < 2:
            continue
        level = level_of_patch[patch]  # per top voxel
        level_vox = np.bincount(level, minlength=n_levels)
        level_h = np.bincount(level, weights=voxel_height[tops], minlength=n_levels) / np.maximum(level_vox, 1)
        split = None
        for lo in range(n_levels - 1):
            if level_vox[lo] < min_level_vox:
                continue
            above = members & (voxel_height > level_h[lo] + 0.5 * settings.step_min_m)
            lower_xy = xy[tops[level == lo]]
            reach = _Reach(above, edges_in)
            for hi in range(n_levels - 1, lo, -1):
                cand = reach.component(tops[level == hi])
                n_cand = int(cand.sum())
                if n_cand < min_side_vox or int(members.sum()) - n_cand < min_side_vox:
                    continue
                cand_xy = np.compress(cand, xy, axis=0)
                inside = _inside_hull(cand_xy, lower_xy, ctx.size.voxel_m)
                if inside.mean() >= _MIN_INSIDE:
                    split = cand
                    break
                # a stack of one diameter: the lower top shows only as a crescent
                # around the upper object's foot, too thin to hold it; the lower
                # object's body (all of the segment at and below the lower top) does,
                # and the crescent lies outside the upper object (a bowl's or a mug's
                # inside bottom lies within its walls instead)
                body = members & ~above & ~cand
                in_body = _inside_hull(cand_xy, np.compress(body, xy, axis=0), ctx.size.voxel_m)
                crescent_out = ~_inside_hull(lower_xy, cand_xy, 0.0)
                if (
                    in_body.mean() >= _MIN_IN_BODY
                    and crescent_out.mean() >= _MIN_OUTSIDE
                    and _inside_hull(lower_xy, cand_xy, _HUG_M).mean() >= _MIN_OUTSIDE
                    and level_vox[lo] * ctx.size.voxel_m**2 <= _MAX_CRESCENT * _hull_area(np.compress(body, xy, axis=0))
                ):
                    split = cand
                    break
            if split is not None:
                break
        if split is None:
            continue
        seg[split] = next_label
        edges_in = np.compress(seg[edges_in[:, 0]] == seg[edges_in[:, 1]], edges_in, axis=0)
        pending += [s, next_label]  # either may hold another stack
        next_label += 1
    return dense_labels(seg)


def join_supports(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
    """(V,) segment of every voxel after joining touching segments that are pieces of
    the one top another object stands on (module docstring), 0..G-1."""
    settings, voxel_height, voxel_edges = ctx.settings, ctx.voxel_height, ctx.vox.edges
    seg = np.asarray(seg_of_voxel, dtype=np.int64)
    n_seg = int(seg.max()) + 1 if seg.size else 0
    if n_seg < 3 or voxel_edges.shape[0] == 0:
        return seg
    xy = ctx.voxel_xy
    top = ctx.voxel_is_top
    a, b = seg[voxel_edges[:, 0]], seg[voxel_edges[:, 1]]
    cross = a != b
    a, b = a[cross], b[cross]
    # the touching pairs (lower, higher) distinct by one integer key each (np.unique of
    # rows sorts a structured view, several times slower)
    key = np.unique(np.minimum(a, b) * n_seg + np.maximum(a, b))
    touching = set(zip((key // n_seg).tolist(), (key % n_seg).tolist(), strict=True))
    neighbours: dict[int, set[int]] = {}
    for x, y in touching:
        neighbours.setdefault(x, set()).add(y)
        neighbours.setdefault(y, set()).add(x)
    foot = np.full(n_seg, np.inf)
    np.minimum.at(foot, seg, voxel_height)
    min_level_vox = ctx.size.min_object_voxels_unrounded
    joined: list[tuple[int, int]] = []

    for upper in range(n_seg):
        h = foot[upper]
        if not np.isfinite(h) or h <= settings.standing_max_m or upper not in neighbours:
            continue  # stands on the table, or touches nothing
        # the top voxels at the foot's height, counted for every segment at once (one
        # pass over the voxels per upper object, not one per neighbour)
        at_foot = top & (np.abs(voxel_height - h) <= settings.step_min_m)
        at_foot_vox = np.bincount(seg[at_foot], minlength=n_seg)
        near = [s for s in sorted(neighbours[upper]) if int(at_foot_vox[s]) >= min_level_vox]
        for i, s1 in enumerate(near):
            for s2 in near[i + 1 :]:
                if (s1, s2) not in touching:
                    continue
                level = at_foot & np.isin(seg, (s1, s2))
                inside = _inside_hull(np.compress(seg == upper, xy, axis=0), xy[level], ctx.size.voxel_m)
                if inside.mean() >= _MIN_INSIDE:
                    joined.append((s1, s2))
    return join_pairs(seg, joined, n_seg)
