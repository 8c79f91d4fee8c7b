"""Stage 3b': planar cuts through concave seams inside LCCP segments, after Constrained
Planar Cuts (Schoeler, Papon and Woergoetter, CVPR 2015), vectorised and simplified.

LCCP joins two touching objects whenever a single convex path connects them, e.g. two
boxes whose front faces lie in one plane: the flat front faces join them although the
lower box's top meets the taller box in a concave seam. CPC cuts such a segment with a
plane through its concave adjacencies, and keeps the cut when the adjacencies the plane
crosses are mostly concave.

Here (per round, every segment at once):
1. seams: adjacencies LCCP does not merge (concave, or failing its sanity check: two
   patches side by side, which is how a front face beside a lower box's top looks)
   whose normals differ by at least ``cut_concave_deg``. Of these, RISING seams are a
   top face (normal within ``cut_max_tilt_deg`` of the table's) against a side face
   whose patch reaches at least ``cut_min_rise_m`` out of the other's plane
   (`seam_rise`): a wall standing on a floor. The odd patch straddling a box's convex
   edge also fails LCCP's checks, but stays behind both faces' planes.
2. candidate planes through every rising seam (x_i, n_i) - (x_j, n_j) inside a segment,
   at its midpoint, VERTICAL (normal in the table plane: objects standing on the table
   touch along vertical planes; stacked ones LCCP separates already), with normal the
   in-table direction of n_i, of n_j (the seam lies in the side face: the taller box's
   side above the lower box's top) or of the crease n_i x n_j (the taller box's side is
   seen edge-on, so only its front face meets the lower top, and the cut runs across
   the crease).
3. for each candidate, the adjacencies of its segment whose supervoxels lie on opposite
   sides of the plane, weighted by how squarely the plane cuts them (|d . n|, CPC's
   directional weighting); score = rising seams / all, where convex creases weigh
   1 + ``cut_crease_weight`` and non-rising seams nothing (noise either way). Accepted
   when score >= ``cut_min_score``, the plane crosses at least ``cut_min_explained`` of
   the segment's rising seams (a seam left whole is a concavity of the object itself:
   a bowl, a handle), at least ``cut_min_flat_share`` of its other crossings are flat
   (normals within ``cut_flat_deg``: touching objects meet in seams and coplanar faces,
   a plane through one object crosses its curves), at least ``cut_min_concave_edges``
   seams, and leaves both sides at least ``cut_min_side_m2`` and LCCP's smallest
   segment (else the side would merge straight back).
4. the best accepted candidate of each segment splits its supervoxels by side; repeat
   up to ``cut_max_rounds`` times; pieces are then the connected components, small
   pieces join their largest neighbour (LCCP's rule).
"""

from __future__ import annotations

import numpy as np

from clearcli.perception.context import RefineContext
from clearcli.perception.lccp import EdgeShape, convex_edges, edge_shape, rejoin_pieces
from clearcli.perception.size import SegmentSize
from clearcli.perception.supervoxels import Supervoxels
from clearcli.settings.segment import SegmentSettings


def _unit(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = np.linalg.norm(v, axis=-1)
    return v / np.maximum(n, 1e-12)[..., None], n


def concave_adjacencies(sv: Supervoxels, settings: SegmentSettings, size: SegmentSize | None = None) -> np.ndarray:
    """(A,) bool: seams, adjacencies LCCP does not merge (concave, or failing its sanity
    or smoothness check) whose normals are at least ``cut_concave_deg`` apart; a small
    angle is a noisy flat patch, not a seam. ``size``: as for `lccp.convex_edges`."""
    if sv.edges.shape[0] == 0:
        return np.zeros(0, dtype=bool)
    convex, angle = _convex_and_angle(sv, settings, size)
    return ~convex & (angle >= settings.cut_concave_deg)


def _convex_and_angle(
    sv: Supervoxels, settings: SegmentSettings, size: SegmentSize | None, shape: EdgeShape | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(A,) LCCP's merge verdict (`lccp.convex_edges`) and (A,) the angle (degrees)
    between the normals of each adjacency: a seam is what LCCP does not merge, a crease
    what it does, each with its normals at least ``cut_concave_deg`` apart. ``shape``:
    `lccp.edge_shape` of these ``sv``, ``settings`` and ``size``, when the caller has it
    (`RefineContext.sv_edge_shape`, LCCP's own: issue 39)."""
    shape = shape if shape is not None else edge_shape(sv, settings, size)
    return convex_edges(sv, settings, size, shape=shape), shape.normal_angle


def seam_rise(
    sv: Supervoxels, voxel_centroids: np.ndarray, edges: np.ndarray, voxels_by_sv: np.ndarray | None = None
) -> np.ndarray:
    """(K,) how far (m) either patch of each adjacency in ``edges`` reaches out of the
    other's plane, towards its normal: the largest (x_v - x_j) . n_j over the voxels v
    of i, and the same the other way round.

    Patches meeting in a convex crease stay behind each other's planes; a wall standing
    on a floor rises out of the floor's plane. The odd patch straddling a box's edge
    fails LCCP's sanity check with both faces, like a seam does, but stays behind
    both planes (a few mm of noise).

    ``voxels_by_sv``: the voxels by supervoxel (``np.argsort(sv.voxel_label,
    kind="stable")``, `RefineContext.voxels_by_sv`), when the caller has it: the sort
    was half of a call, and three stages call this on one frame."""
    lab = sv.voxel_label
    n_sv = sv.centroids.shape[0]
    order = np.argsort(lab, kind="stable") if voxels_by_sv is None else voxels_by_sv
    count = np.bincount(lab, minlength=n_sv)
    start = np.cumsum(count) - count
    out = np.full(edges.shape[0], -np.inf)
    for a, b in ((0, 1), (1, 0)):
        i, j = edges[:, a], edges[:, b]
        reps = count[i]
        k = np.repeat(np.arange(edges.shape[0]), reps)
        offset = np.arange(int(reps.sum())) - np.repeat(np.cumsum(reps) - reps, reps)
        v = order[start[i][k] + offset]
        jk = j[k]
        # rows by index: np.take is several times faster than a[idx] (the same rows)
        dist = np.einsum(
            "ij,ij->i",
            np.take(voxel_centroids, v, axis=0) - np.take(sv.centroids, jk, axis=0),
            np.take(sv.normals, jk, axis=0),
        )
        np.maximum.at(out, k, dist)
    return out


def candidate_planes(sv: Supervoxels, edges: np.ndarray, up: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertical candidate planes through the adjacencies ``edges`` (K, 2): (points (C, 3),
    unit normals (C, 3), index into ``edges`` of the adjacency each came from (C,))."""
    xi, xj = sv.centroids[edges[:, 0]], sv.centroids[edges[:, 1]]
    ni, nj = sv.normals[edges[:, 0]], sv.normals[edges[:, 1]]
    dirs = np.stack([ni, nj, np.cross(ni, nj)], axis=1)  # (K, 3, 3)
    dirs, _ = _unit(dirs)
    flat = dirs - np.einsum("kcj,j->kc", dirs, up)[..., None] * up
    flat, length = _unit(flat)
    # only directions mostly in the table plane: the projection of a near-vertical one
    # is noise (the normal of a top face, a crease along the table's normal)
    ok = length >= 0.5
    k, c = np.nonzero(ok)
    return ((xi + xj) / 2)[k], flat[k, c], k


def planar_cuts(
    seg: np.ndarray,
    ctx: RefineContext,
    trace: list[dict[str, np.ndarray]] | None = None,
) -> np.ndarray:
    """The stage (supervoxel level): (S,) segment of every supervoxel after the cuts,
    0..G-1 (``seg`` from LCCP). ``trace``, when given, receives a dict per round with
    every candidate's figures (for choosing the thresholds)."""
    settings, size, sv, up = ctx.settings, ctx.size, ctx.sv, ctx.up
    seg = np.asarray(seg, dtype=np.int64).copy()
    e = sv.edges
    if e.shape[0] == 0 or seg.size == 0:
        return seg
    # `concave_adjacencies`, and the convex creases below, from one `convex_edges`
    convex, angle = _convex_and_angle(sv, settings, size, ctx.sv_edge_shape)
    concave = ~convex & (angle >= settings.cut_concave_deg)
    if not concave.any():
        return seg
    d_unit, _ = _unit(sv.centroids[e[:, 0]] - sv.centroids[e[:, 1]])

    # convex creases (a box's edge between its top and its front) count extra against a
    # cut: a plane along a box's edge crosses the odd patch straddling the edge, whose
    # adjacencies fail LCCP's checks like a seam's
    crease = convex & (angle >= settings.cut_concave_deg)
    penalty = 1.0 + settings.cut_crease_weight * crease
    # a side smaller than LCCP's small segments would only rejoin its neighbour
    min_side_vox = size.min_side_voxels
    # seams of a top face (normal near the table's) against a side face (normal near the
    # table plane): where a lower object's top meets a taller one's side
    up_cos = np.abs(sv.normals @ up)
    top = up_cos >= np.cos(np.radians(settings.cut_max_tilt_deg))
    side_face = up_cos <= np.sin(np.radians(settings.cut_max_tilt_deg))
    top_side = (top[e[:, 0]] & side_face[e[:, 1]]) | (side_face[e[:, 0]] & top[e[:, 1]])
    rising = np.zeros_like(concave)
    # both patches of a seam at least a quarter of a seed cell (a 1.5 cm square at the
    # defaults): the few voxels of a side at a small object's foot, left in the segment
    # of the top it stands on, are not a wall to cut along
    min_patch = 0.25 * size.seed_voxels
    pick = concave & top_side & (np.minimum(sv.n_voxels[e[:, 0]], sv.n_voxels[e[:, 1]]) >= min_patch)
    # rows by a mask: np.compress, several times faster than boolean indexing of rows
    rising[pick] = (
        seam_rise(sv, ctx.vox.centroids, np.compress(pick, e, axis=0), ctx.voxels_by_sv) >= settings.cut_min_rise_m
    )
    cut_any = False
    for _ in range(settings.cut_max_rounds):
        inside = seg[e[:, 0]] == seg[e[:, 1]]
        # planes only through seams where one patch rises out of the other's plane
        seeds = np.flatnonzero(inside & rising)
        if seeds.size == 0:
            break
        p0, normal, src = candidate_planes(sv, e[seeds], up)
        if p0.shape[0] == 0:
            break
        cand_seg = seg[e[seeds[src], 0]]  # (C,)
        # sides of every supervoxel for every candidate: (C, S); a few hundred each way
        side = (sv.centroids @ normal.T).T > np.einsum("cj,cj->c", p0, normal)[:, None]
        in_seg = seg[None, :] == cand_seg[:, None]
        ie = np.flatnonzero(inside)
        ea, eb = e[ie, 0], e[ie, 1]
        crossed = (side[:, ea] != side[:, eb]) & (seg[ea][None, :] == cand_seg[:, None])
        w = np.abs(normal @ d_unit[ie].T) * crossed  # (C, E_in)
        # seams that are not rising (the odd patches along an edge) say nothing either way
        total = (w * (penalty * ~(concave & ~rising))[ie][None, :]).sum(axis=1)
        score = (w * rising[ie][None, :]).sum(axis=1) / np.maximum(total, 1e-12)
        n_concave = (crossed & concave[ie][None, :]).sum(axis=1)
        # the share of its segment's rising seams the plane crosses
        seam_seg = seg[e[ie, 0]][rising[ie]]
        seams_in_seg = (seam_seg[None, :] == cand_seg[:, None]).sum(axis=1)
        explained = (crossed & rising[ie][None, :]).sum(axis=1) / np.maximum(seams_in_seg, 1)
        # the share of flat adjacencies among its other crossings
        plain = crossed & ~concave[ie][None, :]
        flat = plain & (angle[ie] < settings.cut_flat_deg)[None, :]
        n_plain = plain.sum(axis=1)
        flat_share = np.where(n_plain > 0, flat.sum(axis=1) / np.maximum(n_plain, 1), 1.0)  # none: all seams
        vox_pos = (side & in_seg) @ sv.n_voxels
        vox_all = in_seg @ sv.n_voxels
        sv_pos = (side & in_seg).sum(axis=1)
        sv_all = in_seg.sum(axis=1)
        good = (
            (score >= settings.cut_min_score)
            & (explained >= settings.cut_min_explained)
            & (flat_share >= settings.cut_min_flat_share)
            & (n_concave >= settings.cut_min_concave_edges)
            & (vox_pos >= min_side_vox)
            & (vox_all - vox_pos >= min_side_vox)
            & (np.minimum(sv_pos, sv_all - sv_pos) >= settings.min_segment_supervoxels)
        )
        if trace is not None:
            trace.append(
                dict(
                    seg=seg.copy(),
                    cand_seg=cand_seg,
                    score=score,
                    n_concave=n_concave,
                    n_crossed=crossed.sum(axis=1),
                    vox_pos=vox_pos,
                    vox_all=vox_all,
                    side=side,
                    good=good,
                    normal=normal,
                    p0=p0,
                    crossed=crossed,
                    ie=ie,
                    rising=rising,
                    explained=explained,
                    flat_share=flat_share,
                )
            )
        if not good.any():
            break
        # the best candidate of each segment (ties: the more concave adjacencies cut)
        cand = np.flatnonzero(good)
        order = np.lexsort((-n_concave[cand], -score[cand], cand_seg[cand]))
        cand = cand[order]
        first = np.ones(cand.size, dtype=bool)
        first[1:] = cand_seg[cand][1:] != cand_seg[cand][:-1]
        next_label = int(seg.max()) + 1
        for c in cand[first].tolist():
            move = in_seg[c] & side[c]
            seg[move] = next_label
            next_label += 1
        cut_any = True
    if not cut_any:
        return seg
    # a side may fall apart into pieces; pieces are connected components, small ones
    # rejoin their largest neighbour as after LCCP
    return rejoin_pieces(seg, e, size.min_segment_supervoxels, sv.n_voxels, size.min_segment_voxels)
