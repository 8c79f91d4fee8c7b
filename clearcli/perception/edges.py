"""Stage 3a': depth discontinuities on the pixel grid cut the voxel adjacency (ours,
after the depth-discontinuity edges of PCL's OrganizedEdgeBase).

Two objects of equal height standing a few millimetres apart are one surface to a 5 mm
voxel grid: their tops are coplanar, the grid's 26-neighbourhood bridges the gap, and
LCCP sees only flat, convex adjacencies. In an organized frame the gap is plain to see:
the pixels between the two tops look through to the table, centimetres farther, or lost
their depth. So, before the supervoxels:

1. The object points' pixels are joined to their 8 neighbours when both are object
   points and their ranges differ by at most ``depth_edge_rel`` of the nearer range
   (PCL's relative threshold: it grows with the depth noise and with the depth step of
   a surface seen at a slant). The connected pieces of that pixel graph are the
   surfaces the image shows unbroken.
2. Each voxel takes the piece most of its points are in.
3. A voxel adjacency between two voxels of different pieces is dropped, when both pieces
   are large enough to be objects (``depth_edge_min_piece_m2`` of voxels); a piece of a
   few stray pixels (a flying pixel at a silhouette) cuts nothing.

Objects that touch stay joined: at a contact the depth is continuous. A nearer object
hiding part of a farther one breaks the farther one's pixels apart too, but those
pieces are also apart in space unless the occluder is thin; `occlusion.py` joins
pieces that continue each other behind a nearer object, after LCCP.

Skipped on an unorganized cloud (no pixel grid): the result then equals the result with
the stage off.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from clearcli.perception.graph import components
from clearcli.perception.raster import flat_step
from clearcli.perception.supervoxels import VoxelCloud

# 4 of the 8 neighbour offsets (row, column): each undirected pixel pair found once; the
# first joins a pixel to the next in its row
_PIXEL_OFFSETS = ((0, 1), (1, 0), (1, 1), (1, -1))


def pixel_pieces(
    points: np.ndarray, shape: tuple[int, int], point_index: np.ndarray, rel: float, xyz: np.ndarray | None = None
) -> np.ndarray:
    """(M,) piece of each of the M points ``point_index`` (flat pixel indices into the
    organized ``points`` of ``shape``): connected over 8-neighbour pixels of the set whose
    ranges differ by at most ``rel`` times the nearer one.

    With ``point_index`` in raster order (as the stages pass it) a pixel joined to the
    next in its row is the next point: such runs are numbered by a running count and
    the pairs between rows go to `components` once per pair of runs next to each other
    in their list (a tenth of the pixel pairs on an mOSD frame). The ranges are compared on an
    image of them (NaN off the set, which compares False), so no pair's ranges are
    gathered; the pieces are numbered as `components` numbers them, in order of their
    first point. ``xyz``: ``points[point_index]`` in float64 when the caller has them
    (the segmentation's points above the table), else gathered here."""
    m = point_index.shape[0]
    # the pairs lie within the set's bounding box: images over that box only, the pairs
    # in the same raster order over a fraction of the pixels
    # the quotient, and the remainder from it: np.divmod divides twice as slowly
    row = point_index // shape[1]
    col = point_index - row * shape[1]
    top, left = (int(row.min()), int(col.min())) if m else (0, 0)
    height, width = (int(row.max()) + 1 - top, int(col.max()) + 1 - left) if m else (0, 0)
    at = (row - top) * width + (col - left)
    # rows by index: take is several times faster than a[idx]; the caller's copy spares
    # gathering them again (0.4 ms a frame of the edges step, issue 39)
    p = xyz if xyz is not None else np.take(points, point_index, axis=0).astype(np.float64)
    # np.linalg.norm(p, axis=1)'s sums in its order, a fifth of its time (no (M, 3) squares)
    rng = np.sqrt((p[:, 0] * p[:, 0] + p[:, 1] * p[:, 1]) + p[:, 2] * p[:, 2])
    if not (m > 1 and bool((point_index[1:] > point_index[:-1]).all())):
        return _every_pair_pieces(at, rng, height, width, rel)
    r = np.full(height * width, np.nan)
    r[at] = rng
    n_pixels = height * width
    diff_buf, limit_buf, hit_buf = np.empty(n_pixels), np.empty(n_pixels), np.empty(n_pixels, dtype=bool)

    # Each offset as one step along the box's pixels in raster order (1, width - 1, width,
    # width + 1), over the flat images: one run over contiguous memory per pass, where
    # (rows, columns) views went a row at a time and boolean indexing of a 2-D view is
    # slow; with the buffers below and the division, pixel_pieces 142 -> 117 ms over
    # mOSD's 50 and the 9 RealSense frames (issue 39). The pairs that wrap to the wrong
    # row (raster.flat_step) are struck out, and the pairs left come in the (row, column)
    # order of the views.
    def near(step: int, wrap_col: int) -> np.ndarray:
        """(max(0, n_pixels - step),) bool: the pixel and the one ``step`` after it are
        both in the set with near ranges (NaN compares False), False for the pixels of
        column ``wrap_col`` (-1: none), whose step wraps to the wrong row."""
        n = max(0, n_pixels - step)
        ra, rb = r[:n], r[step : step + n]
        # |ra - rb| <= rel * min(ra, rb), the same operations into reused buffers
        diff, limit, hit = diff_buf[:n], limit_buf[:n], hit_buf[:n]
        np.abs(np.subtract(ra, rb, out=diff), out=diff)
        np.multiply(rel, np.minimum(ra, rb, out=limit), out=limit)
        np.less_equal(diff, limit, out=hit)
        if wrap_col >= 0:
            hit[wrap_col::width] = False
        return hit

    # raster order: a pixel joined to the one before it in its row is the point before
    # (never the first of a row: the step from the row before's last column wraps)
    joined_img = np.zeros(n_pixels, dtype=bool)
    joined_img[1:] = near(*flat_step(_PIXEL_OFFSETS[0], width))
    start = ~np.take(joined_img, at)
    start[0] = True  # the first point has none before it
    run = np.cumsum(start) - 1
    runs = np.zeros(n_pixels, dtype=np.int64)  # off the set: never read (near is False)
    runs[at] = run
    ra_parts, rb_parts = [], []
    for step, wrap_col in (flat_step(offset, width) for offset in _PIXEL_OFFSETS[1:]):
        hit = near(step, wrap_col)
        n = hit.shape[0]
        # a pair whose two pixels are each joined to the one before in their row, where
        # the pair before it was near too, joins the same two runs: left out here, where
        # it costs a byte a pixel, not gathered (the pieces depend only on what is joined).
        # The pair before the first of a row's pairs is struck (it wraps) or its pixels
        # are the first of their rows (never joined to the one before): no test across rows
        hit[1:] &= ~(hit[:-1] & joined_img[1:n] & joined_img[step + 1 : step + n])
        ra_parts.append(runs[:n][hit])
        rb_parts.append(runs[step : step + n][hit])
    ra, rb = np.concatenate(ra_parts), np.concatenate(rb_parts)
    # one pair per pair of runs next to each other in the list: pairs along a row come
    # one after the other, so a repeat of the pair before it adds no join
    if ra.size > 1:
        new = np.empty(ra.size, dtype=bool)
        new[0] = True
        np.not_equal(ra[1:], ra[:-1], out=new[1:])
        new[1:] |= rb[1:] != rb[:-1]
        ra, rb = np.compress(new, ra), np.compress(new, rb)
    return components(int(run[-1]) + 1, np.stack([ra, rb], axis=1))[run]


def _every_pair_pieces(at: np.ndarray, rng: np.ndarray, height: int, width: int, rel: float) -> np.ndarray:
    """`pixel_pieces` of points out of raster order: every near pixel pair an edge.
    ``at``: each point's flat pixel in the (height, width) box, ``rng``: its range."""
    m = at.shape[0]
    where = np.full(height * width, -1, dtype=np.int64)
    where[at] = np.arange(m)
    img = where.reshape(height, width)

    def pairs(dv: int, du: int) -> np.ndarray:
        a = img[: height - dv, max(0, -du) : width - max(0, du)].ravel()
        b = img[dv:, max(0, du) : width - max(0, -du)].ravel()
        both = (a >= 0) & (b >= 0)
        a, b = a[both], b[both]
        ra, rb = rng[a], rng[b]
        near = np.abs(ra - rb) <= rel * np.minimum(ra, rb)
        return np.stack((a[near], b[near]), axis=1)

    return components(m, np.concatenate([pairs(dv, du) for dv, du in _PIXEL_OFFSETS]))


def _voxel_piece(point_voxel: np.ndarray, point_piece: np.ndarray, n_voxels: int) -> np.ndarray:
    """(V,) the piece most of each voxel's points are in (ties: the lower piece).

    Most voxels' points all lie in one piece (a voxel inside one surface): those read
    it from their lowest and highest piece (`np.minimum.at` / `np.maximum.at`, no
    sort); only the voxels of two pieces or more (along a depth edge) count their
    points' pieces (`_counted_piece`, on their points alone)."""
    if point_voxel.size == 0:
        return np.zeros(n_voxels, dtype=np.int64)
    n_pieces = int(point_piece.max()) + 1
    lo = np.full(n_voxels, n_pieces, dtype=np.int64)  # a voxel without points: none (0 below)
    hi = np.full(n_voxels, -1, dtype=np.int64)
    np.minimum.at(lo, point_voxel, point_piece)
    np.maximum.at(hi, point_voxel, point_piece)
    out = np.where(lo == hi, lo, 0)
    mixed = lo < hi
    if mixed.any():
        sel = np.flatnonzero(mixed[point_voxel])
        out[mixed] = _counted_piece(point_voxel[sel], point_piece[sel], n_voxels)[mixed]
    return out


def _counted_piece(point_voxel: np.ndarray, point_piece: np.ndarray, n_voxels: int) -> np.ndarray:
    """`_voxel_piece` by counting every (voxel, piece) pair of the points (one sort)."""
    key = point_voxel.astype(np.int64) * (int(point_piece.max()) + 1) + point_piece
    uniq, count = np.unique(key, return_counts=True)
    n_pieces = int(point_piece.max()) + 1
    vox, piece = _most_counted(uniq // n_pieces, uniq % n_pieces, count)
    out = np.zeros(n_voxels, dtype=np.int64)
    out[vox] = piece
    return out


def _most_counted(row: np.ndarray, col: np.ndarray, count: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each distinct ``row`` (``row``, ``col``: `np.unique`'s keys unpacked, sorted by
    row, then column), the ``col`` of the largest ``count`` (ties: the lower column), as
    (rows, their columns): the first entry reaching its row's maximum, in one pass (the
    same entries as a lexsort by row, descending count and column, several times faster)."""
    if row.size == 0:
        return row, col
    starts = np.flatnonzero(np.concatenate(([True], row[1:] != row[:-1])))
    best = np.maximum.reduceat(count, starts)
    hit = np.flatnonzero(count == np.repeat(best, np.diff(np.append(starts, row.size))))
    first = np.concatenate(([True], row[hit[1:]] != row[hit[:-1]]))
    return row[hit[first]], col[hit[first]]


def _join_small(piece: np.ndarray, large: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """A voxel of a small piece (stray pixels at a silhouette) joins the large piece most
    of its adjacent voxels are in: it would otherwise bridge the cut it stands in."""
    # each adjacency both ways, (small, large) pairs only, without the (2E, 2) copy
    e0, e1 = edges[:, 0], edges[:, 1]
    pa, pb = piece[e0], piece[e1]
    la, lb = large[pa], large[pb]
    fwd, bwd = ~la & lb, la & ~lb
    if not (fwd.any() or bwd.any()):
        return piece
    # the order of the pairs is np.unique's to choose: the same keys and counts
    v = np.concatenate((np.compress(fwd, e0), np.compress(bwd, e1)))
    p = np.concatenate((np.compress(fwd, pb), np.compress(bwd, pa)))
    n_pieces = int(piece.max()) + 1
    uniq, count = np.unique(v * n_pieces + p, return_counts=True)
    vv, pp = _most_counted(uniq // n_pieces, uniq % n_pieces, count)
    out = piece.copy()
    out[vv] = pp
    return out


def cut_depth_edges(
    vox: VoxelCloud,
    points: np.ndarray,
    shape: tuple[int, int],
    point_index: np.ndarray,
    rel: float,
    min_piece_voxels: int,
    xyz: np.ndarray | None = None,
) -> VoxelCloud:
    """``vox`` without the adjacencies that cross a depth discontinuity between two
    large pieces (module docstring). ``point_index``: the frame index of each voxelized
    point, in the order of ``vox.point_voxel``; ``xyz``: those points in float64 when the
    caller has them (`pixel_pieces`)."""
    if vox.edges.shape[0] == 0 or point_index.size == 0:
        return vox
    piece_of_point = pixel_pieces(points, shape, point_index, rel, xyz)
    piece = _voxel_piece(vox.point_voxel, piece_of_point, vox.n_voxels)
    large = np.bincount(piece) >= min_piece_voxels
    piece = _join_small(piece, large, vox.edges)
    a, b = piece[vox.edges[:, 0]], piece[vox.edges[:, 1]]
    cut = (a != b) & large[a] & large[b]
    if not cut.any():
        return vox
    # rows by a mask: np.compress, several times faster than boolean indexing of rows
    return dataclasses.replace(vox, edges=np.compress(~cut, vox.edges, axis=0))
