"""Stage 3b'''' (ours, not in the thesis): colour splits a segment where its geometry
already hints at two objects.

LCCP joins two patches when any chain of convex or nearly flat adjacencies links them:
a soup can standing on a tin of its diameter (their walls continue each other), a tin
on an eraser on a food container, two mugs side by side are one segment each, although
the seam between them is concave where it shows. Colour tells them apart, but colour
alone also cuts every printed label, logo and shadow. So colour only decides where a
seam runs that geometry has already put there:

1. each supervoxel's mean colour (CIELAB, from its points);
2. within a segment, the adjacencies whose two supervoxels differ by at least
   ``color_split_delta`` (CIE76 dE) and are no convex crease (a box's edge: its top
   and its sides often differ in colour, and belong together) are cut;
3. the segment falls into pieces along those cuts; two pieces stay apart only when at
   least ``_MIN_CONCAVE_SHARE`` of the adjacencies between them are concave (normals
   at least ``_CONCAVE_DEG`` apart: a seam between two objects, not a print on one
   surface) and each holds at least the smallest object's area; every other piece joins
   back the neighbour it shares most adjacencies with.

Runs when the frame has usable colour (segment.color_state) and ``color_split`` is on;
it is off by default: measured on mOSD, prints mislead it (settings/segment.py).
"""

from __future__ import annotations

import numpy as np

from clearcli.perception.context import RefineContext
from clearcli.perception.flat import group_lab
from clearcli.perception.lccp import _angle_deg, join_pairs
from clearcli.perception.supervoxels import Supervoxels

# a seam between two pieces: this share of the adjacencies between them are concave by
# this many degrees between their normals
_MIN_CONCAVE_SHARE = 0.25
_CONCAVE_DEG = 20.0
# a convex crease (never cut by colour): normals this far apart
_CREASE_DEG = 30.0


def supervoxel_lab(sv: Supervoxels, point_voxel: np.ndarray, colors: np.ndarray) -> np.ndarray:
    """(S, 3) CIELAB of each supervoxel's mean colour (``colors`` (M, 3) uint8 of the
    points whose voxel is ``point_voxel``)."""
    return group_lab(sv.voxel_label[point_voxel], colors, sv.centroids.shape[0])


def split_by_colour(seg_of_sv: np.ndarray, ctx: RefineContext) -> np.ndarray:
    """The stage (supervoxel level): `color_splits` with the frame's colour, or the
    segments as they are without usable colour."""
    if ctx.point_colors is None:
        return seg_of_sv
    lab = supervoxel_lab(ctx.sv, ctx.vox.point_voxel, ctx.point_colors)
    return color_splits(seg_of_sv, ctx.sv, lab, ctx.settings.color_split_delta, ctx.size.min_object_voxels)


def color_splits(
    seg_of_sv: np.ndarray, sv: Supervoxels, lab: np.ndarray, min_delta: float, min_voxels: int
) -> np.ndarray:
    """(S,) segment per supervoxel after the colour splits (module doc)."""
    e = sv.edges
    if e.shape[0] == 0:
        return seg_of_sv
    a, b = e[:, 0], e[:, 1]
    same = seg_of_sv[a] == seg_of_sv[b]
    n1, n2 = sv.normals[a], sv.normals[b]
    d = sv.centroids[a] - sv.centroids[b]
    angle = _angle_deg(n1, n2)
    convex = _angle_deg(d, n1) - _angle_deg(d, n2) <= 0
    concave = ~convex & (angle >= _CONCAVE_DEG)
    delta = np.linalg.norm(lab[a] - lab[b], axis=1)
    cut = same & (delta >= min_delta)
    if not cut.any():
        return seg_of_sv
    n_sv = seg_of_sv.shape[0]
    keep = same & ~cut
    piece = join_pairs(np.arange(n_sv), e[keep], n_sv)
    n_piece = int(piece.max()) + 1
    if n_piece == int(seg_of_sv.max()) + 1:
        return seg_of_sv
    size = np.bincount(piece, weights=sv.n_voxels, minlength=n_piece)
    pa, pb = piece[a[cut]], piece[b[cut]]
    lo, hi = np.minimum(pa, pb), np.maximum(pa, pb)
    key = lo * n_piece + hi
    pairs, inverse = np.unique(key, return_inverse=True)
    total = np.bincount(inverse, minlength=pairs.size)
    seam = np.bincount(inverse, weights=concave[cut].astype(np.float64), minlength=pairs.size)
    p_lo, p_hi = pairs // n_piece, pairs % n_piece
    apart = (seam >= _MIN_CONCAVE_SHARE * total) & (size[p_lo] >= min_voxels) & (size[p_hi] >= min_voxels)
    # pieces that stay apart from none of their neighbours, or are too small, join the
    # neighbour they share most adjacencies with; pieces apart from each other stay so
    join = np.zeros(pairs.size, dtype=bool)
    for p in range(n_piece):
        mine = (p_lo == p) | (p_hi == p)
        if not mine.any():
            continue
        if size[p] >= min_voxels and (mine & apart).any():
            continue
        cand = np.flatnonzero(mine)
        join[cand[np.argmax(total[cand])]] = True
    joined = join_pairs(piece, np.stack([p_lo[join], p_hi[join]], axis=1), n_piece)
    # never join across segments: a piece is inside one segment, and so are its pairs
    return joined
