"""Stage 3f (ours, issue 37): a learned join of the pieces of one over-segmented object.

On noisy depth (an Asus Xtion's, a RealSense's at a metre) and clear plastic, one object
often comes out as two or three segments that touch: a plush toy's two halves, a can's
side and top, a cup's rim and body. The stages before join pieces by one rule each;
this stage weighs the cues they already compute together, with weights the project
trains itself (training/join.py, from the mOSD learn frames' labels and the foreign
frames' choose part; the model is ``clearcli/data/join_model.json``, a few hundred
bytes of logistic-regression weights with a version string).

For each pair of touching segments (voxel adjacencies across their seam) it computes
`FEATURES`: how long the seam is against the smaller segment's outline, the share of
convex supervoxel adjacencies across it (LCCP's criterion), the normal angle across it,
the range step and the rise (`cuts.seam_rise`) along it, the colour difference of the
two segments and along the seam, the sizes and heights of both. The model gives the
probability that both are one object. Pairs at least ``learned_join_min_p`` plus a
margin (`MARGIN_LOGIT`, in log-odds) are joined, most probable first; the margin keeps
pairs near the threshold as they are, so that a rounding-sized change of the points
(which moves a probability by far less) never flips a join. Never joined: two segments
the colour rule keeps apart (colours ``color_split_delta`` apart and a seam rising
``color_split_min_rise_m``, colors.py), nor, by a chain of joins, two segments that are
apart.
"""

from __future__ import annotations

import dataclasses
import functools
import json
from typing import Any

import numpy as np

from clearcli.errors import ClearError
from clearcli.perception.context import RefineContext
from clearcli.perception.cuts import seam_rise
from clearcli.perception.graph import ApartSets
from clearcli.perception.lccp import _angle_deg, convex_edges, join_pairs

MODEL_RESOURCE = "data/join_model.json"
# the file's format (the version of its weights is the file's "version")
MODEL_FORMAT = "clear-join-logistic-1"
# a join needs a log-odds this much above the threshold's: 0.2 is p 0.70 -> 0.74; a
# +-1 um move of the points changes a pair's log-odds by ~0.002 (gqcnn_primesense_4)
MARGIN_LOGIT = 0.2
# two segments are a pair when outline voxels of both are this close (m): touching
# (voxels 5 mm apart, 8.7 mm diagonally) or a few voxels apart
GAP_M = 0.015
# seam statistics of a pair with no supervoxel adjacency across it (both sides of the
# seam in one supervoxel, split by a voxel-level stage): a flat, convex seam
_NO_SV_SEAM = (1.0, 0.0, 0.0)

FEATURES: tuple[str, ...] = (
    "seam_share",  # seam voxels of the smaller segment / its outline voxels
    "seam_per_sqrt",  # seam voxels of the smaller segment / sqrt(its voxels)
    "gap_mm",  # the least distance between voxels of the two
    "convex_share",  # convex supervoxel adjacencies across the seam / all of them
    "normal_angle_deg",  # median angle between the normals across the seam
    "range_step_mm",  # median range difference of the voxel pairs across the seam
    "rise_mm",  # median seam_rise of the supervoxel pairs across the seam (clipped 50)
    "colour_de",  # CIE76 dE of the two segments' mean colours (0 without colour)
    "seam_de",  # median dE of the supervoxel pairs across the seam (0 without colour)
    "log_small",  # log of the smaller segment's voxels
    "log_large",  # log of the larger segment's voxels
    "top_small_mm",  # highest point of the smaller segment above the table
    "top_large_mm",
    "bottom_small_mm",  # lowest point of the smaller segment above the table
    "top_step_mm",  # |top_large - top_small|
)


@dataclasses.dataclass(frozen=True)
class PairFeatures:
    """The touching pairs of a segmentation and their features."""

    pairs: np.ndarray  # (P, 2) segment numbers, lo < hi, sorted
    x: np.ndarray  # (P, len(FEATURES)) float64
    apart: np.ndarray  # (P,) bool: the colour rule keeps them apart
    # (P,) supervoxel adjacencies across each seam (what convex_share is a share of; 0
    # where both sides lie in one supervoxel): a share of one or two is no evidence
    seam_adjacencies: np.ndarray | None = None


@dataclasses.dataclass(frozen=True)
class JoinModel:
    version: str
    mean: np.ndarray  # (F,) of the training features
    scale: np.ndarray  # (F,) their standard deviation
    weights: np.ndarray  # (F,) on the standardized features
    bias: float

    def logit(self, x: np.ndarray) -> np.ndarray:
        """(P,) log-odds that each row of ``x`` (P, F) is one object."""
        return np.asarray(((x - self.mean) / self.scale) @ self.weights + self.bias, dtype=np.float64)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> JoinModel:
        if d.get("format") != MODEL_FORMAT or tuple(d.get("features", ())) != FEATURES:
            raise ClearError(
                f"the join model is of format {d.get('format')!r}, not {MODEL_FORMAT!r}, or other features"
            )
        return cls(
            str(d["version"]),
            np.asarray(d["mean"], dtype=np.float64),
            np.asarray(d["scale"], dtype=np.float64),
            np.asarray(d["weights"], dtype=np.float64),
            float(d["bias"]),
        )


@functools.cache
def load_model() -> JoinModel:
    """The shipped model (read once a process)."""
    # importlib.resources (~1 ms, and the modules it imports) only where the model is read:
    # [segment] learned_join is off by default, and a plan reads no other package data
    from importlib import resources  # noqa: PLC0415

    text = (resources.files("clearcli") / MODEL_RESOURCE).read_text(encoding="utf-8")
    return JoinModel.from_dict(json.loads(text))


def _median_by(key: np.ndarray, values: np.ndarray, n: int, empty: float) -> np.ndarray:
    """(n,) the median of ``values`` per ``key`` in 0..n-1 (``empty`` where none)."""
    out = np.full(n, empty, dtype=np.float64)
    if key.size == 0:
        return out
    order = np.lexsort((values, key))
    k, v = key[order], values[order]
    count = np.bincount(k, minlength=n)
    start = np.cumsum(count) - count
    has = count > 0
    lo = start[has] + (count[has] - 1) // 2
    hi = start[has] + count[has] // 2
    out[has] = 0.5 * (v[lo] + v[hi])
    return out


def pair_features(seg_of_voxel: np.ndarray, ctx: RefineContext) -> PairFeatures:
    """The touching pairs of ``seg_of_voxel`` (V,) and their `FEATURES`."""
    from scipy.spatial import cKDTree  # noqa: PLC0415

    seg = np.asarray(seg_of_voxel, dtype=np.int64)
    n_seg = int(seg.max()) + 1 if seg.size else 0
    nf = len(FEATURES)
    none = PairFeatures(np.zeros((0, 2), np.int64), np.zeros((0, nf)), np.zeros(0, bool))
    if n_seg < 2:
        return none
    e = ctx.vox.edges
    c = ctx.vox.centroids
    # a segment's outline: voxels touching another segment, or with fewer than 8
    # neighbours of their own (a surface's edge has about 5, its inside 8 or more; a
    # depth edge cut the adjacency there)
    cross_edge = seg[e[:, 0]] != seg[e[:, 1]]
    own = np.bincount(np.compress(~cross_edge, e, axis=0).ravel(), minlength=seg.size)
    touching = np.zeros(seg.size, dtype=bool)
    touching[np.compress(cross_edge, e, axis=0).ravel()] = True
    is_outline = touching | (own < 8)
    outline = np.bincount(seg, weights=is_outline.astype(np.float64), minlength=n_seg)
    # the seam: outline voxels of two segments within GAP_M of each other (touching, or
    # apart across a depth edge or a strip the outline filter thinned)
    ov = np.flatnonzero(is_outline)
    near = cKDTree(c[ov]).query_pairs(GAP_M, output_type="ndarray")
    ce = ov[near].reshape(-1, 2)
    cross = seg[ce[:, 0]] != seg[ce[:, 1]]
    if not cross.any():
        return none
    # pairs of objects only: a speck under the smallest object's size is dropped anyway,
    # and on the training frames specks are most of the pairs, which drowned the rest
    size = np.bincount(seg, minlength=n_seg)
    big = size >= ctx.size.min_object_voxels
    cross &= big[seg[ce[:, 0]]] & big[seg[ce[:, 1]]]
    if not cross.any():
        return none
    ce = np.compress(cross, ce, axis=0)
    ce = ce[np.lexsort((ce[:, 1], ce[:, 0]))]  # the tree's order is no input's
    ca, cb = seg[ce[:, 0]], seg[ce[:, 1]]
    lo, hi = np.minimum(ca, cb), np.maximum(ca, cb)
    keys, pair_of_edge = np.unique(lo * n_seg + hi, return_inverse=True)
    pairs = np.stack([keys // n_seg, keys % n_seg], axis=1)
    n_pair = pairs.shape[0]
    small_is_lo = size[pairs[:, 0]] <= size[pairs[:, 1]]
    small = np.where(small_is_lo, pairs[:, 0], pairs[:, 1])
    large = np.where(small_is_lo, pairs[:, 1], pairs[:, 0])
    # seam voxels of the smaller segment: distinct (pair, voxel) on its side
    v_small = np.where(seg[ce[:, 0]] == small[pair_of_edge], ce[:, 0], ce[:, 1])
    seam_n = np.bincount(np.unique(pair_of_edge * seg.size + v_small) // seg.size, minlength=n_pair)
    seam_share = seam_n / np.maximum(outline[small], 1.0)
    seam_per_sqrt = seam_n / np.sqrt(size[small])
    gap = np.full(n_pair, np.inf)
    np.minimum.at(gap, pair_of_edge, np.linalg.norm(c[ce[:, 0]] - c[ce[:, 1]], axis=1))
    # range step across the seam
    rng = np.linalg.norm(c, axis=1)
    range_step = _median_by(pair_of_edge, np.abs(rng[ce[:, 0]] - rng[ce[:, 1]]), n_pair, 0.0) * 1000.0
    # supervoxel adjacencies across the seam
    svl = ctx.sv.voxel_label
    na, nb = svl[ce[:, 0]], svl[ce[:, 1]]
    diff = na != nb
    s_lo, s_hi = np.minimum(na, nb)[diff], np.maximum(na, nb)[diff]
    n_sv = ctx.sv.centroids.shape[0]
    sv_keys, first = np.unique(pair_of_edge[diff] * (n_sv * n_sv) + s_lo * n_sv + s_hi, return_index=True)
    sv_pair = pair_of_edge[diff][first]
    sv_edges = np.stack([s_lo[first], s_hi[first]], axis=1)
    if sv_edges.shape[0]:
        sv_cross = dataclasses.replace(ctx.sv, edges=sv_edges)
        convex = convex_edges(sv_cross, ctx.settings, ctx.size).astype(np.float64)
        angle = _angle_deg(ctx.sv.normals[sv_edges[:, 0]], ctx.sv.normals[sv_edges[:, 1]])
        rise = np.clip(seam_rise(ctx.sv, c, sv_edges, ctx.voxels_by_sv) * 1000.0, -50.0, 50.0)
    else:
        convex = angle = rise = np.zeros(0)
    count = np.bincount(sv_pair, minlength=n_pair)
    convex_share = np.where(
        count > 0, np.bincount(sv_pair, weights=convex, minlength=n_pair) / np.maximum(count, 1), _NO_SV_SEAM[0]
    )
    normal_angle = _median_by(sv_pair, angle, n_pair, _NO_SV_SEAM[1])
    rise_mm = _median_by(sv_pair, rise, n_pair, _NO_SV_SEAM[2])
    # colour
    colour_de = np.zeros(n_pair)
    seam_de = np.zeros(n_pair)
    lab = ctx.voxel_lab
    if lab is not None:
        w = ctx.vox.counts.astype(np.float64)
        seg_w = np.maximum(np.bincount(seg, weights=w, minlength=n_seg), 1e-12)
        seg_lab = (
            np.stack([np.bincount(seg, weights=w * lab[:, k], minlength=n_seg) for k in range(3)], axis=1)
            / seg_w[:, None]
        )
        colour_de = np.linalg.norm(seg_lab[pairs[:, 0]] - seg_lab[pairs[:, 1]], axis=1)
        sv_w = np.maximum(np.bincount(svl, weights=w, minlength=n_sv), 1e-12)
        sv_lab = (
            np.stack([np.bincount(svl, weights=w * lab[:, k], minlength=n_sv) for k in range(3)], axis=1)
            / sv_w[:, None]
        )
        de = np.linalg.norm(sv_lab[sv_edges[:, 0]] - sv_lab[sv_edges[:, 1]], axis=1) if sv_edges.size else np.zeros(0)
        seam_de = _median_by(sv_pair, de, n_pair, 0.0)
    # sizes and heights
    h = ctx.voxel_height
    top = np.full(n_seg, -np.inf)
    np.maximum.at(top, seg, h)
    bottom = np.full(n_seg, np.inf)
    np.minimum.at(bottom, seg, h)
    x = np.column_stack(
        [
            seam_share,
            seam_per_sqrt,
            gap * 1000.0,
            convex_share,
            normal_angle,
            range_step,
            rise_mm,
            colour_de,
            seam_de,
            np.log(size[small]),
            np.log(size[large]),
            top[small] * 1000.0,
            top[large] * 1000.0,
            bottom[small] * 1000.0,
            np.abs(top[large] - top[small]) * 1000.0,
        ]
    )
    s = ctx.settings
    apart = (
        (lab is not None)
        & (colour_de >= s.color_split_delta)
        & (rise_mm >= s.color_split_min_rise_m * 1000.0)
        & (size[small] >= ctx.size.min_object_voxels)
    )
    return PairFeatures(pairs, x, apart, count)


def greedy_joins(feats: PairFeatures, score: np.ndarray, chosen: np.ndarray, n_seg: int) -> list[tuple[int, int]]:
    """The ``chosen`` pairs of ``feats`` to join, highest ``score`` first (ties by pair),
    never two segments apart, directly or through a chain of joins (this stage's and
    seams.py's joins alike)."""
    sets = ApartSets(n_seg, feats.pairs[feats.apart].tolist())
    out = []
    for k in np.lexsort((feats.pairs[:, 1], feats.pairs[:, 0], -score)).tolist():
        if not chosen[k] or feats.apart[k]:
            continue
        a, b = int(feats.pairs[k, 0]), int(feats.pairs[k, 1])
        if sets.join(a, b):
            out.append((a, b))
    return out


def joins(feats: PairFeatures, logit: np.ndarray, min_logit: float, n_seg: int) -> list[tuple[int, int]]:
    """The pairs to join: log-odds at least ``min_logit``, most probable first (ties by
    pair), never two segments apart, directly or through a chain of joins."""
    return greedy_joins(feats, logit, logit >= min_logit, n_seg)


def join_learned(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
    """The stage (voxel level): the touching pairs the model finds one object joined."""
    seg = np.asarray(seg_of_voxel, dtype=np.int64)
    n_seg = int(seg.max()) + 1 if seg.size else 0
    feats = pair_features(seg, ctx)
    if feats.pairs.shape[0] == 0:
        return seg
    p = ctx.settings.learned_join_min_p
    min_logit = float(np.log(p / (1.0 - p))) + MARGIN_LOGIT
    chosen = joins(feats, load_model().logit(feats.x), min_logit, n_seg)
    if not chosen:
        return seg
    return join_pairs(seg, np.asarray(chosen, dtype=np.int64), n_seg)
