"""Stage 3b'''' (ours, not in the thesis): colour splits a segment where one object
lies on or against another.

LCCP joins two patches when any chain of convex or nearly flat adjacencies links them:
objects heaped in a bin, a package lying across a clamp, a toy in a blister on a card,
a soup can standing on a tin of its diameter are one segment each. Colour tells them
apart, but colour alone also cuts every printed label, logo and shadow. So colour only
proposes where a seam may run, and geometry decides whether it is one:

1. each supervoxel's mean colour (CIELAB, from its points);
2. within a segment, the adjacencies whose two supervoxels differ by at least
   ``color_split_delta`` (CIE76 dE) and are no convex crease (a box's edge: its top
   and its sides often differ in colour, and belong together) are cut; the segment
   falls into colour pieces;
3. two pieces are apart when both hold at least the smallest object's area and the
   adjacencies between them RISE: the median over them of how far either patch reaches
   out of the other's plane (`cuts.seam_rise`) is at least ``color_split_min_rise_m``.
   One object lying on or leaning against another rises out of its surface by its own
   thickness; a print, a label or a shadow lies in the surface it is printed on;
4. the pieces then join back, the pairs sharing the most adjacencies first (ties by
   piece number), except where a join would put two pieces that are apart into one
   segment; a piece apart from all its neighbours stays a segment of its own;
5. a segment need not be connected (occlusion.py joins the parts of one object seen
   either side of a nearer one): a group that touches no other and is apart from none
   joins the largest group of its segment of a similar mean colour (``_PART_DE``);
6. a group split off its segment that touches a group of another segment of its own
   colour along a seam that does not rise joins that group (`_to_own_object`): a piece
   of a small object that LCCP left with the box it stands on.

Measured (pieces of the 45 mOSD learn frames and of the foreign choose frames,
`benchmarks/foreign.py`): between two objects the median rise is 11-31 mm for 11 of
the 19 pairs of different objects; between pieces of one object at most 9.4 mm, except
a 47-voxel rim piece of a can (17.9 mm); on mOSD no pair of pieces rises more than
3.8 mm. A concave seam alone (the rule before, a quarter of the adjacencies at least
20 degrees concave) also holds between a drill and its battery, a mug and its
handle, a can and its rim: it decides nothing here.

Runs when the frame has usable colour (segment.color_state) and ``color_split`` is on.
"""

from __future__ import annotations

import numpy as np

from clearcli.perception.context import RefineContext
from clearcli.perception.cuts import seam_rise
from clearcli.perception.flat import group_lab
from clearcli.perception.graph import ApartSets
from clearcli.perception.lccp import EdgeShape, _angle_deg, join_pairs
from clearcli.perception.supervoxels import Supervoxels

# a convex crease (never cut by colour): normals this far apart
_CREASE_DEG = 30.0
# two parts of a segment that touch nowhere (occlusion.py joined them across a nearer
# object) stay one when their mean colours (CIELAB, voxel-weighted) differ by less than
# this: on the mOSD learn frames the two parts of one object seen either side of a
# nearer one differ by up to 26.7 dE (learn29: light and shade on a box); on the
# foreign choose frames the parts of a heap's segment that are two objects 50-56 dE
_PART_DE = 40.0


def supervoxel_lab(sv: Supervoxels, point_voxel: np.ndarray, colors: np.ndarray) -> np.ndarray:
    """(S, 3) CIELAB of each supervoxel's mean colour (``colors`` (M, 3) uint8 of the
    points whose voxel is ``point_voxel``)."""
    return group_lab(sv.voxel_label[point_voxel], colors, sv.centroids.shape[0])


def split_by_colour(seg_of_sv: np.ndarray, ctx: RefineContext) -> np.ndarray:
    """The stage (supervoxel level): `color_splits` with the frame's colour, or the
    segments as they are without usable colour."""
    lab = ctx.sv_lab  # `supervoxel_lab` of the frame's points
    if lab is None:
        return seg_of_sv
    s = ctx.settings
    return color_splits(
        seg_of_sv,
        ctx.sv,
        ctx.vox.centroids,
        lab,
        s.color_split_delta,
        s.color_split_min_rise_m,
        ctx.size.min_object_voxels,
        ctx.voxels_by_sv,
        ctx.sv_edge_shape,
    )


def _pieces(
    seg_of_sv: np.ndarray, sv: Supervoxels, lab: np.ndarray, min_delta: float, shape: EdgeShape | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(piece of every supervoxel (S,), the colour cuts between two pieces (A,) bool);
    ``shape``: as for `color_splits`."""
    e = sv.edges
    a, b = e[:, 0], e[:, 1]
    same = seg_of_sv[a] == seg_of_sv[b]
    if shape is not None:
        convex, normal_angle = shape.convex, shape.normal_angle
    else:
        n1, n2 = sv.normals[a], sv.normals[b]
        d = sv.centroids[a] - sv.centroids[b]
        convex, normal_angle = _angle_deg(d, n1) - _angle_deg(d, n2) <= 0, _angle_deg(n1, n2)
    crease = convex & (normal_angle >= _CREASE_DEG)
    cut = same & (np.linalg.norm(lab[a] - lab[b], axis=1) >= min_delta) & ~crease
    n_sv = seg_of_sv.shape[0]
    # rows by a mask: np.compress, several times faster than boolean indexing of rows
    piece = join_pairs(np.arange(n_sv), np.compress(same & ~cut, e, axis=0), n_sv)
    return piece, cut & (piece[a] != piece[b])


def color_splits(
    seg_of_sv: np.ndarray,
    sv: Supervoxels,
    voxel_centroids: np.ndarray,
    lab: np.ndarray,
    min_delta: float,
    min_rise_m: float,
    min_voxels: int,
    voxels_by_sv: np.ndarray | None = None,
    shape: EdgeShape | None = None,
) -> np.ndarray:
    """(S,) segment per supervoxel after the colour splits (module doc), 0..G-1;
    ``voxel_centroids`` (V, 3) of the voxels ``sv.voxel_label`` numbers;
    ``voxels_by_sv``: as for `seam_rise`; ``shape``: `lccp.edge_shape` of ``sv``, when
    the caller has it (`RefineContext.sv_edge_shape`: LCCP's convexity and normal
    angles, the same numbers as worked out here; issue 39)."""
    e = sv.edges
    if e.shape[0] == 0:
        return seg_of_sv
    piece, between = _pieces(seg_of_sv, sv, lab, min_delta, shape)
    n_piece = int(piece.max()) + 1
    if not between.any() and n_piece == np.unique(seg_of_sv).size:
        # no colour cut and every segment in one piece: nothing to split. A segment in
        # parts that touch nowhere (occlusion.py) is still judged by step 5 without a cut
        return seg_of_sv
    size = np.bincount(piece, weights=sv.n_voxels, minlength=n_piece)
    ci = np.flatnonzero(between)
    rise = seam_rise(sv, voxel_centroids, e[ci], voxels_by_sv)
    pa, pb = piece[e[ci, 0]], piece[e[ci, 1]]
    lo, hi = np.minimum(pa, pb), np.maximum(pa, pb)
    pairs, inverse = np.unique(lo * n_piece + hi, return_inverse=True)
    total = np.bincount(inverse, minlength=pairs.size)
    order = np.lexsort((rise, inverse))  # by pair, then by rise: the median of each pair
    start = np.cumsum(total) - total
    median = 0.5 * (rise[order[start + (total - 1) // 2]] + rise[order[start + total // 2]])
    p_lo, p_hi = pairs // n_piece, pairs % n_piece
    apart = (median >= min_rise_m) & (size[p_lo] >= min_voxels) & (size[p_hi] >= min_voxels)
    # join back, most shared adjacencies first, never two pieces apart into one
    sets = ApartSets(n_piece, zip(p_lo[apart].tolist(), p_hi[apart].tolist()))
    for k in np.lexsort((p_hi, p_lo, -total)).tolist():
        if not apart[k]:
            sets.join(int(p_lo[k]), int(p_hi[k]))
    # a segment need not be connected (occlusion.py joins the pieces of an object a
    # nearer one cuts apart): a group apart from nothing joins the largest group of its
    # segment whose mean colour is within _PART_DE of its own (the far side of one
    # object); a group apart from another, or of another colour, stays (in a heap, what
    # shows on either side of an object lying across another is seldom one object)
    seg_of_piece = np.zeros(n_piece, dtype=np.int64)
    seg_of_piece[piece] = seg_of_sv
    roots = np.array([sets.root(p) for p in range(n_piece)])
    group_size = np.bincount(roots, weights=size, minlength=n_piece)
    heads = np.flatnonzero(roots == np.arange(n_piece))
    kept: dict[int, list[int]] = {}
    weight = sv.n_voxels.astype(np.float64)
    group_lab = (
        np.stack([np.bincount(roots[piece], weights=weight * lab[:, c], minlength=n_piece) for c in range(3)], axis=1)
        / np.maximum(group_size, 1e-12)[:, None]
    )
    for r in heads[np.lexsort((heads, -group_size[heads], seg_of_piece[heads]))].tolist():
        mine = kept.setdefault(int(seg_of_piece[r]), [])
        near = [k for k in mine if np.linalg.norm(group_lab[k] - group_lab[r]) < _PART_DE]
        if sets.kept_apart(r) or not near:
            mine.append(r)
        else:
            sets.join_roots(near[0], r)
    # pieces are inside one segment, and so are their pairs: no join crosses segments
    out = join_pairs(piece, np.asarray(sets.joined, dtype=np.int64).reshape(-1, 2), n_piece)
    return _to_own_object(out, seg_of_sv, sv, voxel_centroids, lab, min_delta, min_rise_m, voxels_by_sv)


def _to_own_object(
    out: np.ndarray,
    seg_of_sv: np.ndarray,
    sv: Supervoxels,
    voxel_centroids: np.ndarray,
    lab: np.ndarray,
    min_delta: float,
    min_rise_m: float,
    voxels_by_sv: np.ndarray | None = None,
) -> np.ndarray:
    """A group split off its segment (any but the segment's largest) that touches a group
    of another segment of its colour (mean CIELAB within ``min_delta``) along a seam that
    does not rise (median `seam_rise` under ``min_rise_m``) joins it, the one it shares
    most adjacencies with: it was a piece of that object, left in its neighbour's segment
    by LCCP (a small object's side joined to the box it stands on, its top apart)."""
    n_out = int(out.max()) + 1
    if n_out == int(seg_of_sv.max()) + 1:
        return out
    weight = sv.n_voxels.astype(np.float64)
    size = np.bincount(out, weights=weight, minlength=n_out)
    lab_sum = np.stack([np.bincount(out, weights=weight * lab[:, c], minlength=n_out) for c in range(3)], axis=1)
    mean_lab = lab_sum / np.maximum(size, 1e-12)[:, None]
    seg_of_out = np.zeros(n_out, dtype=np.int64)
    seg_of_out[out] = seg_of_sv
    # the largest group of each segment (ties: the lower number) stays where it is
    order = np.lexsort((np.arange(n_out), -size, seg_of_out))
    first = np.ones(n_out, dtype=bool)
    first[1:] = seg_of_out[order][1:] != seg_of_out[order][:-1]
    main = np.zeros(n_out, dtype=bool)
    main[order[first]] = True
    e = sv.edges
    ga, gb = out[e[:, 0]], out[e[:, 1]]
    cross = seg_of_sv[e[:, 0]] != seg_of_sv[e[:, 1]]
    moves = []
    for g in np.flatnonzero(~main).tolist():
        sel = np.flatnonzero(cross & ((ga == g) | (gb == g)))
        if sel.size == 0:
            continue
        other = np.where(ga[sel] == g, gb[sel], ga[sel])
        rise = seam_rise(sv, voxel_centroids, e[sel], voxels_by_sv)
        best, best_n = -1, 0
        for t in np.unique(other).tolist():
            mine = other == t
            flat = float(np.median(rise[mine])) < min_rise_m
            if flat and np.linalg.norm(mean_lab[g] - mean_lab[t]) < min_delta and int(mine.sum()) > best_n:
                best, best_n = t, int(mine.sum())
        if best >= 0:
            moves.append((best, g))
    if not moves:
        return out
    return join_pairs(out, np.asarray(moves, dtype=np.int64), n_out)
