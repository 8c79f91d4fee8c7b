"""Stage 3b'' (ours, not in the thesis): split a segment whose top faces stand at two
heights, side by side.

Two boxes standing face to face, one taller than the other, are often one LCCP segment:
their front faces continue each other, and the seam where the lower top meets the
taller side is a few supervoxels wide at best, too few for the planar cuts (cuts.py) to
be sure of. Their tops tell them apart plainly: two horizontal faces, centimetres apart
in height, lying on either side of a line in the table plane.

Per segment (every round, every segment):
1. its top patches: supervoxels whose normal is within ``step_max_tilt_deg`` of the
   table's, with their height above the table (a patch's mean: millimetre noise);
2. sorted by height, the largest gap between consecutive patches; a step when it is at
   least ``step_min_m`` and the tops below and above it each cover at least
   ``min_object_area_m2``;
3. the vertical plane that best separates the two tops' voxels in the table plane (90
   directions, every threshold, counted errors); accepted when at most
   ``step_max_error`` of the smaller top lies on the wrong side, not counting voxels
   within 1.5 voxels of the line (a top patch straddles the seam). One object's tops at two
   heights do not pass this: the inside bottom of a bowl or a mug is surrounded by its
   rim, so no line separates them;
4. every voxel of the segment goes to the side of the plane it is on (voxels, not
   supervoxels: a patch may straddle the seam); pieces are connected components, small
   ones rejoin a neighbour (LCCP's rule).
A step also needs one of its two tops to be the top of its side (`_ledges_only`,
``step_max_over_top_m``): a rough, rounded object shows level patches on its flanks.
"""

from __future__ import annotations

import numpy as np

from clearcli.perception.context import RefineContext, by_label, top_patches
from clearcli.perception.graph import dense_labels
from clearcli.perception.lccp import rejoin_pieces

_N_DIRECTIONS = 90  # 2 degree steps over half a turn
_SEAM_BAND_VOXELS = 1.5


def best_separating_line(xy: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, float, int]:
    """The line in the plane that best separates the points ``xy`` (N, 2) flagged
    ``upper`` from the rest: (unit normal (2,), offset, misclassified count); points
    with ``xy @ normal > offset`` are on the upper side."""
    angles = np.arange(_N_DIRECTIONS) * (np.pi / _N_DIRECTIONS)
    normals = np.stack([np.cos(angles), np.sin(angles)], axis=1)  # (D, 2)
    # one row per direction (D, N): every sort, sum and difference below runs along
    # contiguous rows (along the columns of (N, D) it was several times slower)
    proj = np.ascontiguousarray((xy @ normals.T).T)
    n_dir, n = proj.shape
    cols = np.arange(n_dir)
    order = np.argsort(proj, axis=1)
    n_up = int(upper.sum())
    n_low = n - n_up
    # threshold after the first k points (k = 0..N): below it lower, above it upper.
    # With u upper points below it, err_pos = u + (n_low - (k - u)) (upper side = larger
    # projections) and err_neg = (k - u) + (n_up - u): both from t = 2u - k, exact in
    # int32 (counts of at most N points), in two (D, N+1) arrays instead of six
    t = np.zeros((n_dir, n + 1), dtype=np.int32)
    np.cumsum(upper[order], axis=1, dtype=np.int32, out=t[:, 1:])
    t *= 2
    t -= np.arange(n + 1, dtype=np.int32)
    errs = np.minimum(t + n_low, n_up - t)
    # fewest errors; among directions with as few, the widest gap at the threshold (two
    # tops apart by a few millimetres are separated by many directions, and only the
    # widest-margin one runs along the seam)
    all_sorted = np.take_along_axis(proj, order, axis=1)
    k_best = np.argmin(errs, axis=1)
    e_best = errs[cols, k_best]
    fewest = e_best == e_best.min()
    # the best threshold of each direction among those with its fewest errors: widest gap
    masked_gaps = np.empty(errs.shape)
    masked_gaps[:, 0] = masked_gaps[:, -1] = -np.inf
    np.subtract(all_sorted[:, 1:], all_sorted[:, :-1], out=masked_gaps[:, 1:-1])
    masked_gaps[errs != e_best[:, None]] = -np.inf
    k_best = np.argmax(masked_gaps, axis=1)
    margin = masked_gaps[cols, k_best]
    d = int(np.argmax(np.where(fewest, margin, -np.inf)))
    kk = int(k_best[d])
    sorted_proj = all_sorted[d]
    if kk == 0:
        offset = float(sorted_proj[0]) - 1e-6
    elif kk == n:
        offset = float(sorted_proj[-1]) + 1e-6
    else:
        offset = float(sorted_proj[kk - 1] + sorted_proj[kk]) / 2
    normal = normals[d]
    if n_up - t[d, kk] < t[d, kk] + n_low:  # err_neg < err_pos
        normal, offset = -normal, -offset
    return normal, offset, int(errs[d, kk])


def _may_step(seg: np.ndarray, ctx: RefineContext, min_top_vox: float) -> np.ndarray:
    """(G,) bool: the segments whose top patches, ordered by height, have a gap of at
    least ``step_min_m`` with ``min_top_vox`` top voxels below it and above it, for all
    segments at once: only those can split. Each patch's mean height is the sum
    `step_splits` works out (`context.top_patches`); below a gap of more than 0 lie the
    patches not higher, in any order of equal heights: the test is its own, exactly."""
    n_seg = int(seg.max()) + 1
    out = np.zeros(n_seg, dtype=bool)
    s_sorted, h_sorted, n_sorted = top_patches(seg, ctx)
    if s_sorted.size == 0:
        return out
    total = np.bincount(s_sorted, weights=n_sorted, minlength=n_seg)[s_sorted]  # integers: exact in any order
    # top voxels up to each patch within its segment: a running count, less the counts
    # of the segments before (integers: exact in float64)
    run = np.cumsum(n_sorted)
    first = np.r_[True, s_sorted[1:] != s_sorted[:-1]]
    before = (run - n_sorted)[first]
    below = run - np.repeat(before, np.diff(np.r_[np.flatnonzero(first), s_sorted.size]))
    gap = np.diff(h_sorted)
    ok = (
        (s_sorted[1:] == s_sorted[:-1])
        & (gap >= ctx.settings.step_min_m)
        & (below[:-1] >= min_top_vox)
        & (total[:-1] - below[:-1] >= min_top_vox)
    )
    out[s_sorted[1:][ok]] = True
    return out


def _ledges_only(
    voxel_height: np.ndarray,
    members: np.ndarray,
    side: np.ndarray,
    tops: np.ndarray,
    is_upper: np.ndarray,
    max_over_m: float,
) -> bool:
    """Neither top is the top of its side of the line: each side's voxels (their 95th
    percentile of height) stand more than ``max_over_m`` above that side's top patches'
    mean height. Two objects' tops are the tops of their sides; the level patches on the
    flanks of one rounded, rough object (a loofah, a plush toy) are ledges with more of
    the object above them on both sides."""
    h_tops = voxel_height[tops]
    over_upper = np.percentile(voxel_height[members[side]], 95) - h_tops[is_upper].mean()
    over_lower = np.percentile(voxel_height[members[~side]], 95) - h_tops[~is_upper].mean()
    return bool(min(over_upper, over_lower) > max_over_m)


def step_splits(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
    """The stage: (V,) segment of every voxel after splitting at steps between tops,
    0..G-1.

    Works on voxels, not supervoxels: a supervoxel may straddle the seam (the two
    objects' end faces nearly in one plane), and the plane must cut through it. The
    supervoxels give the top patches (`RefineContext.voxel_is_top`)."""
    settings, size, sv, voxel_height = ctx.settings, ctx.size, ctx.sv, ctx.voxel_height
    seg = np.asarray(seg_of_voxel, dtype=np.int64).copy()
    if seg.size == 0:
        return seg
    xy = ctx.voxel_xy  # in the table plane, for the 2-D separation
    top = ctx.voxel_is_top
    min_top_vox = size.min_object_voxels_unrounded
    min_side_vox = size.min_side_voxels
    cut_any = False
    for _ in range(settings.cut_max_rounds):
        next_label = int(seg.max()) + 1
        cut_round = False
        # each segment's voxels in index order (what a mask over all voxels gave), from
        # one sort; a split this round relabels only the segment being split
        by_seg = by_label(seg, next_label)
        sorted_seg = seg[by_seg]
        starts = np.flatnonzero(np.r_[True, sorted_seg[1:] != sorted_seg[:-1]])
        ends = np.append(starts[1:], seg.size)
        # segments that cannot split are skipped (with a step of 0, equal heights
        # would leave which patch is below to argsort's order: all are tried then)
        may_step = _may_step(seg, ctx, min_top_vox) if settings.step_min_m > 0 else None
        for a, b in zip(starts.tolist(), ends.tolist(), strict=True):
            if may_step is not None and not may_step[sorted_seg[a]]:
                continue
            members = by_seg[a:b]
            tops = members[top[members]]
            if tops.size < 2:
                continue
            # top patches: the segment's part of each top supervoxel, at its mean height
            patch = dense_labels(sv.voxel_label[tops])
            n_vox = np.bincount(patch)
            h = np.bincount(patch, weights=voxel_height[tops]) / n_vox
            order = np.argsort(h)
            gaps = np.diff(h[order])
            below_vox = np.cumsum(n_vox[order])[:-1]
            above_vox = tops.size - below_vox
            ok = (gaps >= settings.step_min_m) & (below_vox >= min_top_vox) & (above_vox >= min_top_vox)
            if not ok.any():
                continue
            k = int(np.argmax(np.where(ok, gaps, -np.inf)))
            is_upper = np.isin(patch, order[k + 1 :])
            normal2, offset, _ = best_separating_line(xy[tops], is_upper)
            smaller = min(int(is_upper.sum()), int((~is_upper).sum()))
            # Misplaced top voxels within a voxel and a half of the line are the seam's
            # (a top patch straddles it when the tops are as narrow as a seed, ~3 cm): they
            # say nothing against a step. Those farther away do (a bowl's inside bottom,
            # ringed by its rim, leaves many far on the wrong side of any line).
            dist = xy[tops] @ normal2 - offset
            errors = int((((dist > 0) != is_upper) & (np.abs(dist) > _SEAM_BAND_VOXELS * size.voxel_m)).sum())
            if errors > settings.step_max_error * smaller:
                continue
            side = xy[members] @ normal2 > offset
            if min(int(side.sum()), int((~side).sum())) < min_side_vox:
                continue
            if _ledges_only(voxel_height, members, side, tops, is_upper, settings.step_max_over_top_m):
                continue
            seg[members[side]] = next_label
            next_label += 1
            cut_round = True
        if not cut_round:
            break
        cut_any = True
    if not cut_any:
        return dense_labels(seg)
    # a side may fall apart into pieces: pieces are connected components, small ones
    # rejoin their largest neighbour (LCCP's rule, counted in voxels)
    return rejoin_pieces(seg, ctx.vox.edges, size.min_segment_voxels)
