"""Stage 1: finite points and outlier removal.

Kinect-style depth sensors produce "flying pixels" between a foreground edge and the
background; left in, they bridge objects and the table. The original pipeline removed
them with a statistical filter over a fixed k = 10 neighbours, which also removes most
of the far, sparsely sampled points (parameters.md). Ours judges every point by a radius
proportional to its range, so the test means the same thing near and far.
"""

from __future__ import annotations

import numpy as np

from clearcli.errors import SettingsError
from clearcli.perception.raster import flat_step
from clearcli.settings.segment import SegmentSettings


def finite_mask(points: np.ndarray) -> np.ndarray:
    """(N,) bool: rows with finite x, y and z. One column at a time: ``.all(axis=1)``
    over (N, 3) is twenty times slower (7 ms on a 640x480 frame)."""
    finite = np.isfinite(points[:, 0])
    for k in range(1, points.shape[1]):
        finite &= np.isfinite(points[:, k])
    return finite


# Pixels per block of rows in `_organized_neighbor_counts`: the block's ten or so
# float32 planes (2.4 MB) stay in the cache through the ~60 passes over them, where a
# whole 1280x720 frame's (37 MB) went to memory on each, and reused buffers spare the
# fresh pages of every whole-frame temporary. Measured on 640x480 and 1280x720 frames:
# 30k-100k pixels equally fast; 4k pays NumPy's per-call cost (2-3x slower), whole
# frames with the same buffers 2.5-3x slower.
_BLOCK_PIXELS = 60_000


def _organized_neighbor_counts(points: np.ndarray, shape: tuple[int, int], radius_at_1m_m: float) -> np.ndarray:
    """Number of the 8 pixel neighbours of each pixel within the range-scaled radius.

    The radius of a pair uses their mean range so the relation is symmetric; that lets
    4 of the 8 offsets do all the work (each hit counts for both pixels). Blocks of rows
    at a time (`_BLOCK_PIXELS`), each with the row below it for the downward offsets.
    """
    # at most 8: counted in uint8, adding the hits' bytes (a bool's byte is 0 or 1), where
    # adding bools to int16 went through a cast on every pass
    counts_image = np.zeros(shape, dtype=np.uint8)
    # Only the box of the pixels with a finite depth: a pixel without one has a NaN or
    # infinite range and no neighbour, so no pair out of the box is a hit. A fifth to a
    # third of an mOSD frame's rows have no depth at all; the counts 247 -> 206 ms over
    # mOSD's 50 and the 9 RealSense frames (issue 39)
    finite = np.isfinite(points[:, 2]).reshape(shape)
    rows_in = np.flatnonzero(finite.any(axis=1))
    if rows_in.size == 0:
        return counts_image.reshape(-1).astype(np.int16)
    cols_in = np.flatnonzero(finite.any(axis=0))
    box = (slice(int(rows_in[0]), int(rows_in[-1]) + 1), slice(int(cols_in[0]), int(cols_in[-1]) + 1))
    # one contiguous float32 plane per coordinate: the squared lengths below are the sums
    # einsum("ijk,ijk->ij") gave on (h, w, 3) rows, in its order ((x x + y y) + z z), in
    # half its time
    grid = points.reshape(shape[0], shape[1], 3)[box]
    h, w = grid.shape[0], grid.shape[1]
    counts = np.zeros(h * w, dtype=np.uint8)
    k2 = np.float32((radius_at_1m_m * 0.5) ** 2)
    rows = max(1, _BLOCK_PIXELS // max(w, 1))
    size = (rows + 1) * w
    buf = [np.empty(size, dtype=np.float32) for _ in range(4)]  # d, d2, rr, limit
    hit_buf = np.empty(size, dtype=bool)
    # Each offset as one step along the block's pixels in row order (1, w - 1, w, w + 1):
    # one run over contiguous memory per pass, where (rows, columns) views went a row at
    # a time: the counts 304 -> 233 ms over mOSD's 50 and the 9 RealSense frames, the
    # filter step 382 -> 326 ms over mOSD's 50 (issue 39). The pairs that wrap to the
    # wrong row (raster.flat_step) have their hits struck out.
    steps = [flat_step(offset, w) for offset in ((0, 1), (1, -1), (1, 0), (1, 1))]
    # A point beyond 1e19 m (absurd intrinsics: a principal point at 1e30 pixels) squares
    # to inf, and inf - inf is NaN: such a point has no neighbour, silently (NaN compares False)
    with np.errstate(over="ignore", invalid="ignore"):
        for r0 in range(0, h, rows):
            r1 = min(r0 + rows, h)  # the block's rows; the pairs start in them
            r_end = min(r1 + 1, h)  # and the row below, where the downward pairs end
            x, y, z = (grid[r0:r_end, :, k].astype(np.float32).reshape(-1) for k in range(3))
            rng = np.sqrt((x * x + y * y) + z * z)  # NaN for invalid pixels
            block = counts[r0 * w : r_end * w]
            n_start = (r1 - r0) * w  # the pixels whose pairs start in the block
            for step, wrap_col in steps:
                n = min(n_start, x.shape[0] - step)
                if n <= 0:
                    continue
                d, d2, rr, limit = (b[:n] for b in buf)
                hit = hit_buf[:n]
                np.subtract(x[:n], x[step : step + n], out=d)
                np.multiply(d, d, out=d2)
                np.subtract(y[:n], y[step : step + n], out=d)
                d *= d
                d2 += d
                np.subtract(z[:n], z[step : step + n], out=d)
                d *= d
                d2 += d
                np.add(rng[:n], rng[step : step + n], out=rr)
                np.multiply(k2, rr, out=limit)
                limit *= rr
                np.less(d2, limit, out=hit)  # NaN compares False
                if wrap_col >= 0:
                    hit[wrap_col::w] = False
                hit8 = hit.view(np.uint8)
                block[:n] += hit8
                block[step : step + n] += hit8
    counts_image[box] = counts.reshape(h, w)
    return counts_image.reshape(-1).astype(np.int16)


def depth_radius_mask(
    points: np.ndarray, shape: tuple[int, int] | None, radius_at_1m_m: float, min_neighbors: int
) -> np.ndarray:
    """(N,) bool: finite points with at least ``min_neighbors`` neighbours within
    ``radius_at_1m_m * range``. Pixel neighbours when organized, a KD-tree otherwise."""
    if shape is not None and shape[0] > 1 and shape[0] * shape[1] == points.shape[0]:
        counts = _organized_neighbor_counts(points, shape, radius_at_1m_m)
        if min_neighbors >= 1:  # only finite pixels have neighbours (NaN compares False)
            return counts >= min_neighbors
        return finite_mask(points) & (counts >= min_neighbors)
    finite = finite_mask(points)
    from scipy.spatial import cKDTree

    idx = np.flatnonzero(finite)
    p = points[idx].astype(np.float64)
    if p.shape[0] == 0:
        return finite
    out = np.zeros(points.shape[0], dtype=bool)
    if min_neighbors <= 0:
        out[idx] = True
        return out
    tree = cKDTree(p)
    # a cloud that is not a camera's (range from the origin means nothing, e.g. a z-up
    # cloud in the table's frame, or one thinned on a grid): never judge a point by a
    # radius under 2.5 typical point spacings
    spacing = float(np.median(tree.query(p[:: max(1, p.shape[0] // 2000)], k=2)[0][:, 1]))
    radius = np.maximum(radius_at_1m_m * np.linalg.norm(p, axis=1), 2.5 * spacing)
    # At least m neighbours within the radius <=> the m-th nearest other point is within
    # it: a k-nearest query with k = m + 1 (the point itself first) costs the same
    # however dense the cloud is, where counting every point in the ball grew with the
    # density (merged views, dense scanners: minutes for a few million points).
    dist, _ = tree.query(p, k=min_neighbors + 1, distance_upper_bound=float(radius.max()) * (1 + 1e-9), workers=-1)
    out[idx] = dist[:, min_neighbors] <= radius
    return out


def statistical_mask(points: np.ndarray, k: int, std_mul: float) -> np.ndarray:
    """(N,) bool: the original statistical outlier removal (PCL semantics): a point
    survives when its mean distance to its k nearest neighbours is at most the mean of
    those distances over the cloud plus ``std_mul`` standard deviations."""
    from scipy.spatial import cKDTree

    finite = finite_mask(points)
    idx = np.flatnonzero(finite)
    out = np.zeros(points.shape[0], dtype=bool)
    if idx.size <= k:
        out[idx] = True
        return out
    p = points[idx].astype(np.float64)
    dist, _ = cKDTree(p).query(p, k=k + 1, workers=-1)
    mean_d = dist[:, 1:].mean(axis=1)
    out[idx] = mean_d <= mean_d.mean() + std_mul * mean_d.std()
    return out


def clean_mask(points: np.ndarray, shape: tuple[int, int] | None, settings: SegmentSettings) -> np.ndarray:
    """Stage 1: (N,) bool of the points that go on to table detection."""
    method = settings.outlier_method
    if method == "depth_radius":
        return depth_radius_mask(points, shape, settings.outlier_radius_at_1m_m, settings.outlier_min_neighbors)
    if method == "statistical":
        return statistical_mask(points, settings.outlier_k, settings.outlier_std)
    if method == "none":
        return finite_mask(points)

    raise SettingsError(f"settings: [segment] outlier_method must be depth_radius, statistical or none, got {method!r}")
