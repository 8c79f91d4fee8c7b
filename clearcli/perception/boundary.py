"""Stage 3g (ours, issue 37; off by default): a supervoxel on a segment's boundary moves
to the neighbouring segment whose surface it continues.

A piece of an object can end up in a neighbour's segment: LCCP joins it there across a
convex adjacency, or a small piece joins its largest neighbour (LCCP's rule), or a later
stage draws the line a supervoxel off. Such a supervoxel touches the segment it belongs
to more convexly than the one it is in. The rule, for every supervoxel lying whole in
one segment (a supervoxel a voxel-level stage cut in two was cut on purpose) and
touching another segment:

- its convex adjacencies (LCCP's own test, `lccp.convex_edges`, the same colour-aware
  tolerance, without the sanity criterion: that one rejects patches lying side by side,
  which is what a piece and the surface it continues often are) to each neighbouring
  segment and to its own, counting only supervoxels that lie whole in one segment;
- it moves to the neighbouring segment it has the most convex adjacencies with, when
  these outnumber its convex adjacencies within its own segment by at least
  ``boundary_min_lead``;
- one round, all moves at once, and never more than half of a segment's voxels (a
  boundary moves; a segment is not taken apart by it).

Why off (the choose data, issue 37). On the foreign choose frames the supervoxels left in
a neighbour's segment (38 of them at a segment boundary, each mostly one labelled object
held by a segment of another) are convex to the segment they are in and concave to
their own object's in 30 of 38 (LCCP's criterion), and none of the cues at hand tells
them from the 191 boundary supervoxels that are where they belong: convex adjacencies
with the sanity criterion off (this rule) take 5 of the 38 and 1 of the 191, all 5 on
uois frames that were exactly right already; colour (supervoxel Lab against the
neighbours', or the segments' means), normals and range-continuous pixel adjacency take
as many wrong ones as right ones. With the stage on, the choose part stays 59 of 89
objects exactly right (merged 6, split 17, missed 7, spurious 0), and the voxels of
labelled objects held by another object's segment go from 3961 to 3940 (32 fewer on
uois_image_0002 and _0006, 11 more on gqcnn_primesense_0).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from clearcli.perception.context import RefineContext
from clearcli.perception.graph import dense_labels
from clearcli.perception.lccp import convex_edges


def move_boundary_supervoxels(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
    """The stage (voxel level): (V,) segment of every voxel, 0..G-1, with supervoxels on
    a boundary moved to the segment they continue (module docstring)."""
    seg = np.asarray(seg_of_voxel, dtype=np.int64).copy()
    sv, settings = ctx.sv, ctx.settings
    n_sv = int(sv.centroids.shape[0])
    if seg.size == 0 or sv.edges.shape[0] == 0:
        return seg
    relaxed = dataclasses.replace(settings, sanity_criterion=False)
    sv_lab = ctx.sv_lab if settings.lccp_color_delta > 0 else None
    e = np.compress(convex_edges(sv, relaxed, ctx.size, sv_lab, ctx.vox), sv.edges, axis=0)
    label = sv.voxel_label
    n_seg = int(seg.max()) + 1
    lo = np.full(n_sv, n_seg, dtype=np.int64)
    hi = np.full(n_sv, -1, dtype=np.int64)
    np.minimum.at(lo, label, seg)
    np.maximum.at(hi, label, seg)
    whole = lo == hi  # the supervoxel lies in one segment
    # both directions of every convex adjacency between two whole supervoxels
    a = np.concatenate([e[:, 0], e[:, 1]])
    b = np.concatenate([e[:, 1], e[:, 0]])
    both = whole[a] & whole[b]
    a, b = a[both], b[both]
    if a.size == 0:
        return dense_labels(seg)
    # convex adjacencies of each supervoxel per segment: (supervoxel, segment) keys
    key, count = np.unique(a * n_seg + lo[b], return_counts=True)
    v, target = key // n_seg, key % n_seg
    at_home = target == lo[v]
    home = np.zeros(n_sv, dtype=np.int64)
    home[v[at_home]] = count[at_home]
    cand = ~at_home & (count >= home[v] + settings.boundary_min_lead)
    if not cand.any():
        return dense_labels(seg)
    # per supervoxel, the segment with the most convex adjacencies (ties: the lower one)
    v, target, count = v[cand], target[cand], count[cand]
    order = np.lexsort((target, -count, v))
    v, target = v[order], target[order]
    first = np.r_[True, v[1:] != v[:-1]]
    v, target = v[first], target[first]
    # a segment loses at most half of its voxels
    seg_vox = np.bincount(seg, minlength=n_seg)
    lost = np.bincount(lo[v], weights=sv.n_voxels[v], minlength=n_seg)
    ok = lost[lo[v]] <= 0.5 * seg_vox[lo[v]]
    dest = np.full(n_sv, -1, dtype=np.int64)
    dest[v[ok]] = target[ok]
    moved = dest[label]
    return dense_labels(np.where(moved >= 0, moved, seg))
