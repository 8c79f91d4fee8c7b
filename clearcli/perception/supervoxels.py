"""Stage 3a: supervoxels after VCCS (Papon et al., CVPR 2013), vectorised.

Voxel grid -> 26-neighbourhood voxel adjacency -> voxel normals -> seeds on a grid of
``seed_m`` cells -> every voxel joins the nearby seed with the smallest VCCS distance
    D = spatial_importance * |dx| / seed_m + normal_importance * (1 - |n . n_s|)
        + color_importance * dE / 100
(dE: CIE76 distance of the voxels' mean colours in CIELAB, where PCL takes the RGB
distance / 255), seeds move to the mean of their voxels, repeat; finally each supervoxel
is split into its connected pieces over the voxel adjacency (VCCS grows supervoxels
through adjacency, so a supervoxel never jumps a gap), and a piece cut off from its seed
joins the neighbour it touches most.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clearcli.perception.flat import cielab
from clearcli.perception.graph import components
from clearcli.perception.size import SegmentSize
from clearcli.settings.segment import SegmentSettings

# 13 of the 26 neighbour offsets: each undirected adjacency found once
_HALF_OFFSETS = np.array(
    [(dx, dy, dz) for dx in (-1, 0, 1) for dy in (-1, 0, 1) for dz in (-1, 0, 1) if (dx, dy, dz) > (0, 0, 0)],
    dtype=np.int64,
)
# The grids over camera-frame coordinates (voxels, seed cells) have their cell boundaries
# shifted off the whole millimetre: depth images store whole millimetres (RealSense,
# Kinect, mOSD), so a fifth of a real frame's points have a depth exactly on a multiple
# of 5 mm, a voxel boundary, and floor() put each on whichever side float rounding
# chose: moving every point by a micrometre moved thousands between voxels. Shifted by
# 0.35 mm, a boundary lies 0.35 mm from any whole millimetre (0.15 from a half, 0.05
# from a tenth), and a micrometre moves only the few points that are truly that close.
GRID_SHIFT_M = 0.00035
# the six distinct entries of a symmetric 3 x 3 matrix, in `VoxelCloud.scatter`'s order
_SCATTER_ENTRIES = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))


def grid_cells(points: np.ndarray, cell_m: float) -> np.ndarray:
    """(N, 3) int64 cell of each point on the grid of ``cell_m`` (boundaries shifted off
    the millimetre: GRID_SHIFT_M)."""
    return np.floor((points + GRID_SHIFT_M) / cell_m).astype(np.int64)


@dataclass(frozen=True, eq=False)
class VoxelCloud:
    point_voxel: np.ndarray  # (M,) voxel index of every input point
    centroids: np.ndarray  # (V, 3)
    counts: np.ndarray  # (V,) points per voxel
    keys: np.ndarray  # (V, 3) integer grid coordinates
    colors: np.ndarray | None  # (V, 3) float mean RGB
    edges: np.ndarray  # (E, 2) adjacent voxel pairs (26-neighbourhood), i < j unordered
    # (V, 6) each voxel's points' scatter about its centroid, sum of d d^T with d = p - c,
    # entries (xx, xy, xz, yy, yz, zz), m^2; None: not computed (a hand-made cloud)
    scatter: np.ndarray | None = None

    @property
    def n_voxels(self) -> int:
        return int(self.centroids.shape[0])


def _unique_inverse(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(keys, return_inverse=True)`` of (M,) int64 ``keys`` listed in runs (the
    points of a frame in pixel order: a voxel's points mostly come one after another):
    the sort is done on one key per run, a third of the points on a camera frame, and
    the inverse spread back over the runs. The same arrays, in half the time."""
    m = keys.shape[0]
    if m == 0:
        return keys.copy(), np.zeros(0, dtype=np.int64)
    starts = np.flatnonzero(keys[1:] != keys[:-1]) + 1
    run_keys = np.concatenate((keys[:1], keys[starts]))
    lengths = np.diff(np.concatenate(([0], starts, [m])))
    n_runs = run_keys.shape[0]
    run_bits = max(1, (n_runs - 1).bit_length())
    low, high = int(run_keys.min()), int(run_keys.max())
    if low < 0 or high.bit_length() + run_bits > 62:
        uniq, run_inverse = np.unique(run_keys, return_inverse=True)
        return uniq, np.repeat(run_inverse.astype(np.int64, copy=False), lengths)
    # np.unique's argsort, as one sort of the keys with each run's place in the low bits:
    # the same arrays, a third less time (issue 39)
    packed = np.left_shift(run_keys, run_bits)
    packed |= np.arange(n_runs)
    packed.sort()
    sorted_keys = packed >> run_bits
    first = np.empty(n_runs, dtype=bool)
    first[0] = True
    np.not_equal(sorted_keys[1:], sorted_keys[:-1], out=first[1:])
    uniq = np.compress(first, sorted_keys)
    packed &= (1 << run_bits) - 1
    run_inverse = np.empty(n_runs, dtype=np.int64)
    run_inverse[packed] = np.cumsum(first) - 1
    return uniq, np.repeat(run_inverse, lengths)


def voxelize(points: np.ndarray, voxel_m: float, colors: np.ndarray | None = None, scatter: bool = False) -> VoxelCloud:
    """Voxel grid of ``points`` (M, 3) and the voxel adjacency graph; ``scatter``: also
    each voxel's scatter of its points (`VoxelCloud.scatter`, for `weighted_voxel_normals`)."""
    # the cells of `grid_cells`, one coordinate at a time: reductions over axis 0 of an
    # (M, 3) array are several times slower than over a column; floor is monotonic, so
    # a column's lowest cell is the cell of its lowest float
    # (in place: the same operations, no fresh temporaries)
    cols = []
    for k in range(3):
        col = points[:, k] + GRID_SHIFT_M
        col /= voxel_m
        cols.append(np.floor(col, out=col))
    lo = [int(c.min()) - 1 for c in cols]  # one empty layer around so offsets never wrap
    keys_cols = [c.astype(np.int64) for c in cols]
    for c, low in zip(keys_cols, lo):
        c -= low
    dims = [int(c.max()) + 2 for c in keys_cols]
    packed = keys_cols[0]
    packed *= dims[1]
    packed += keys_cols[1]
    packed *= dims[2]
    packed += keys_cols[2]
    uniq, inverse = _unique_inverse(packed)
    n_vox = uniq.shape[0]
    counts = np.bincount(inverse, minlength=n_vox)
    cent = np.stack(
        [np.bincount(inverse, weights=points[:, k], minlength=n_vox) for k in range(3)], axis=1, dtype=np.float64
    )
    cent /= counts[:, None]
    vcol = None
    if colors is not None:
        vcol = (
            np.stack(
                [np.bincount(inverse, weights=colors[:, k].astype(np.float64), minlength=n_vox) for k in range(3)],
                axis=1,
            )
            / counts[:, None]
        )
    keys = np.stack([uniq // (dims[1] * dims[2]), (uniq // dims[2]) % dims[1], uniq % dims[2]], axis=1)
    # the points' scatter in each voxel: with the counts and centroids it gives the exact
    # covariance of the points of any set of voxels (`voxel_normals`), so a point passing
    # from one voxel to a neighbour changes no fit over both (issue 37)
    scat = None
    if scatter:
        dev = [points[:, k] - np.take(cent[:, k], inverse) for k in range(3)]
        scat = np.stack(
            [np.bincount(inverse, weights=dev[a] * dev[b], minlength=n_vox) for a, b in _SCATTER_ENTRIES], axis=1
        )
    return VoxelCloud(inverse, cent, counts, keys, vcol, _adjacency(uniq, dims), scat)


def _adjacency(uniq: np.ndarray, dims: list[int]) -> np.ndarray:
    """(E, 2) pairs of the sorted packed voxel keys ``uniq`` one of `_HALF_OFFSETS` apart:
    the offsets' blocks in their order, each ascending in its first voxel.

    The keys are sorted with z fastest, so the three offsets (dx, dy, -1..1) of one
    (dx, dy) are consecutive keys: one binary search finds the first, and each of the
    other two is the next key when the one before was present. 4 searches, not 13: the
    keys are distinct integers, so the first key from uniq[i] + 1 on is uniq[i + 1]."""
    n_vox = uniq.shape[0]
    if n_vox == 0:
        return np.zeros((0, 2), np.int64)
    # a sentinel past every key, so that a position one past the last reads no key
    ext = np.concatenate((uniq, [uniq[-1] + 2 * dims[2] * dims[1] + 2]))
    blocks: dict[tuple[int, int, int], tuple[np.ndarray, np.ndarray]] = {}
    for dx, dy in ((0, 0), (0, 1), (1, -1), (1, 0), (1, 1)):
        base = uniq + (dx * dims[1] + dy) * dims[2]
        dzs = (1,) if (dx, dy) == (0, 0) else (-1, 0, 1)
        pos = np.arange(1, n_vox + 1) if (dx, dy) == (0, 0) else np.searchsorted(uniq, base + dzs[0])
        for dz in dzs:
            hit = np.take(ext, pos) == base + dz  # take: faster than [pos]
            src = np.flatnonzero(hit)
            blocks[(dx, dy, dz)] = (src, np.take(pos, src))
            pos = pos + hit  # the next key follows when this one was present
    ordered = [blocks[(int(o[0]), int(o[1]), int(o[2]))] for o in _HALF_OFFSETS]
    edges = np.empty((sum(src.shape[0] for src, _ in ordered), 2), dtype=np.int64)
    at = 0
    for src, dst in ordered:  # straight into the columns: no concatenated copies to stack
        edges[at : at + src.shape[0], 0] = src
        edges[at : at + src.shape[0], 1] = dst
        at += src.shape[0]
    return edges


def orient_towards(normals: np.ndarray, points: np.ndarray, viewpoint: np.ndarray) -> np.ndarray:
    """Flip normals so that they face the viewpoint."""
    # the dot product column by column, summed as einsum("ij,ij->i") sums it (_dot3):
    # a normal almost across the line of sight flips as it did
    to_view = tuple(viewpoint[j] - points[:, j] for j in range(3))
    flip = _dot3(tuple(normals[:, j] for j in range(3)), to_view) < 0
    return np.where(flip[:, None], -normals, normals)


def smallest_eigenvectors(cov: np.ndarray) -> np.ndarray:
    """(N, 3) unit eigenvectors of the smallest eigenvalue of symmetric (N, 3, 3) ``cov``.

    Closed form where that eigenvalue stands apart (the usual case for a surface patch):
    eigenvalues from the trigonometric solution of the characteristic cubic, the
    eigenvector as the longest cross product of two rows of ``cov - lambda I``
    (D. Eberly, "A Robust Eigensolver for 3x3 Symmetric Matrices", the method of open3d's
    normal estimation). np.linalg.eigh for the rest. A few times faster than eigh alone
    on thousands of matrices; the same vectors up to sign (1e-5 degrees).
    """
    return _smallest_eigenvectors6(cov[:, 0, 0], cov[:, 0, 1], cov[:, 0, 2], cov[:, 1, 1], cov[:, 1, 2], cov[:, 2, 2])


def _dot3(x: tuple[np.ndarray, ...], y: tuple[np.ndarray, ...]) -> np.ndarray:
    """x . y of 3-vectors given by their components, summed as ``np.einsum`` sums a row of
    3 (two SIMD lanes: (x0 y0 + x2 y2) + x1 y1), so that the bits are einsum's: the
    callers replaced einsum over (N, 3) rows, and every later comparison sees the same
    floats (tests/perception/test_supervoxels.py holds einsum to it)."""
    return (x[0] * y[0] + x[2] * y[2]) + x[1] * y[1]


def _smallest_eigenvectors6(
    c00: np.ndarray, c01: np.ndarray, c02: np.ndarray, c11: np.ndarray, c12: np.ndarray, c22: np.ndarray
) -> np.ndarray:
    """`smallest_eigenvectors` of the symmetric matrices given by their 6 distinct
    entries, each (N,): the same arithmetic on contiguous columns instead of (N, 3, 3)
    views, the cross products written out (np.cross's order of operations) and no
    (N, 3, 3) array but for the matrices eigh takes."""
    n = c00.shape[0]
    out = np.empty((n, 3))
    if n == 0:
        return out
    scale = np.maximum(
        np.maximum(np.maximum(np.abs(c00), np.abs(c01)), np.maximum(np.abs(c02), np.abs(c11))),
        np.maximum(np.abs(c12), np.abs(c22)),
    )
    scale[scale == 0] = 1.0
    a00, a01, a02, a11, a12, a22 = (c / scale for c in (c00, c01, c02, c11, c12, c22))
    q = (a00 + a11 + a22) / 3.0
    b00, b11, b22 = a00 - q, a11 - q, a22 - q
    p = np.sqrt((b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * (a01 * a01 + a02 * a02 + a12 * a12)) / 6.0)
    ok = p > 1e-12
    ps = np.where(ok, p, 1.0)
    det = (b00 * (b11 * b22 - a12 * a12) - a01 * (a01 * b22 - a12 * a02) + a02 * (a01 * a12 - b11 * a02)) / ps**3
    half = np.clip(0.5 * det, -1.0, 1.0)
    lam = q + 2.0 * p * np.cos(np.arccos(half) / 3.0 + 2.0 * np.pi / 3.0)  # the smallest
    m00, m11, m22 = a00 - lam, a11 - lam, a22 - lam
    # the rows r0 = (m00, a01, a02), r1 = (a01, m11, a12), r2 = (a02, a12, m22); each
    # cross product (u1 v2 - u2 v1, u2 v0 - u0 v2, u0 v1 - u1 v0) as np.cross computes it
    c_01 = (a01 * a12 - a02 * m11, a02 * a01 - m00 * a12, m00 * m11 - a01 * a01)  # r0 x r1
    c_02 = (a01 * m22 - a02 * a12, a02 * a02 - m00 * m22, m00 * a12 - a01 * a02)  # r0 x r2
    c_12 = (m11 * m22 - a12 * a12, a12 * a02 - a01 * m22, a01 * a12 - m11 * a02)  # r1 x r2
    len2 = [_dot3(c, c) for c in (c_01, c_02, c_12)]
    # the longest, the first of equals (np.argmax)
    take1 = len2[1] > len2[0]
    best_len2 = np.where(take1, len2[1], len2[0])
    take2 = len2[2] > best_len2
    best_len2 = np.where(take2, len2[2], best_len2)
    length = np.sqrt(best_len2)
    # half < 0: the smallest eigenvalue is the one farthest from the other two; else
    # (a thin strip, an edge: a sixth of a frame's voxels) the longest cross product is
    # still exact while it is long, the smallest eigenvalue well apart from the middle
    # one (1e-2: all but a handful of them, within 3e-6 degrees of eigh's vector)
    fast = ok & (((half < 0.0) & (length > 1e-12)) | (length > 1e-2))
    safe = np.where(fast, length, 1.0)
    for j in range(3):
        out[:, j] = np.where(take2, c_12[j], np.where(take1, c_02[j], c_01[j])) / safe
    slow = np.flatnonzero(~fast)
    if slow.size:
        cov = np.empty((slow.size, 3, 3))
        for (i, j), c in zip(((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)), (c00, c01, c02, c11, c12, c22)):
            cov[:, i, j] = cov[:, j, i] = c[slow]
        out[slow] = np.linalg.eigh(cov)[1][:, :, 0]
    return out


def radius_knn(points: np.ndarray, k: int, radius_m: float) -> np.ndarray:
    """(N, k) indices of the ``k`` nearest of ``points`` (N, 3) to each of them (itself
    included) closer than ``radius_m``, nearest first, ``N`` where fewer: exactly what
    ``cKDTree(points).query(points, k=k, distance_upper_bound=radius_m)[1]`` gives, with
    less CPU (mOSD voxel centroids: a fifth less; the tree's query is single-threaded
    C++, this is NumPy over ~35 neighbours a point).

    The tree's pairs within the radius (``query_pairs``, a fifth of the time of its
    k-nearest query) are sorted by one int64 key per (point, neighbour): the point, then
    the squared distance quantised to the bits left over, then the neighbour. Where a
    point's first k + 1 distances fall into distinct buckets and none near the radius,
    their order is the distances' and the k nearest are the tree's, whatever its order
    of ties; a point with two in one bucket (equal distances: whole-millimetre depths)
    or one near the radius is asked of the tree itself, a few per frame.

    The tree stays for the pairs: a search by the centroids' integer voxel cells (each
    voxel against the cells within the radius) meets 37 candidates a voxel for 17 pairs
    on a cluttered mOSD frame (test55), more NumPy work than ``query_pairs`` (issue 39)."""
    from scipy.spatial import cKDTree

    points = np.asarray(points, dtype=np.float64)  # the tree's distances are float64
    n = points.shape[0]
    if n == 0:
        return np.zeros((0, max(k, 1)), dtype=np.intp)
    tree = cKDTree(points)
    n_bits = max(1, (n - 1).bit_length())
    # the buckets as whole floats: 2**52 - 1 is one, and no rounding up spills a bucket
    # into the point's bits
    q_bits = min(52, 63 - 2 * n_bits)
    # the pairs grow with the radius cubed where the tree's query stays at k a point: a
    # radius of many voxels (settings) goes to the tree, judged on a sample of points
    sample = points[:: max(1, n // 64)]
    crowded = float(np.mean(tree.query_ball_point(sample, radius_m, return_length=True))) > 4 * k
    if q_bits < 20 or k < 1 or crowded:  # also millions of points: no room for the distances
        return np.asarray(tree.query(points, k=max(k, 1), distance_upper_bound=radius_m)[1]).reshape(n, max(k, 1))
    # a little beyond the radius: the tree's own rounding decides at the radius
    pairs = tree.query_pairs(radius_m * (1.0 + 1e-7), output_type="ndarray")
    n_pairs = pairs.shape[0]
    first, second = np.ascontiguousarray(pairs[:, 0]), np.ascontiguousarray(pairs[:, 1])
    # Two buffers of 2 n_pairs + n int64 hold every array of n_pairs or more below: the
    # keys (and a window of k after them, so that every row's window of k keys lies
    # within the buffer), and ``work``: the squared distances and their scratch, then
    # each key's (point, bucket). Fresh arrays cost their first touch of every page on
    # top of the arithmetic: radius_knn 29.5 -> ~26 ms on test55 (issue 39).
    n_keys = 2 * n_pairs + n
    key_buf = np.empty(n_keys + k, dtype=np.int64)
    key_buf[n_keys:] = 0
    key = key_buf[:n_keys]
    work = np.empty(n_keys, dtype=np.int64)
    # the squared distances, in place: (dx dx + dy dy) + dz dz (the first square is
    # 0 + dx dx's float)
    d2, dj = work[:n_pairs].view(np.float64), work[n_pairs : 2 * n_pairs].view(np.float64)
    other = key_buf[:n_pairs].view(np.float64)
    for j in range(3):
        col = np.ascontiguousarray(points[:, j])
        term = d2 if j == 0 else dj
        np.take(col, first, out=term, mode="clip")  # indices in range: no clipping, no buffered copy
        term -= np.take(col, second, out=other, mode="clip")
        term *= term
        if j:
            d2 += dj
    r2 = radius_m * radius_m
    top = (1 << q_bits) - 1
    scale = float(top - 1) / r2
    # floor(d2 * scale) is monotonic in d2: distinct buckets order as the distances do
    d2 *= scale
    np.minimum(d2, float(top), out=d2)
    # the buckets where the keys of (second, first) go, then those keys in place there
    q = key[n_pairs : 2 * n_pairs]
    np.copyto(q, d2, casting="unsafe")  # astype(np.int64)'s conversion
    band_lo, band_hi = int(r2 * (1.0 - 1e-9) * scale), int(r2 * (1.0 + 1e-9) * scale)
    shift = n_bits + q_bits
    q <<= n_bits
    # the keys of (first, second), (second, first) and (i, i), written in place
    block = key[:n_pairs]
    np.left_shift(first, shift, out=block)
    block |= q
    block |= second
    high = work[:n_pairs]  # the squared distances are spent
    np.left_shift(second, shift, out=high)
    q |= high
    q |= first
    own = np.arange(n, dtype=np.int64)
    selves = key[2 * n_pairs : n_keys]
    np.left_shift(own, shift, out=selves)
    selves |= own
    key.sort()
    per_row = np.bincount(first, minlength=n)
    per_row += np.bincount(second, minlength=n)
    per_row += 1
    at = np.cumsum(per_row) - per_row  # where each point's row of the sorted keys starts
    # The tests on every key at once, and on a row's place only where one is met (a few
    # hundred keys): a loop over the first k + 1 places of all rows, a dozen passes over
    # n points each, cost a third more on a cluttered mOSD frame (issue 39).
    # ``hi``: the key without the neighbour's bits, the point and the bucket; two keys in
    # a row with the same are two of one point in one bucket (a tie), asked of the tree
    # when the later one is among the point's first k + 1
    hi = np.right_shift(key, n_bits, out=work)
    tie_at = np.flatnonzero(hi[1:] == hi[:-1])
    tie_at += 1
    bucket = hi
    bucket &= top
    # from the band on (one near the radius, or beyond it): the last keys of their rows
    # (a row is sorted by bucket); one in the band among the first k + 1 is asked too
    far_at = np.flatnonzero(bucket >= band_lo)
    flagged = np.concatenate((tie_at, far_at[np.take(bucket, far_at) <= band_hi]))
    flagged_row = np.take(key, flagged) >> shift
    ask_tree = np.zeros(n, dtype=bool)
    ask_tree[flagged_row[flagged - np.take(at, flagged_row) <= k]] = True
    # a row's neighbours: its keys before the band, the first k of them; n after. Each
    # row's window of k keys copied whole (a view of the windows, indexed by the rows'
    # starts): no (N, k) array of positions to gather one key at a time
    n_near = per_row - np.bincount(np.take(key, far_at) >> shift, minlength=n)
    nb = np.lib.stride_tricks.sliding_window_view(key_buf, k)[at]
    nb &= (1 << n_bits) - 1
    np.putmask(nb, np.arange(k) >= n_near[:, None], n)  # past the band, or the row's end
    nb = nb.astype(np.intp, copy=False)
    asked = np.flatnonzero(ask_tree)
    if asked.size:
        nb[asked] = np.asarray(tree.query(points[asked], k=k, distance_upper_bound=radius_m)[1]).reshape(-1, k)
    return nb


def voxel_normals(centroids: np.ndarray, radius_m: float, viewpoint: np.ndarray, max_nn: int = 30) -> np.ndarray:
    """(V, 3) unit normals of the voxel centroids, facing the viewpoint.

    PCA over each centroid's neighbourhood: its ``max_nn`` nearest centroids (itself
    included) within ``radius_m``; the normal is the eigenvector of the smallest
    eigenvalue of their covariance. A neighbourhood of fewer than 3 centroids has no
    plane: its normal is +z before orienting. This is what open3d's
    ``estimate_normals`` with a hybrid (radius, max_nn) search gave, used here before:
    the same normals (mOSD frames: all but one in 230k voxels within 0.1 degree) in
    tens of milliseconds, without importing open3d (most of a second).
    """
    n = centroids.shape[0]
    if n == 0:
        return np.zeros((0, 3))
    k = min(max_nn, n)
    # the k-d tree's neighbours in the k-d tree's order (radius_knn): centroids at equal
    # distances are common (whole-millimetre depths), and the order decides the order
    # of the sums below, so the bits of the normals
    nb = radius_knn(centroids, k, radius_m)
    # a missing neighbour has index n; it becomes the centroid itself, offset 0, which
    # adds nothing to the sums (offsets from the query centroid: no cancellation)
    flat = nb.reshape(-1)
    missing = np.flatnonzero(flat == n)
    cnt = k - np.bincount(missing // k, minlength=n)
    flat[missing] = missing // k
    # (3, V, k): one contiguous (V, k) block of offsets per coordinate, as before
    cols = np.ascontiguousarray(centroids.T)
    off = np.take(cols, nb, axis=1)
    off -= cols[:, :, None]
    mean = off.sum(axis=2) / cnt
    c = {(a, b): np.einsum("vk,vk->v", off[a], off[b]) / cnt - mean[a] * mean[b] for a in range(3) for b in range(a, 3)}
    normals = _smallest_eigenvectors6(c[0, 0], c[0, 1], c[0, 2], c[1, 1], c[1, 2], c[2, 2])
    normals[cnt < 3] = (0.0, 0.0, 1.0)
    return orient_towards(normals, centroids, viewpoint)


def weighted_voxel_normals(
    vox: VoxelCloud, radius_m: float, voxel_m: float, viewpoint: np.ndarray, full_weight_points: int = 4
) -> np.ndarray:
    """(V, 3) unit normals of the voxels, facing the viewpoint: the smallest
    eigenvector of the weighted covariance of the points of every voxel whose grid cell
    lies within ``radius_m`` of the voxel's cell (cell centres ``voxel_m`` apart; itself
    included), all of them, no cap on their number.

    The neighbourhood is a fixed stencil of cells, not the centroids within a radius of
    the voxel's centroid: a centroid moves when one of its points passes to a neighbour
    cell (a voxel of 3 points: by a millimetre), and a ball around a moving centre, or
    centroids moving across its rim, took whole voxels in or out (issue 37). A voxel
    weighs min(points, ``full_weight_points``) / ``full_weight_points``, its centroid
    and its scatter (`VoxelCloud.scatter`) scaled alike, so a voxel of one point that
    appears or vanishes moves the fit by a fraction of a voxel among the thirty or more
    (the fit on the 30 nearest centroids turned normals by 5-13 degrees when one came or
    went). Fewer than 3 voxels: +z before orienting, as `voxel_normals`."""
    from scipy.spatial import cKDTree

    cent = vox.centroids
    n = cent.shape[0]
    if n == 0:
        return np.zeros((0, 3))
    counts = vox.counts.astype(np.float64)
    weight = np.minimum(counts, float(full_weight_points)) / float(full_weight_points)
    # each voxel's scatter, scaled as its weight scales its points
    scatter = vox.scatter * (weight / counts)[:, None] if vox.scatter is not None else np.zeros((n, 6))
    # integer cell coordinates: their squared distances are whole numbers, so the
    # stencil's rim lies a whole 1e-6 cell from any of them
    radius_cells = radius_m / voxel_m + 1e-6
    pairs = cKDTree(vox.keys.astype(np.float64)).query_pairs(radius_cells, output_type="ndarray")
    first, second = pairs[:, 0], pairs[:, 1]
    # each pair adds each voxel to the other's sums; offsets from the voxel's centroid
    # (the covariance does not depend on the origin; near it, no cancellation)
    ends = np.concatenate((first, second))
    others = np.concatenate((second, first))
    w = np.take(weight, others)
    o = [np.take(cent[:, a], others) - np.take(cent[:, a], ends) for a in range(3)]
    total = weight + np.bincount(ends, weights=w, minlength=n)
    s1 = [np.bincount(ends, weights=w * o[a], minlength=n) / total for a in range(3)]
    cov = []
    for e, (a, b) in enumerate(_SCATTER_ENTRIES):
        s2 = np.bincount(ends, weights=w * o[a] * o[b] + np.take(scatter[:, e], others), minlength=n)
        cov.append((s2 + scatter[:, e]) / total - s1[a] * s1[b])
    normals = _smallest_eigenvectors6(*cov)
    n_nb = 1 + np.bincount(ends, minlength=n)
    normals[n_nb < 3] = (0.0, 0.0, 1.0)
    return orient_towards(normals, cent, viewpoint)


def _pair_keys(pairs: np.ndarray, n: int) -> np.ndarray:
    """(P,) int64 key ``a * n + b`` of each row (a, b) of ``pairs``, ints in [0, n): the
    keys sort as the rows do (first column major), so ``np.unique`` on them gives the rows
    of ``np.unique(pairs, axis=0)`` in its order, several times faster than its sort on
    rows; `_pairs_of` turns keys back into rows."""
    return pairs[:, 0].astype(np.int64) * n + pairs[:, 1]


def _distinct(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(keys, return_counts=True)`` of (P,) int64 ``keys`` by a sort and a
    comparison of neighbours: NumPy 2.4's np.unique finds the distinct values through a
    hash table, then sorts them, 3-4x the time of the sort on a frame's supervoxel
    adjacency keys (31k keys on test55: 0.76 -> 0.18 ms, issue 39)."""
    ordered = np.sort(keys)
    first = np.empty(ordered.shape[0], dtype=bool)
    first[:1] = True
    np.not_equal(ordered[1:], ordered[:-1], out=first[1:])
    starts = np.flatnonzero(first)
    return np.take(ordered, starts), np.diff(starts, append=ordered.shape[0])


def _pairs_of(keys: np.ndarray, n: int) -> np.ndarray:
    """(K, 2) rows of the keys of `_pair_keys`."""
    return np.stack([keys // n, keys % n], axis=1)


def _seed_sums(values: np.ndarray, lab: np.ndarray, used: np.ndarray | None, n_seeds: int) -> np.ndarray:
    """(n_seeds, 3) per-seed sums of the rows of ``values`` (V, 3) of the voxels ``used``
    (all when None), whose seeds are ``lab``; bincount's sums, in voxel order."""
    return np.stack(
        [
            np.bincount(
                lab, weights=values[:, j] if used is None else np.compress(used, values[:, j]), minlength=n_seeds
            )
            for j in range(3)
        ],
        axis=1,
    )


def seed_normal_tensors(
    cent: np.ndarray, seed_vox: np.ndarray, radius_m: float, spread: float
) -> tuple[np.ndarray, np.ndarray]:
    """Each seed's normal as a tensor: (S, 6) entries (`_SCATTER_ENTRIES` order) of
    T = sum_i w_i e_i e_i^T over the eigenpairs (lambda_i, e_i) of the covariance of the
    30 nearest voxel centroids within ``radius_m`` of the seed voxel's (the neighbourhood
    of `voxel_normals`), with w_i = max(0, 1 - (lambda_i / lambda_0 - 1) / ``spread``) ** 2
    and lambda_0 the least (w_0 = 1); and (S,) whether any other w_i is above 0.

    A seed whose next eigenvalue lies ``spread`` times the least or more above it has
    T = e_0 e_0^T: its voxel's normal, and the second array says False. One whose two
    least are nearly equal (a crease, a blob: the normal is any direction of a plane)
    spreads over both, continuously in the covariance: the least eigenvector there turns
    by tens of degrees under a rounding-sized change (gqcnn_primesense_4 perturbed: a seed
    voxel of 3 points -> 2, eigenvalues 1.48 and 1.74e-5 m^2 -> 1.43 and 1.99e-5, its normal
    turned 17 degrees), the tensor by a fraction (w_1 0.69 -> 0.37). Squared, the weight
    leaves 0 with no slope at the ratio 1 + ``spread``."""
    from scipy.spatial import cKDTree

    n = cent.shape[0]
    k = min(30, n)
    _, nb = cKDTree(cent).query(cent[seed_vox], k=k, distance_upper_bound=radius_m)
    nb = np.asarray(nb).reshape(seed_vox.shape[0], k)
    valid = nb < n
    pts = cent[np.where(valid, nb, 0)] - cent[seed_vox][:, None, :]
    pts[~valid] = 0.0
    cnt = np.maximum(valid.sum(axis=1), 1)
    mean = pts.sum(axis=1) / cnt[:, None]
    cov = np.einsum("ska,skb->sab", pts, pts) / cnt[:, None, None] - mean[:, :, None] * mean[:, None, :]
    evals, evecs = np.linalg.eigh(cov)
    least = np.maximum(evals[:, :1], 1e-18)
    weight = np.clip(1.0 - (np.maximum(evals, 1e-18) / least - 1.0) / spread, 0.0, 1.0) ** 2
    weight[:, 0] = 1.0
    tensor = np.einsum("sai,si,sbi->sab", evecs, weight, evecs)
    # fewer than 3 centroids: no plane, the voxel normal is +z (voxel_normals); kept
    spread_out = (weight[:, 1] > 0.0) & (valid.sum(axis=1) >= 3)
    return np.stack([tensor[:, a, b] for a, b in _SCATTER_ENTRIES], axis=1), spread_out


def _tensor_alignment(seed_tensor: np.ndarray, nb: np.ndarray, voxel_nrm: tuple[np.ndarray, ...]) -> np.ndarray:
    """(P,) sqrt(n^T T n) of voxel normals n (3 columns of P) against the tensors T
    (`seed_normal_tensors`) of seeds ``nb`` (P,): |n . n_s| where T = n_s n_s^T."""
    t = [np.take(seed_tensor[:, e], nb) for e in range(6)]
    x, y, z = voxel_nrm
    q = t[0] * x * x + t[3] * y * y + t[5] * z * z + 2.0 * (t[1] * x * y + t[2] * x * z + t[4] * y * z)
    return np.sqrt(np.clip(q, 0.0, 1.0))


def supervoxel_labels(
    vox: VoxelCloud,
    normals: np.ndarray,
    settings: SegmentSettings,
    size: SegmentSize | None = None,
    trace: list[np.ndarray] | None = None,
) -> np.ndarray:
    """(V,) supervoxel index of every voxel, 0..S-1 (``size``: the frame's seed;
    `SegmentSize.of(settings)` when None). ``trace`` (benchmarks/stability.py): gets
    the seed voxels (S,), then per assignment each voxel's seed (V,, -1 none) and its
    cost margin to the runner-up (V,, inf when it has none)."""
    from scipy.spatial import cKDTree

    size = size if size is not None else SegmentSize.of(settings)
    cent = vox.centroids
    n_vox = vox.n_voxels
    seed_m = size.seed_m
    # seeds: in every occupied seed cell holding enough voxels (a speck is no seed), the
    # voxel nearest to the mean of that cell's voxels (the first of equals)
    cols = [np.floor((cent[:, k] + GRID_SHIFT_M) / seed_m).astype(np.int64) for k in range(3)]  # grid_cells
    cols = [c - c.min() for c in cols]
    cdims = [int(c.max()) + 1 for c in cols]
    # the voxels come in key order, so a seed cell's voxels come in runs too
    _, cinv = _unique_inverse((cols[0] * cdims[1] + cols[1]) * cdims[2] + cols[2])
    n_cells = int(cinv.max()) + 1 if n_vox else 0
    ccount = np.bincount(cinv, minlength=n_cells)
    cmean = np.stack(
        [np.bincount(cinv, weights=cent[:, k], minlength=n_cells) for k in range(3)], axis=1, dtype=np.float64
    )
    cmean /= ccount[:, None]
    dist_to_mean = np.linalg.norm(cent - cmean[cinv], axis=1)
    # per cell the least distance, then the lowest voxel at it: a lexsort's first, unsorted
    least = np.full(n_cells, np.inf)
    np.minimum.at(least, cinv, dist_to_mean)
    at_least = np.flatnonzero(dist_to_mean == least[cinv])
    seed_of_cell = np.full(n_cells, n_vox, dtype=np.int64)
    np.minimum.at(seed_of_cell, cinv[at_least], at_least)
    seed_vox = seed_of_cell[ccount >= size.min_seed_voxels]
    if seed_vox.size == 0:
        seed_vox = np.array([0], dtype=np.int64)

    seed_pos = cent[seed_vox]
    seed_nrm = normals[seed_vox]
    # colour in CIELAB, whose distances follow what the eye sees as a difference (the
    # colour stages after LCCP judge in it too; RGB distances overstate changes of
    # brightness); / 100 puts dE on the scale of the other terms (100: black to white)
    voxel_lab = cielab(vox.colors) / 100.0 if (vox.colors is not None and settings.color_importance > 0) else None
    seed_lab = voxel_lab[seed_vox] if voxel_lab is not None else None
    k = min(8, seed_pos.shape[0])
    voxel_nrm = tuple(normals[:, j, None] for j in range(3))
    # the seeds whose first normal is a tensor (seed_normal_spread): their tensors, and
    # (S + 1,) which seeds they are (a missing candidate, index S, is none)
    spread: tuple[np.ndarray, np.ndarray] | None = None
    if settings.seed_normal_spread > 0:
        tensors, spread_out = seed_normal_tensors(cent, seed_vox, size.normal_radius_m, settings.seed_normal_spread)
        if spread_out.any():
            spread = (tensors, np.append(spread_out, False))
    rows = np.arange(n_vox) * k  # each voxel's first place in the flat (V, k) arrays
    seed_nrm_cols = tuple(np.empty((n_vox, k)) for _ in range(3))  # the seeds' normals, per pass
    n_iterations = max(1, settings.supervoxel_iterations)
    for iteration in range(n_iterations):
        n_s = seed_pos.shape[0]
        # the tree's k-nearest query, not a search of pairs: the pairs within the bound (10 a
        # voxel) from sparse_distance_matrix, or from a grid of seed cells (26 candidates a
        # voxel) with their distances and a sort, took 0.9-1.2x its time (mOSD, issue 39)
        dist, nb = cKDTree(seed_pos).query(cent, k=k, distance_upper_bound=1.5 * seed_m)
        if k == 1:
            dist, nb = dist[:, None], nb[:, None]
        # a missing neighbour has index n_s and distance inf: its cost is inf whatever the
        # rest (spatial_importance > 0), so no mask; it reads a zero normal appended at n_s
        # take: faster than [nb]; into the same three (V, k) buffers each pass, and the dot
        # product below in place in them: fresh (V, k) arrays cost their first touch of
        # every page here, a fifth of the work outside the tree's query (issue 39)
        for j in range(3):
            np.take(np.append(seed_nrm[:, j], 0.0), nb, out=seed_nrm_cols[j], mode="clip")  # nb <= n_s: no clipping
        # spatial_importance * dist / seed_m + normal_importance * (1 - |n . n_s|), the
        # same operations in the same order, in place; the normals' dot products summed
        # as einsum("vj,vkj->vk") sums them (_dot3: (x0 y0 + x2 y2) + x1 y1, each
        # product the same float whichever factor comes first)
        cost = np.multiply(settings.spatial_importance, dist, out=dist)
        cost /= seed_m
        normal_term, nrm_y, nrm_z = seed_nrm_cols
        normal_term *= voxel_nrm[0]
        nrm_z *= voxel_nrm[2]
        normal_term += nrm_z
        nrm_y *= voxel_nrm[1]
        normal_term += nrm_y
        np.abs(normal_term, out=normal_term)
        if iteration == 0 and spread is not None:
            # a crease's seed: the alignment with its tensor, every other pair as it was
            at_v, at_k = np.nonzero(np.take(spread[1], nb))
            columns = tuple(np.take(c[:, 0], at_v) for c in voxel_nrm)
            normal_term[at_v, at_k] = _tensor_alignment(spread[0], nb[at_v, at_k], columns)
        np.subtract(1.0, normal_term, out=normal_term)
        np.multiply(settings.normal_importance, normal_term, out=normal_term)
        cost += normal_term
        if seed_lab is not None and voxel_lab is not None:
            nb_safe = np.where(nb < n_s, nb, 0)
            cost = cost + settings.color_importance * np.linalg.norm(voxel_lab[:, None, :] - seed_lab[nb_safe], axis=2)
        picked = np.take(nb, rows + np.argmin(cost, axis=1))  # nb[row, argmin] of the flat (V * k) array
        labels = np.where(picked < n_s, picked, -1)
        if trace is not None:
            if iteration == 0:
                trace.append(seed_vox.copy())
            two = (
                np.partition(cost, 1, axis=1)[:, :2] if k > 1 else np.column_stack((cost[:, 0], np.full(n_vox, np.inf)))
            )
            with np.errstate(invalid="ignore"):  # inf - inf: a voxel with no seed
                trace += [labels.copy(), two[:, 1] - two[:, 0]]
        if iteration == n_iterations - 1:
            break  # the last assignment is the answer: seeds moved after it would serve none
        # move the seeds to the mean of their voxels
        used = labels >= 0
        every = bool(used.all())
        lab = labels if every else np.compress(used, labels)
        cnt = np.bincount(lab, minlength=n_s)
        keep = cnt > 0

        new_pos = _seed_sums(cent, lab, None if every else used, n_s)
        new_nrm = _seed_sums(normals, lab, None if every else used, n_s)
        seed_pos = np.where(keep[:, None], new_pos / np.maximum(cnt, 1)[:, None], seed_pos)
        nn = np.linalg.norm(new_nrm, axis=1)
        seed_nrm = np.where((keep & (nn > 1e-9))[:, None], new_nrm / np.maximum(nn, 1e-9)[:, None], seed_nrm)
        if seed_lab is not None and voxel_lab is not None:
            seed_lab = np.where(
                keep[:, None],
                _seed_sums(voxel_lab, lab, None if every else used, n_s) / np.maximum(cnt, 1)[:, None],
                seed_lab,
            )

    # connectivity: pieces of one supervoxel that do not touch become separate pieces;
    # unassigned voxels form pieces of their own
    e = vox.edges
    same = labels[e[:, 0]] == labels[e[:, 1]]
    piece = components(n_vox, np.compress(same, e, axis=0))  # rows by a mask: compress is several times faster
    # the piece holding most of a supervoxel's voxels keeps it; other pieces are orphans
    n_pieces = int(piece.max()) + 1 if n_vox else 0
    piece_size = np.bincount(piece, minlength=n_pieces)
    piece_label = np.full(n_pieces, -1, dtype=np.int64)
    piece_label[piece] = labels
    main = np.zeros(n_pieces, dtype=bool)
    has = piece_label >= 0
    if has.any():
        order = np.lexsort((-piece_size[has], piece_label[has]))
        pl = piece_label[has][order]
        firsts = np.ones(pl.shape[0], dtype=bool)
        firsts[1:] = pl[1:] != pl[:-1]
        main[np.flatnonzero(has)[order[firsts]]] = True
    # an orphan piece joins the main piece it shares most adjacencies with (one pass)
    pa, pb = piece[e[:, 0]], piece[e[:, 1]]
    cross = pa != pb
    pa, pb = np.compress(cross, pa), np.compress(cross, pb)
    pairs = np.concatenate([np.stack([pa, pb], 1), np.stack([pb, pa], 1)])
    # rows by a mask: np.compress, several times faster than boolean indexing of rows
    pairs = np.compress(~main[pairs[:, 0]] & main[pairs[:, 1]], pairs, axis=0)
    target = np.arange(n_pieces)
    if pairs.shape[0]:
        keys, cnt = _distinct(_pair_keys(pairs, n_pieces))
        uniq = _pairs_of(keys, n_pieces)
        order = np.lexsort((-cnt, uniq[:, 0]))
        u = uniq[order]
        firsts = np.ones(u.shape[0], dtype=bool)
        firsts[1:] = u[1:, 0] != u[:-1, 0]
        target[u[firsts, 0]] = u[firsts, 1]
    final = target[piece]
    # the rank of each voxel's piece among the pieces left: np.unique's inverse, unsorted
    present = np.zeros(n_pieces, dtype=bool)
    present[final] = True
    return (np.cumsum(present) - 1)[final]


@dataclass(frozen=True, eq=False)
class Supervoxels:
    voxel_label: np.ndarray  # (V,) supervoxel of each voxel
    centroids: np.ndarray  # (S, 3)
    normals: np.ndarray  # (S, 3) unit, facing the viewpoint
    n_voxels: np.ndarray  # (S,) voxels per supervoxel
    edges: np.ndarray  # (A, 2) adjacent supervoxel pairs, i < j


def supervoxel_stats(
    vox: VoxelCloud, voxel_normals_: np.ndarray, labels: np.ndarray, viewpoint: np.ndarray
) -> Supervoxels:
    """Centroid and normal (PCA of its voxel centroids; the mean voxel normal when the
    patch is too small or too thin for PCA) of every supervoxel, and their adjacency."""
    n_sv = int(labels.max()) + 1 if labels.size else 0
    cent = vox.centroids
    cnt = np.bincount(labels, minlength=n_sv).astype(np.float64)
    mean = np.stack([np.bincount(labels, weights=cent[:, k], minlength=n_sv) for k in range(3)], axis=1) / cnt[:, None]
    d = cent - mean[labels]
    cov = np.zeros((n_sv, 3, 3))
    for a in range(3):
        for b in range(a, 3):
            cov[:, a, b] = cov[:, b, a] = np.bincount(labels, weights=d[:, a] * d[:, b], minlength=n_sv)
    evals, evecs = np.linalg.eigh(cov)
    pca_n = evecs[:, :, 0]
    mean_n = np.stack(
        [np.bincount(labels, weights=voxel_normals_[:, k], minlength=n_sv) for k in range(3)], axis=1, dtype=np.float64
    )
    mean_n /= np.maximum(np.linalg.norm(mean_n, axis=1, keepdims=True), 1e-12)
    # PCA needs a patch that spans two directions. The switch is a step: on
    # uois_image_0000 (perturbation seed 5) one voxel more took a supervoxel of 17 from a
    # ratio of 3.44 to 4.27 and turned its normal by 36 degrees (benchmarks/flips.py
    # --margins). Blending the two normals by log(ratio) over 2..8, or over 2.83..5.66,
    # mended that flip and gained one foreign choose object (59 -> 60 of 89), but lost
    # renders in three choose families (exactly right: gap_3mm_across 7 -> 5 or 6 %,
    # wide_objects 88 -> 87 %, dense_mix 52 -> 51 % or small_on_large 99 -> 98 %): not
    # taken (hC-flips).
    good = (cnt >= 4) & (evals[:, 1] > 4.0 * np.maximum(evals[:, 0], 1e-12))
    normals = np.where(good[:, None], pca_n, mean_n)
    normals = orient_towards(normals, mean, viewpoint)
    e = vox.edges
    la, lb = labels[e[:, 0]], labels[e[:, 1]]
    cross = la != lb
    la, lb = np.compress(cross, la), np.compress(cross, lb)
    # the keys of `_pair_keys` of the rows (min, max), without the rows
    keys = np.minimum(la, lb) * n_sv + np.maximum(la, lb)
    pairs = _pairs_of(_distinct(keys)[0], n_sv) if keys.shape[0] else np.zeros((0, 2), np.int64)
    return Supervoxels(labels, mean, normals, cnt.astype(np.int64), pairs)


def stage_voxel_normals(
    vox: VoxelCloud, viewpoint: np.ndarray, settings: SegmentSettings, size: SegmentSize
) -> np.ndarray:
    """(V, 3) the voxel normals the stage uses: `voxel_normals` (the 30 nearest voxel
    centroids), or with ``settings.normal_stencil`` `weighted_voxel_normals`; also what
    benchmarks/stability.py compares between runs."""
    if settings.normal_stencil:
        return weighted_voxel_normals(
            vox, size.normal_radius_m, size.voxel_m, viewpoint, settings.normal_full_weight_points
        )
    return voxel_normals(vox.centroids, size.normal_radius_m, viewpoint)


def compute_supervoxels(
    vox: VoxelCloud, viewpoint: np.ndarray, settings: SegmentSettings, size: SegmentSize | None = None
) -> Supervoxels:
    """Stage 3a: voxel normals, VCCS clustering, supervoxel centroids/normals/adjacency.
    ``size``: the frame's seed and normal radius (`SegmentSize.of(settings)` when None)."""
    size = size if size is not None else SegmentSize.of(settings)
    normals = stage_voxel_normals(vox, viewpoint, settings, size)
    labels = supervoxel_labels(vox, normals, settings, size)
    return supervoxel_stats(vox, normals, labels, viewpoint)
