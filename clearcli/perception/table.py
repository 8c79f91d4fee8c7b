"""Stage 2: the table. RANSAC planes, the support surface among them, its 2D convex hull
and the polygonal prism of points above it.

A frame that is not cropped to the table holds several planes (floor, walls, other
tables, big flat objects). The support surface is the candidate with the most points
standing on it (above it, inside its hull, within a hand's reach), after the points of
every candidate plane are set aside; a wall's "objects" are mostly the table, which is
itself a plane, and a book's hull holds little.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, replace
from functools import lru_cache

import numpy as np

from clearcli.errors import SceneError
from clearcli.perception.raster import dilate_square, flat_step, label_8
from clearcli.perception.support import MAT_MIN_AREA_M2, Surface, choose, standing_on
from clearcli.perception.types import PlaneVerdict, TablePlane
from clearcli.settings.segment import SegmentSettings
from clearcli.transforms import cross3

# Height band (m) in which points count as "standing on" a candidate plane when scoring
# candidates: tabletop objects, not furniture standing on a floor.
_SCORE_HEIGHT_M = 0.4
# Below this camera-to-plane distance (m) the cloud is not in a camera frame (e.g. a
# z-up cloud in the table's own frame): orient the plane by where the objects are.
_MIN_CAMERA_HEIGHT_M = 0.05
# RANSAC works on at most this many points (a regular subsample)
_RANSAC_SAMPLE = 30000
# off-plane margin per squared metre of range when scoring candidates: about three
# standard deviations of a Kinect's depth noise (1.2 mm + 1.9 mm (z - 0.4)^2)
_NOISE_PER_M2 = 0.005
_RANSAC_EVAL = 1000
_RANSAC_CHUNK = 50
_REFITS = 10  # least-squares refits of a RANSAC plane at most (they settle in a few)
# Off-plane points within this of a candidate's hull boundary count neither as standing on
# it nor as behind it: they show its edge, not what it holds. The sides of a slab seen over
# its edge (a board as big as the table) lie there below its top, and the table in front
# of a wall (or of a big box's front face) lies there off the wall's bottom edge; both
# within a few mm. What stands on a table, or under one seen from below, is inside.
_EDGE_BAND_M = 0.02
# points resting on a support: within this past its noise band (the feet of what stands on
# it). Objects on a table: hundreds to thousands of points on the choose part; a face seen
# with things before it (a desk's front behind a table): 0 on the self-made desks
_RESTING_M = 0.03
# a support the image would be turned for gives way to an upright one with this many
# times the points resting on it (and `min_obj`): desks behind tables 0 against 248-335
_RESTING_OVER = 4
# A RANSAC plane smaller than table_min_area_m2 lying along a candidate already found
# (parallel within `_RESIDUE_COS`, its inliers' median within `_RESIDUE_M` of that plane)
# is the residue of that surface's own noise: a far floor's depth noise (3 sigma 13 mm at
# 1.7 m) leaves bands 1-2 cm off its plane that RANSAC finds next. It does not use up one
# of the plane_candidates tries (at most as many again are spent on residues), or a raised
# surface over such a floor is never tried (self-made raised_surface(4): the floor's two
# residues 12 mm off took the last tries, the stool's top was never a candidate).
_RESIDUE_COS = float(np.cos(np.radians(15.0)))
_RESIDUE_M = 0.03
# beyond_the_edge(): pieces of the plane smaller than this many pixels are not judged; a
# piece is beyond a gap when at least this many looks at the gap see through it, and
# this many times as many as see something nearer. 1.25 (2 until stop 61): more see
# through than nearer, with a margin; the table's own objects at its far edge hide part
# of a gap (desk_level_behind(2), oblique RealSense: 30 through, 19 nearer), while a
# piece of the table cut off behind an object shows 0-2 through against 20-650 nearer
# on mOSD, the fixtures and the foreign frames
_EDGE_MIN_PIECE_PX = 200
_EDGE_MIN_CELLS = 5
_EDGE_RATIO = 1.25
# ... and a table pixel more than this far under the plane belongs to no piece (as one
# at a depth jump): a face's top beyond a narrow gap, seen over the table's edge, lies in
# the plane's band under the plane and joined the bench behind to the table pixel by
# pixel (desk_level_behind(3, 9); half the band: a table's noise crosses it in scattered
# pixels, which split no piece)
_EDGE_UNDER_M = 0.005
# hull_vertices(): below this many points Qhull runs on them all; above, on the points
# not more than this far (m) inside the octagon of extreme points (rounding is 1e-16 m)
_HULL_FILTER_FROM = 64
_HULL_INSIDE_M = 1e-9
# inside_convex_raster(): its cells (m)
_RASTER_CELL_M = 0.005


@dataclass(frozen=True, eq=False)
class TableFit:
    plane: TablePlane
    polygon_2d: np.ndarray  # (K, 2) hull vertices, counter-clockwise, in (u, v) plane coordinates
    origin: np.ndarray  # (3,) a point on the plane, the 2D origin
    basis: np.ndarray  # (2, 3) rows u, v: in-plane unit axes; u x v = normal
    camera_is_origin: bool  # the cloud is in a camera frame (sensor at the origin, above the table)
    # every plane RANSAC found and what became of it (the chosen one first), for --json
    planes: tuple[PlaneVerdict, ...] = ()
    # the rasters of its polygon drawn so far (`_raster`, by margin and cell size): the
    # table's stage and _exclude test points against the same grown hull three times a
    # frame. Not an argument: a fit made from this one by `replace` draws its own.
    rasters: dict[tuple[float, float], np.ndarray] = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def polygon(self) -> np.ndarray:
        """(K, 3) hull vertices on the plane, in the sensor frame."""
        return self.origin + self.polygon_2d @ self.basis

    def to_2d(self, points: np.ndarray) -> np.ndarray:
        return project(points, self.basis) - self.origin @ self.basis.T

    def inside(self, points: np.ndarray, margin_m: float = 0.0, of_n: int | None = None) -> np.ndarray:
        """`inside_convex_raster` of the points in the plane's coordinates. ``of_n``: the
        points are a part of that many, and get the answers a test of them all gives (the
        raster or the exact test is chosen by the count, and they differ within a cell of
        the boundary)."""
        return self.inside_2d(self.to_2d(points), margin_m, of_n)

    def inside_2d(self, xy: np.ndarray, margin_m: float = 0.0, of_n: int | None = None) -> np.ndarray:
        """`inside` of points given in the plane's coordinates (``to_2d``'s (N, 2)), for
        a caller that has them already."""
        return _inside_raster_xy(xy[:, 0], xy[:, 1], self.polygon_2d, margin_m, _RASTER_CELL_M, xy, self.rasters, of_n)


def _tuple(v: np.ndarray) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


def project(points: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """(N, K) coordinates of points along the K rows of ``axes``. One matrix-vector
    product per axis: (N, 3) @ (3, K) with a tiny inner size is several times slower."""
    return np.stack([points @ a for a in axes], axis=1)


def plane_basis(normal: np.ndarray) -> np.ndarray:
    """(2, 3) orthonormal in-plane axes u, v with u x v = normal."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = cross3(helper, normal)
    u /= np.linalg.norm(u)
    v = cross3(normal, u)
    return np.stack([u, v])


def column_sums(rows: np.ndarray) -> np.ndarray:
    """``rows.sum(axis=0)``, the same floats: each column summed row by row, in order.
    For C-contiguous float64 rows by einsum, a fifth of the cost (the reduction along
    axis 0 walks the rows a few entries at a time, issue 39). einsum starts from +0.0
    where the reduction starts from the first row: the two differ only in the sign of
    a sum that comes out zero, and such a column is summed again the reduction's way."""
    if rows.ndim == 2 and rows.dtype == np.float64 and rows.flags.c_contiguous:
        sums = np.einsum("ij->j", rows)
        if sums.all():
            return sums
    return rows.sum(axis=0)


def fit_plane_lsq(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Least-squares plane (unit normal, offset) through points."""
    # mean(axis=0) is the column sums over the count, the same floats
    c = column_sums(points) / points.shape[0] if points.shape[0] else points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - c, full_matrices=False)
    n = vt[2]
    return n, float(-n @ c)


def ransac_plane(
    points: np.ndarray,
    distance_m: float,
    iterations: int,
    rng: np.random.Generator,
    usable: np.ndarray | None = None,
    range2: np.ndarray | None = None,
) -> tuple[np.ndarray, float]:
    """`_ransac_fit`'s plane."""
    n, d, _ = _ransac_fit(points, distance_m, iterations, rng, usable, range2)
    return n, d


def _ransac_fit(
    points: np.ndarray,
    distance_m: float,
    iterations: int,
    rng: np.random.Generator,
    usable: np.ndarray | None = None,
    range2: np.ndarray | None = None,
) -> tuple[np.ndarray, float, np.ndarray | None]:
    """The plane with the most inliers among random triplets (scored on a subsample),
    refined by least squares on its inliers. Hypotheses are drawn in chunks and the
    search stops once enough were drawn to have hit an all-inlier triplet of the best
    plane so far with probability 0.999 (at most ``iterations``).

    ``usable``: (N,) bool, the points the plane is sought among (all when None). Every
    position (of the scoring points and of the triplets) is drawn over all of ``points``,
    as when all are usable, and a draw that lands on an unusable point is taken by
    `_redirected` to the next usable point in a fixed scrambled order of the positions:
    every draw is valid however few points remain, and a point made unusable (or kept)
    changes only the draws that land on it or on the unusable points just before it in
    that order, never the others (drawing over the usable subset shifted every later
    draw: one point more or less left by an earlier plane changed the later planes,
    issue 37). All usable: the same draws as without the mask, bit for bit.

    ``range2``: (N,) the points' `squared_range`, when the caller has it (`_refined`
    reads their largest).

    Returns (normal, offset, fitted): ``fitted`` the sorted positions in ``points`` of
    the rows whose `fit_plane_lsq` the plane is (None: RANSAC's own plane, under 3
    inliers), for a caller that would fit those rows again (`find_table`)."""
    n_pts = points.shape[0]
    redirect = None
    if usable is not None and not bool(usable.all()):
        if not bool(usable.any()):
            raise SceneError("no plane: no usable points")
        redirect = _redirection(usable)
    ev_at = rng.integers(0, n_pts, size=min(_RANSAC_EVAL, n_pts))
    if redirect is not None:
        ev_at = _redirected(ev_at, *redirect)
    ev = points[ev_at]
    best_count, best_n, best_d = -1, None, 0.0
    drawn = 0
    # each chunk's distances and verdicts in the same buffers (a fresh (E, K) array a
    # chunk cost a third of the products' time, issue 39)
    dist_buf = np.empty(ev.shape[0] * _RANSAC_CHUNK)
    hit_buf = np.empty(ev.shape[0] * _RANSAC_CHUNK, dtype=bool)
    while drawn < iterations:
        chunk = min(_RANSAC_CHUNK, iterations - drawn)
        drawn += chunk
        at = rng.integers(0, n_pts, size=(chunk, 3))
        if redirect is not None:
            at = _redirected(at, *redirect)
        tri = points[at]
        normals = cross3(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        norm = np.linalg.norm(normals, axis=1)
        ok = norm > 1e-9
        if not ok.any():
            continue
        normals = normals[ok] / norm[ok, None]
        offsets = -np.einsum("ij,ij->i", normals, tri[ok, 0])
        # each hypothesis's inliers among the scoring points, in place (one (E, K) array:
        # the same sums, a few times faster than a temporary per operation)
        dist = np.matmul(ev, normals.T, out=dist_buf[: ev.shape[0] * normals.shape[0]].reshape(ev.shape[0], -1))
        dist += offsets
        np.abs(dist, out=dist)
        hit = np.less_equal(dist, distance_m, out=hit_buf[: dist.size].reshape(dist.shape))
        # down each column, the bools' bytes summed in uint16 (at most _RANSAC_EVAL):
        # count_nonzero along an axis cast each one to intp first, at twice the cost
        counts = hit.view(np.uint8).sum(axis=0, dtype=np.uint16)
        k = int(np.argmax(counts))
        if counts[k] > best_count:
            best_count, best_n, best_d = int(counts[k]), normals[k], float(offsets[k])
        w = best_count / max(ev.shape[0], 1)
        if w >= 1.0 or (w > 0 and drawn >= np.log(1e-3) / np.log(1.0 - w**3)):
            break
    if best_n is None:
        raise SceneError("no plane: the points are degenerate")
    if usable is not None and redirect is not None:
        points = np.compress(usable, points, axis=0)  # rows by a mask: compress is faster
        range2 = None if range2 is None else np.compress(usable, range2)
        n, d, fitted = _refined(points, best_n, best_d, distance_m, range2)
        return n, d, None if fitted is None else np.flatnonzero(usable)[fitted]
    n, d, fitted = _refined(points, best_n, best_d, distance_m, range2)
    return n, d, None if fitted is None else np.flatnonzero(fitted)


# `_redirection`'s scrambled order: position i comes at rank (i * a) mod N, with the
# multiplier a near N / golden ratio (made coprime to N), so that neighbours in the order
# lie far apart in the points' own (raster) order. In raster order a removed surface
# leaves runs of hundreds of unusable positions, and the one usable point after each
# run would take all of its draws (RANSAC would draw little but the points at the
# removed surface's edge); scrambled, the runs are short (about 1 / f - 1 positions
# when a share f remains) and land on points all over the frame.
_ORDER_MULT = 0.6180339887498949


def _order_step(n: int) -> int:
    """The multiplier of `_redirection`'s order for ``n`` positions: the integer nearest
    ``_ORDER_MULT * n`` that is coprime to ``n`` (so that the order is a permutation)."""
    a = max(1, round(_ORDER_MULT * n))
    while math.gcd(a, n) != 1:
        a += 1
    return a


@lru_cache(maxsize=8)
def _positions_by_rank(n: int) -> np.ndarray:
    """(n,) the position at each rank of `_redirection`'s order: rank r holds position
    (r * a^-1) mod n. The same few sample sizes recur (a frame's planes all draw over its
    RANSAC sample): kept, read-only."""
    out = (np.arange(n, dtype=np.int64) * pow(_order_step(n), -1, n)) % n
    out.flags.writeable = False
    return out


def _redirection(usable: np.ndarray) -> tuple[np.ndarray, np.ndarray, int, int]:
    """What `_redirected` needs for ``usable`` (N,) bool, not all False: the ranks of the
    usable positions in the scrambled order (sorted), the position at each of those
    ranks, the multiplier and N. (Not a table of every position's destination: that is
    two random gathers over all N, more than the few hundred draws a plane makes cost.)"""
    n = usable.shape[0]
    positions_by_rank = _positions_by_rank(n)
    usable_ranks = np.flatnonzero(np.take(usable, positions_by_rank))  # sorted, without a sort
    return usable_ranks, np.take(positions_by_rank, usable_ranks), _order_step(n), n


def _redirected(at: np.ndarray, usable_ranks: np.ndarray, usable_at: np.ndarray, a: int, n: int) -> np.ndarray:
    """Drawn positions ``at`` (any shape), each moved to the first usable position at or
    after its own rank in the scrambled order (wrapping round): a usable one stays."""
    k = np.searchsorted(usable_ranks, (at * a) % n)
    k[k == usable_ranks.size] = 0
    return np.take(usable_at, k)


def _refined(
    points: np.ndarray, n: np.ndarray, d: float, distance_m: float, range2: np.ndarray | None = None
) -> tuple[np.ndarray, float, np.ndarray | None]:
    """RANSAC's plane (n, d) refined: least squares on the inliers until they no longer
    change, so that the plane is a fixed point of the refit rather than of the draws
    (which points the random indices pick changes when one point more or less survives
    the filter); at most ``_REFITS`` refits, the last one's plane.

    The plane returned is `fit_plane_lsq` of the same inliers as refitting with it every
    time gives, bit for bit, for one SVD in all: the refits between are the plane of the
    scatter matrix's smallest eigenvector, its sums kept up to date by the points that
    join or leave (a tenth of an SVD each). Where that plane could put a point on the
    other side of ``distance_m`` than the SVD's would (a point within `_moments_margin`
    of it, or an ill-posed scatter), that refit and those after it are SVDs.

    ``range2``: the points' `squared_range` when the caller has it (their largest bounds
    the rounding).

    Returns (normal, offset, fitted): ``fitted`` (N,) bool, the inliers whose
    `fit_plane_lsq` the plane is (None: the plane given, under 3 inliers)."""
    # each refit's distances, and their distances from distance_m, in two buffers, in
    # place (the same floats; fresh temporaries cost as much as the arithmetic, issue 39)
    dist, off = np.empty(points.shape[0]), np.empty(points.shape[0])
    np.matmul(points, n, out=dist)
    dist += d
    inl = np.abs(dist, out=dist) <= distance_m
    fitted: np.ndarray | None = None  # the inliers of the last refit
    by_svd = False  # was it `fit_plane_lsq`'s (or the moments' plane, to be fitted so at the end)
    if range2 is None:
        range2 = squared_range(points)
    r2 = float(range2.max()) if points.shape[0] else 0.0
    count = int(inl.sum())
    chosen = np.compress(inl, points, axis=0)  # rows by a mask: compress is several times faster
    s1, s2 = column_sums(chosen), chosen.T @ chosen
    exact = False
    for _ in range(_REFITS):
        if count < 3:
            break
        if not exact:
            plane = _moments_plane(s1, s2, count, r2)
            if plane is None:
                exact = True
            else:
                np.matmul(points, plane[0], out=dist)
                dist += plane[1]
                np.abs(dist, out=dist)
                np.subtract(dist, distance_m, out=off)
                if bool((np.abs(off, out=off) <= plane[2]).any()):
                    exact = True
        fitted = inl
        if exact:
            by_svd = True
            n, d = fit_plane_lsq(np.compress(inl, points, axis=0))
            again = np.abs(points @ n + d) <= distance_m
        else:
            by_svd = False
            again = dist <= distance_m
        if (again == inl).all():
            break
        changed = np.flatnonzero(again != inl)
        if not exact:
            moved = points[changed]
            sign = np.where(again[changed], 1.0, -1.0)
            s1 = s1 + (sign[:, None] * moved).sum(axis=0)
            s2 = s2 + (moved * sign[:, None]).T @ moved
        count += int(again[changed].sum()) * 2 - changed.size
        inl = again
    if fitted is not None and not by_svd:
        n, d = fit_plane_lsq(np.compress(fitted, points, axis=0))
    return n, d, fitted


def _moments_plane(s1: np.ndarray, s2: np.ndarray, count: int, r2: float) -> tuple[np.ndarray, float, float] | None:
    """(normal, offset, margin) of the least-squares plane of ``count`` points from their
    sum ``s1`` and the sum of their outer products ``s2``: the smallest eigenvector of
    the scatter matrix; ``margin`` (m) bounds how far its distances may lie from the
    SVD's (`fit_plane_lsq`) on points within sqrt(``r2``) of the origin. None when the
    bound is not small (an ill-posed scatter: a line of points)."""
    c = s1 / count
    scatter = s2 - count * np.outer(c, c)
    w, vecs = np.linalg.eigh(scatter)
    gap = float(w[1] - w[0])
    # the sums' rounding (and the SVD's) bounded generously: count * eps * r2 per entry,
    # a hundredfold; the normal turns by at most that over the eigenvalues' gap (radians)
    err = 100.0 * count * 2.3e-16 * max(r2, 1.0)
    if gap <= 0.0 or err > 1e-9 * gap:
        return None
    normal = vecs[:, 0]
    margin = max(1e-9, 4.0 * (err / gap) * np.sqrt(max(r2, 1.0)))
    return normal, float(-normal @ c), margin


def _hull_candidates(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(N,) bool: the points that may be vertices of the convex hull of (x, y): all but
    those more than ``_HULL_INSIDE_M`` inside the polygon of the extreme points along x,
    x + y, y, y - x and their opposites (Akl-Toussaint's throw-away, with an octagon),
    about nine in ten of a surface's points."""
    s, d = x + y, y - x
    pick = [
        np.argmax(x),
        np.argmax(s),
        np.argmax(y),
        np.argmax(d),
        np.argmin(x),
        np.argmin(s),
        np.argmin(y),
        np.argmin(d),
    ]
    px, py = x[pick].tolist(), y[pick].tolist()  # counter-clockwise
    keep = np.zeros(x.shape[0], dtype=bool)
    left, t = np.empty_like(x), np.empty_like(x)
    for k in range(8):
        ax, ay, bx, by = px[k], py[k], px[(k + 1) % 8], py[(k + 1) % 8]
        ex, ey = bx - ax, by - ay
        length = (ex * ex + ey * ey) ** 0.5
        if length == 0.0:
            continue
        # ex (y - ay) - ey (x - ax): |e| times the distance left of the edge a -> b
        np.multiply(y, ex, out=left)
        np.multiply(x, ey, out=t)
        left -= t
        keep |= left <= ex * ay - ey * ax + _HULL_INSIDE_M * length
    return keep


def hull_vertices(points_2d: np.ndarray) -> np.ndarray:
    """Indices of the vertices of the convex hull of ``points_2d`` (N, 2), counter-
    clockwise: ``scipy.spatial.ConvexHull(points_2d).vertices`` (of two equal points
    either may be the vertex: the same coordinates), and its errors.

    Qhull runs on `_hull_candidates` only: the points well inside the hull are no
    vertex, and on a surface's thousands of points Qhull's time is theirs (table and
    object hulls: a third of it; the same vertices in the same order on the mOSD,
    RealSense and fixture frames). Any error there: the whole set again, whose error
    is the one raised."""
    from scipy.spatial import ConvexHull, QhullError

    n = points_2d.shape[0]
    if n > _HULL_FILTER_FROM:
        x = np.ascontiguousarray(points_2d[:, 0], dtype=np.float64)
        y = np.ascontiguousarray(points_2d[:, 1], dtype=np.float64)
        sub = np.flatnonzero(_hull_candidates(x, y))
        if 3 <= sub.size < n:
            try:
                return sub[ConvexHull(points_2d[sub]).vertices]
            except (QhullError, ValueError):
                pass
    return ConvexHull(points_2d).vertices


def convex_hull_2d(points_2d: np.ndarray) -> np.ndarray:
    """(K, 2) hull vertices counter-clockwise."""
    from scipy.spatial import QhullError

    try:
        vertices = hull_vertices(points_2d)
    except QhullError as exc:
        raise SceneError(f"no table: the table points are degenerate ({str(exc).splitlines()[0]})") from None
    return points_2d[vertices]


def mirrored_hull(polygon_2d: np.ndarray) -> np.ndarray:
    """The counter-clockwise hull (K, 2) of the points whose hull is ``polygon_2d`` with
    their x negated: its vertices mirrored, read backwards."""
    return polygon_2d[::-1] * np.array([-1.0, 1.0])


def polygon_area(polygon_2d: np.ndarray) -> float:
    """Area (m^2) of a simple polygon (K, 2) (the shoelace formula)."""
    x, y = polygon_2d[:, 0], polygon_2d[:, 1]
    return float(abs(x @ np.roll(y, -1) - y @ np.roll(x, -1)) / 2.0)


def inside_convex(points_2d: np.ndarray, polygon_2d: np.ndarray, margin_m: float = 0.0) -> np.ndarray:
    """(N,) bool: points inside the counter-clockwise convex polygon grown by margin_m."""
    edges = np.roll(polygon_2d, -1, axis=0) - polygon_2d
    out_normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1)
    out_normals /= np.maximum(np.linalg.norm(out_normals, axis=1, keepdims=True), 1e-12)
    limits = np.einsum("ij,ij->i", out_normals, polygon_2d) + margin_m
    inside = np.ones(points_2d.shape[0], dtype=bool)
    for k in range(polygon_2d.shape[0]):  # loop over hull edges (tens), vectorised over points
        inside &= points_2d @ out_normals[k] <= limits[k]
    return inside


def inside_convex_raster(
    points_2d: np.ndarray, polygon_2d: np.ndarray, margin_m: float = 0.0, cell_m: float = _RASTER_CELL_M
) -> np.ndarray:
    """`inside_convex` looked up in a raster of the polygon (cells of ``cell_m``): exact
    to within a cell near the boundary, and an order of magnitude faster for the
    hundreds of thousands of table points than testing every hull edge."""
    return _inside_raster_xy(points_2d[:, 0], points_2d[:, 1], polygon_2d, margin_m, cell_m, points_2d)


def _inside_raster_xy(
    x: np.ndarray,
    y: np.ndarray,
    polygon_2d: np.ndarray,
    margin_m: float,
    cell_m: float,
    points_2d: np.ndarray | None = None,
    rasters: dict[tuple[float, float], np.ndarray] | None = None,
    of_n: int | None = None,
) -> np.ndarray:
    """`inside_convex_raster` of the points (x, y) given as two columns (``points_2d``:
    them as one (N, 2) array when the caller has it; the exact test needs it).
    ``rasters``: the polygon's rasters drawn before, by (margin, cell), to read and add to.
    ``of_n``: the count the test is chosen for (`TableFit.inside`; None: these points')."""
    lo = polygon_2d.min(axis=0) - margin_m - cell_m
    hi = polygon_2d.max(axis=0) + margin_m + cell_m
    span = np.ceil((hi - lo) / cell_m)
    # the cell count in floats: a hull from a damaged cloud (coordinates of 4e9 m) has
    # more cells than an int64 product holds, and a wrapped product passed the test
    n_cells = float(span[0]) * float(span[1])
    if not n_cells <= 2_000_000 or (x.shape[0] if of_n is None else of_n) < n_cells // 4:
        return inside_convex(np.stack([x, y], axis=1) if points_2d is None else points_2d, polygon_2d, margin_m)
    dims = span.astype(np.int64)
    grid = None if rasters is None else rasters.get((margin_m, cell_m))
    if grid is None:
        grid = _raster(polygon_2d, margin_m, cell_m, lo, dims)
        if rasters is not None:
            rasters[(margin_m, cell_m)] = grid
    # a point off the raster clipped into its border of outside cells; clipped before the
    # cast too: a point 1e38 m away (a damaged cloud) has a cell index no int64 holds
    # (and after it, for NaN's integer)
    # the flat cell of each point, in floats and in place (a dozen fresh temporaries of
    # the points' size were most of the lookup's time, issue 39): every value is a whole
    # number below 2^53 there, so the same cell as in int64
    cx, cy = _cell_of(x, lo[0], cell_m, dims[0]), _cell_of(y, lo[1], cell_m, dims[1])
    cx *= dims[1] + 2
    cx += cy
    return np.take(grid, cx.astype(np.intp))  # one flat lookup


def _cell_of(v: np.ndarray, lo: float, cell_m: float, n: int) -> np.ndarray:
    """(N,) float: the raster row (or column) of each coordinate ``v``, 1..n, with 0 and
    n + 1 the border of outside cells: a point off the raster is clipped into it, before
    any cast (a point 1e38 m away, from a damaged cloud, has a cell index no int64
    holds), and NaN's too: fmax / fmin take the number over a NaN."""
    c = np.subtract(v, lo)
    c /= cell_m
    np.fmax(c, -1.0, out=c)
    np.fmin(c, float(n), out=c)
    np.floor(c, out=c)
    c += 1.0
    return c


def _raster(polygon_2d: np.ndarray, margin_m: float, cell_m: float, lo: np.ndarray, dims: np.ndarray) -> np.ndarray:
    """(dims + 2 flattened,) bool: `inside_convex` of the centres of the (dims[0], dims[1])
    cells of ``cell_m`` from ``lo``, with a border of one cell that is outside all round
    (rows of dims[1] + 2)."""
    gx = lo[0] + (np.arange(dims[0]) + 0.5) * cell_m
    gy = lo[1] + (np.arange(dims[1]) + 0.5) * cell_m
    grid = np.zeros((dims[0] + 2, dims[1] + 2), dtype=bool)
    runs = _inside_runs(gx, gy, polygon_2d, margin_m)
    if runs is not None:
        first, stop = runs
        j = np.arange(dims[1])
        grid[1:-1, 1:-1] = (j >= first[:, None]) & (j < stop[:, None])
    else:
        centers = np.stack(np.meshgrid(gx, gy, indexing="ij"), axis=-1).reshape(-1, 2)
        grid[1:-1, 1:-1] = inside_convex(centers, polygon_2d, margin_m).reshape(dims[0], dims[1])
    return grid.ravel()


# _inside_runs(): a cell is judged without the exact test when its centre lies farther
# than this share of the coordinates' size from every edge's line (the test's rounding
# is ~1e-16 of it)
_RUN_TOLERANCE = 1e-9


def _inside_runs(
    gx: np.ndarray, gy: np.ndarray, polygon_2d: np.ndarray, margin_m: float
) -> tuple[np.ndarray, np.ndarray] | None:
    """`inside_convex` of the grid of centres (gx[i], gy[j]) (both increasing) as one run
    of j per i: (first, stop) (len(gx),) each, cell (i, j) inside when first[i] <= j <
    stop[i], the very verdicts of the exact test; None when some centre lies too near an
    edge's line to tell them without it (then every centre is tested).

    The polygon is convex: per edge, the centres of a column inside it are those on one
    side of one row (gy[j] * b, b the edge normal's second component, is monotonic in
    j), found by a binary search each, and the runs of all edges intersect. A centre is
    counted only when it is more than `_RUN_TOLERANCE` (relative) off the edge's line on
    both the run's bounds; that holds when the run it is certainly inside is the run it
    may be inside. Per column tens of binary searches replace the test of every cell
    against every edge (issue 39: most of a raster's time)."""
    if polygon_2d.dtype != np.float64 or not (np.isfinite(gx).all() and np.isfinite(gy).all()):
        return None
    # the exact test's normals and limits (inside_convex), computed as it does
    edges = np.roll(polygon_2d, -1, axis=0) - polygon_2d
    out_normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1)
    out_normals /= np.maximum(np.linalg.norm(out_normals, axis=1, keepdims=True), 1e-12)
    limits = np.einsum("ij,ij->i", out_normals, polygon_2d) + margin_m
    if not (np.isfinite(out_normals).all() and np.isfinite(limits).all()):
        return None
    nx, ny = gx.shape[0], gy.shape[0]
    sure_lo, sure_hi = np.zeros(nx, dtype=np.int64), np.full(nx, ny, dtype=np.int64)
    may_lo, may_hi = sure_lo.copy(), sure_hi.copy()
    big_x, big_y = float(np.abs(gx).max()), float(np.abs(gy).max())
    for (a, b), limit in zip(out_normals.tolist(), limits.tolist(), strict=True):
        tol = _RUN_TOLERANCE * (big_x * abs(a) + big_y * abs(b) + abs(limit)) + 1e-15
        room = limit - gx * a  # inside: gy[j] * b <= room, to within rounding
        if b > 0.0:
            along = gy * b  # non-decreasing
            np.minimum(sure_hi, np.searchsorted(along, room - tol, side="right"), out=sure_hi)
            np.minimum(may_hi, np.searchsorted(along, room + tol, side="right"), out=may_hi)
        elif b < 0.0:
            along = gy * -b  # non-decreasing: inside is -gy[j] b >= -room
            np.maximum(sure_lo, np.searchsorted(along, tol - room, side="left"), out=sure_lo)
            np.maximum(may_lo, np.searchsorted(along, -room - tol, side="left"), out=may_lo)
        else:  # the whole column on one side
            if bool(((room > -tol) & (room <= tol)).any()):
                return None
            out = room <= -tol
            sure_hi[out] = 0
            may_hi[out] = 0
    sure_empty = sure_lo >= sure_hi
    may_empty = may_lo >= may_hi
    same = (sure_empty & may_empty) | ((sure_lo == may_lo) & (sure_hi == may_hi))
    if not bool(same.all()):
        return None
    return np.where(sure_empty, 0, sure_lo), np.where(sure_empty, 0, sure_hi)


def _packed(*cells: np.ndarray) -> tuple[list[np.ndarray], np.ndarray, int]:
    """Each (N, 2) int64 array of grid indices (none empty) as one int64 key per row over
    their joint range (offset to non-negative, first column major: the keys sort as the
    rows do), with the offset and the second column's span that unpack them."""
    lo = np.min([[c[:, 0].min(), c[:, 1].min()] for c in cells], axis=0)  # per column: faster than axis=0
    span = int(max(int(c[:, 1].max()) for c in cells) - lo[1]) + 1
    return [(c[:, 0] - lo[0]) * span + (c[:, 1] - lo[1]) for c in cells], lo, span


def unique_cells(cells: np.ndarray) -> np.ndarray:
    """The distinct rows of ``cells`` (N, 2) int64 grid indices, in the lexicographic
    order of ``np.unique(cells, axis=0)``: each row packed into one int64 key (`_packed`)
    and those sorted, several times faster than the sort on rows that ``axis=0`` does (it
    was most of the table stage on 1280x720)."""
    if cells.shape[0] == 0:
        return cells.reshape(0, 2)
    (packed,), lo, span = _packed(cells)
    top = int(packed.max()) + 1
    if top <= 4 * packed.shape[0] + 1024:
        # the keys' range is not much larger than their number: a mark per key, read back
        # in order (the sorted distinct keys without a sort)
        seen = np.zeros(top, dtype=bool)
        seen[packed] = True
        keys = np.flatnonzero(seen)
    else:
        keys = np.unique(packed)
    return np.stack([keys // span + lo[0], keys % span + lo[1]], axis=1)


def largest_component(u: np.ndarray, v: np.ndarray, cell_m: float, join_gap_m: float = 0.0) -> tuple[np.ndarray, float]:
    """Mask of the points (``u``, ``v``: their two in-plane coordinates, (N,) each) in
    the largest 8-connected piece of the occupied grid cells, together with every other
    piece within ``join_gap_m`` of it (objects standing on a table and their shadows cut
    its visible surface into pieces), and their area (m^2).

    Column by column, in place, and the cells as one flat index each: the same floats
    and cells as (N, 2) rows broadcast against the two minima and indexed by pairs of
    arrays, at half the cost (the table's 25 000 sample points, issue 39)."""
    offsets = []
    for c in (u, v):
        o = np.subtract(c, c.min())
        o /= cell_m
        offsets.append(np.floor(o, out=o))
    # counted in floats: points from absurd intrinsics (a principal point 1e18 px away)
    # span more cells than an int64 holds, and the product of the sides wrapped round
    sides = np.array([o.max() for o in offsets]) + 1
    n_cells = float(np.prod(sides))
    if n_cells > 4_000_000:  # a plane reaching far away: coarser cells (a long thin one: by its long side)
        scale = float(np.ceil(max(np.sqrt(n_cells / 4_000_000), float(sides.max()) / 4_000_000)))
        offsets = [np.floor(o / scale) for o in offsets]
        cell_m *= scale
    cu, cv = (o.astype(np.int64) for o in offsets)
    dims = (int(cu.max()) + 1, int(cv.max()) + 1)
    flat = cu * dims[1]
    flat += cv
    grid = np.zeros(dims[0] * dims[1], dtype=bool)
    grid[flat] = True
    labels, n = label_8(grid.reshape(dims))
    if n == 0:
        return np.zeros(u.shape[0], dtype=bool), 0.0
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    best = int(np.argmax(sizes))
    chosen = np.zeros(n + 1, dtype=bool)
    chosen[best] = True
    steps = int(round(join_gap_m / cell_m))
    if steps > 0 and n > 1:
        near = dilate_square(labels == best, steps)
        touched = np.unique(labels[near])
        touched = touched[(touched > 0) & (sizes[touched] >= 4)]  # not specks
        chosen[touched] = True
    return np.take(chosen, np.take(labels.ravel(), flat)), float(sizes[chosen].sum()) * cell_m * cell_m


@dataclass
class _Candidate:
    normal: np.ndarray
    offset: float
    members: np.ndarray  # indices into the sample of the largest connected piece
    area_m2: float
    on_plane: np.ndarray  # bool over the sample: within distance of this plane
    refit: tuple[np.ndarray, float] | None = None  # `fit_plane_lsq` of the members, when known
    # with ``refit``: the coordinates of the plane's inliers along plane_basis(normal)
    # (two columns) and which of them are the members
    uv: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None


def _residue(n: np.ndarray, inliers: np.ndarray, candidates: list[_Candidate]) -> bool:
    """Is the plane of normal ``n`` (its ``inliers``) a residue of a candidate's own noise:
    parallel to it within `_RESIDUE_COS` and its inliers' median within `_RESIDUE_M` of it?"""
    for c in candidates:
        if (
            abs(float(n @ c.normal)) >= _RESIDUE_COS
            and float(np.median(np.abs(inliers @ c.normal + c.offset))) <= _RESIDUE_M
        ):
            return True
    return False


def _hidden_from_origin(fit: TableFit, loose: np.ndarray, loose_range2: np.ndarray, settings: SegmentSettings) -> int:
    """How many of ``loose`` stand behind ``fit``'s support as seen from the origin (its
    normal turned towards the origin; within the scoring's height band, beyond its noise)
    with their line of sight from the origin crossing the support inside its outline
    (shrunk by `_EDGE_BAND_M`): points a camera at the origin could not see through an
    opaque support. Points seen past its edge (a floor beyond a table) cross outside it."""
    n, d = fit.plane.normal, fit.plane.offset  # d > 0: the origin on the normal's side
    h = loose @ n + d
    behind = (h < -(settings.prism_min_height_m + _NOISE_PER_M2 * loose_range2)) & (h >= -_SCORE_HEIGHT_M)
    far = np.compress(behind, loose, axis=0)
    # the ray t * p meets the plane n . x + d = 0 at t = d / (d - h), 0 < t < 1 behind it
    crossing = far * (d / (d - np.compress(behind, h)))[:, None]
    return int(np.count_nonzero(inside_convex(fit.to_2d(crossing), fit.polygon_2d, -_EDGE_BAND_M)))


def _considered(planes: Sequence[PlaneVerdict]) -> str:
    """The candidate planes for a one-line error, as a user can find them in the view:
    each one's area and distance from the sensor's origin."""
    return ", ".join(f"{v.area_m2:.3f} m^2 at {abs(v.offset_m):.2f} m" for v in planes)


def find_table(
    points: np.ndarray,
    settings: SegmentSettings,
    organized: bool,
    source: str = "",
    pinhole: Callable[[], bool] | None = None,
    upright_check: bool = True,
    needs_turn: Callable[[np.ndarray], bool] | None = None,
) -> TableFit:
    """Stage 2a: the support plane among up to ``plane_candidates`` RANSAC planes.

    ``points``: (M, 3) finite float64 points that survived outlier removal. ``pinhole``:
    whether the frame is an organized pinhole grid about its origin (a camera image in
    its optical frame), asked only when the origin's being the camera is in doubt.
    ``upright_check``: an organized camera image whose table faces down the image is
    refused (segment.py turns a rolled image upright first and passes False).
    ``needs_turn``: whether a support of that normal (towards the camera) would have the
    image turned (segment.py's rolled-camera test; None: no turn is considered). A support
    that would, on which nothing rests, gives way to one the image is upright for on
    which objects rest (`_RESTING_M`).

    The cloud is taken to be in a camera frame (the sensor at the origin) when the
    support lies `_MIN_CAMERA_HEIGHT_M` or more from the origin, unless the origin sees
    the support from behind while what the support would hide stands there
    (`_hidden_from_origin`): then the origin is a robot's or the world's frame beneath
    the table, and the support's normal is turned up where the objects are.
    Raises SceneError when no plane of at least ``table_min_area_m2`` exists, or when the
    objects are on the far side of the table (a table seen from below).
    """
    where = f"{source}: " if source else ""
    if points.shape[0] < 100:
        raise SceneError(f"{where}no table: only {points.shape[0]} usable points in the frame")
    rng = np.random.default_rng(0)  # fixed: the same frame always gives the same table
    step = max(1, points.shape[0] // _RANSAC_SAMPLE)
    # a contiguous copy of the regular subsample: the row gathers, masks and products on
    # it below (a dozen a frame) cost 2-3 times as much on the strided view
    sample = np.ascontiguousarray(points[::step])
    # their squared ranges once: each RANSAC plane's refinement, the scoring's noise band
    # and `choose` read them (a row's einsum does not depend on the rows around it: the
    # same floats as of each subset taken apart)
    sample_range2 = squared_range(sample)
    dist = settings.plane_distance_m

    candidates: list[_Candidate] = []
    small: list[PlaneVerdict] = []
    # planes smaller than a table but as large as a mat: the support only by the mat
    # rule (support.choose), each with its place in ``small``, its verdict unless chosen
    mats: list[tuple[_Candidate, int]] = []
    remaining = np.ones(sample.shape[0], dtype=bool)
    tries, residues = 0, 0
    while tries < settings.plane_candidates:
        tries += 1
        idx = np.flatnonzero(remaining)
        if idx.size < 50:
            break
        if settings.ransac_fixed_draws:
            # drawn over the whole sample, the points of earlier planes redirected to
            # remaining ones (`ransac_plane`'s ``usable``): one point more or less left by
            # an earlier plane changes only the draws that meet it, not every draw after it
            n, d, fitted = _ransac_fit(sample, dist, settings.ransac_iterations, rng, remaining, sample_range2)
        elif idx.size == sample.shape[0]:
            # every point remains (the first plane): the sample itself, not a copy of it
            # taken by index (the same rows)
            n, d, fitted = _ransac_fit(sample, dist, settings.ransac_iterations, rng, range2=sample_range2)
        else:
            # rows by index: take is faster than a[idx]
            n, d, fitted = _ransac_fit(
                np.take(sample, idx, axis=0), dist, settings.ransac_iterations, rng, range2=np.take(sample_range2, idx)
            )
            fitted = None if fitted is None else np.take(idx, fitted)  # positions in the sample
        on_plane = np.abs(sample @ n + d) <= dist
        inl = np.flatnonzero(on_plane & remaining)
        remaining &= ~on_plane
        if inl.size < 30:
            continue
        basis = plane_basis(n)
        on = np.take(sample, inl, axis=0)  # rows by index: take is faster than a[idx]
        on_uv = (on @ basis[0], on @ basis[1])
        comp, area = largest_component(*on_uv, settings.table_cell_m, settings.table_join_gap_m)
        if np.count_nonzero(comp) < 3:
            # fewer than 3 points is no plane (points far apart, as an absurd depth scale
            # gives, where a coarsened cell holds one point but a table's area)
            small.append(PlaneVerdict(_tuple(n), float(d), area, 0, False, "its largest piece holds under 3 points"))
            continue
        if residues < settings.plane_candidates and _residue(n, on, candidates):
            # the residue of a surface found, small or not (a floor thickened by a stereo
            # sensor's noise gives two or three parallel planes a centimetre apart): not
            # a try (`_RESIDUE_M`), so the planes sought after it are still sought
            tries -= 1
            residues += 1
        if area < settings.table_min_area_m2:
            if settings.support_by_standing and area >= MAT_MIN_AREA_M2:
                mats.append((_Candidate(n, d, inl[comp], area, on_plane), len(small)))
            small.append(
                PlaneVerdict(
                    _tuple(n),
                    float(d),
                    area,
                    0,
                    False,
                    f"smaller than table_min_area_m2 ({area:.3f} < {settings.table_min_area_m2:g} m^2)",
                )
            )
            continue
        piece = inl[comp]
        # the rows of the plane's own last fit: their least-squares plane is (n, d), the
        # very SVD `fit_plane_lsq` of the members below would repeat (on the table of
        # most frames, whose points all lie in one piece: a 25 000-row SVD, issue 39)
        refit = (n, d) if fitted is not None and np.array_equal(piece, fitted) else None
        if refit is None:
            candidates.append(_Candidate(n, d, piece, area, on_plane))
        else:
            candidates.append(_Candidate(n, d, piece, area, on_plane, refit, (*on_uv, comp)))
    if not candidates:
        considered = (
            ", ".join(
                f"{v.area_m2:.3f} m^2 at {abs(v.offset_m):.2f} m"
                + ("" if v.why.startswith("smaller") else f" ({v.why})")
                for v in small
            )
            or "none"
        )
        raise SceneError(
            f"{where}no table: no plane of at least {settings.table_min_area_m2} m^2 in the frame (surfaces "
            f"considered: {considered}); is a table in view?"
        )

    any_plane = np.zeros(sample.shape[0], dtype=bool)
    for c in candidates:
        any_plane |= c.on_plane
    # points on none of the candidate planes (rows by a mask: compress is several times faster)
    loose = np.compress(~any_plane, sample, axis=0)
    loose_range2 = np.compress(~any_plane, sample_range2)

    # per candidate within reach: ((score, area), fit, points before it, behind it) and the
    # points resting on it; those too far; and every candidate's (fit, score, area), in the
    # same order as the first
    Best = tuple[tuple[int, float], TableFit, int, int]
    min_obj = max(20, int(0.001 * sample.shape[0]))

    def score(
        origin_may_be_camera: bool,
    ) -> tuple[list[tuple[Best, int]], list[PlaneVerdict], list[tuple[TableFit, int, float]], list[int]]:
        """Each candidate's fit, its normal turned towards the camera at the origin (or
        "up", where the objects are, when the origin is no camera), and its score; the
        mats after the candidates, each entry's place in ``small`` (-1: no mat)."""
        ranked: list[tuple[Best, int]] = []
        far: list[PlaneVerdict] = []
        scored: list[tuple[TableFit, int, float]] = []
        mat_at: list[int] = []
        for c, at in (*((c, -1) for c in candidates), *mats):
            # rows by index: take is several times faster than a[idx]; none taken for the
            # plane and the hull of a candidate whose fit and coordinates are known
            members: np.ndarray | None = None
            if c.refit is None:
                members = np.take(sample, c.members, axis=0)
                n, d = fit_plane_lsq(members)
            else:
                n, d = c.refit
            camera_is_origin = origin_may_be_camera and abs(d) >= _MIN_CAMERA_HEIGHT_M
            if camera_is_origin and abs(d) > settings.table_max_distance_m:
                if at >= 0:
                    continue  # a mat: its verdict is in ``small`` already
                far.append(
                    PlaneVerdict(
                        _tuple(n),
                        float(d),
                        c.area_m2,
                        0,
                        False,
                        f"farther than table_max_distance_m ({abs(d):.2f} > {settings.table_max_distance_m:g} m)",
                    )
                )
                continue
            basis = plane_basis(n)
            origin = -d * n
            turned_poly = None
            if camera_is_origin and d < 0:
                # turned towards the camera below: its hull is wanted in the turned plane's axes,
                # and the one in these is its mirror image (u turns to -u exactly, v stays: the
                # same points with x negated, bit for bit), read backwards to run counter-
                # clockwise: the same directed edges as Qhull's of these, so the same test
                # below; one hull of the members, not two
                turned_n, turned_d = -n, -d  # what the turn below makes them
                turned_basis = plane_basis(turned_n)
                members = np.take(sample, c.members, axis=0) if members is None else members
                turned_poly = convex_hull_2d(project(members, turned_basis) - (-turned_d * turned_n) @ turned_basis.T)
                poly = mirrored_hull(turned_poly)
            elif members is None and c.uv is not None:
                # the members' coordinates along this very basis (the plane is the RANSAC
                # plane's own), from the piece's search: the same rows' products
                u, v, in_piece = c.uv
                poly = convex_hull_2d(
                    np.stack([np.compress(in_piece, u), np.compress(in_piece, v)], axis=1) - origin @ basis.T
                )
            else:
                members = np.take(sample, c.members, axis=0) if members is None else members
                poly = convex_hull_2d(project(members, basis) - origin @ basis.T)
            h = loose @ n + d
            # depth noise grows with the square of the range: far off-plane points are
            # noise of the plane itself, not things standing on it
            band = (np.abs(h) > settings.prism_min_height_m + _NOISE_PER_M2 * loose_range2) & (
                np.abs(h) <= _SCORE_HEIGHT_M
            )
            ins = np.zeros(loose.shape[0], dtype=bool)
            loose_band = np.compress(band, loose, axis=0)  # rows by a mask: compress is faster
            ins[band] = inside_convex(project(loose_band, basis) - origin @ basis.T, poly, -_EDGE_BAND_M)
            above = int((ins & (h > 0)).sum())
            below = int((ins & (h < 0)).sum())
            # the points resting on either side: within `_RESTING_M` past the noise band
            near = ins & (np.abs(h) <= settings.prism_min_height_m + _NOISE_PER_M2 * loose_range2 + _RESTING_M)
            rest_above, rest_below = int((near & (h > 0)).sum()), int((near & (h < 0)).sum())
            # orient the normal towards the camera, or, not in a camera frame, "up" where the
            # objects are
            if (d < 0) if camera_is_origin else (below > above):
                n, d, above, below = -n, -d, below, above
                rest_above = rest_below
                # the hull again in the turned plane's axes (unturned, it is the one above)
                basis = plane_basis(n)
                origin = -d * n
                if turned_poly is None:
                    members = np.take(sample, c.members, axis=0) if members is None else members
                    poly = convex_hull_2d(project(members, basis) - origin @ basis.T)
                else:
                    poly = turned_poly
            fit = TableFit(TablePlane(normal=n, offset=float(d)), poly, origin, basis, camera_is_origin)
            # noise lies on both sides of a plane, objects on one: score the difference
            key = (abs(above - below), c.area_m2)
            scored.append((fit, abs(above - below), c.area_m2))
            ranked.append(((key, fit, above, below), rest_above))
            mat_at.append(at)
        return ranked, far, scored, mat_at

    def first_best(ks: Iterable[int]) -> int | None:
        """Of the candidates ``ks`` (a mat is none: `MAT_MIN_AREA_M2`), the one of the
        highest (score, area), the first of equals."""
        return max((k for k in ks if mat_at[k] < 0), key=lambda k: ranked[k][0][0], default=None)

    def before(k: int) -> bool:
        """More points before candidate ``k`` than behind it, and `min_obj` at least."""
        _, _, above, below = ranked[k][0]
        return above > max(below, min_obj)

    ranked, far, scored, mat_at = score(True)
    k_best = first_best(range(len(ranked)))
    best = None if k_best is None else ranked[k_best][0]
    origin_note = ""
    if best is not None and best[1].camera_is_origin and best[3] > max(best[2], min_obj):
        # More stands behind the support than before it, as seen from the origin. A camera
        # there could not see what the support hides: the points whose line of sight from
        # the origin crosses the support inside its outline. Many such points and the
        # origin is no camera but a robot's or the world's frame beneath the table (a
        # mobile base's on the floor): the planes are turned up where the objects are.
        # An organized pinhole grid about the origin is a camera image whatever it shows.
        hidden = _hidden_from_origin(best[1], loose, loose_range2, settings)
        if hidden > max(best[2], min_obj) and not (pinhole is not None and pinhole()):
            ranked, far, scored, mat_at = score(False)
            k_best = first_best(range(len(ranked)))
            best = None if k_best is None else ranked[k_best][0]
            origin_note = (
                f" (the frame's origin is no camera: {hidden} points stand behind the support as seen from "
                "it, where it would hide them; up is where the objects stand)"
            )
    if best is None:
        considered = _considered(far)
        raise SceneError(
            f"{where}no table: every plane of table size is more than "
            f"{settings.table_max_distance_m} m from the camera (surfaces considered: {considered}); "
            "is a table in reach? (a depth image whose unit is not the millimetre needs "
            "[images] depth_scale_m; a table farther away, [segment] table_max_distance_m)"
        )
    assert k_best is not None  # with the best
    k_before = first_best(k for k in range(len(ranked)) if before(k))
    behind_note = ""
    if best[1].camera_is_origin and best[3] > max(best[2], min_obj) and k_before is not None:
        # The most points across a plane, but behind it as the camera sees it: no support
        # seen from above but a face with a body behind it (the front of a box or a raised
        # surface seen at an angle: its body rises behind it). Another plane holds points
        # on the camera's side, standing on it: that one is the support. (With none, the
        # frame is a table seen from below and is refused below, as before.)
        k_behind = k_best
        behind_note = (
            f"more points behind it than standing on it ({best[3]} against {best[2]}, as the camera sees it): "
            "a face with its body behind it, not a support"
        )
        k_best = k_before
        best = ranked[k_best][0]
    turn_note = ""
    if needs_turn is not None and best[1].camera_is_origin and needs_turn(best[1].plane.normal):
        # A support the image would be turned for (a rolled camera), on which nothing
        # rests: the points before it stand apart from it (the objects on a table in front
        # of a desk's face, seen at an angle). Another plane that the image is upright for
        # holds objects resting on it, `_RESTING_OVER` times as many at least: that one is
        # the support, and the image is read as it is (a rolled camera's table holds its
        # objects resting on it; a wall behind it, nothing).
        resting_best = ranked[k_best][1]
        k_upright = first_best(
            k
            for k in range(len(ranked))
            if not needs_turn(ranked[k][0][1].plane.normal)
            and ranked[k][1] >= max(_RESTING_OVER * resting_best, min_obj)
            and before(k)
        )
        if k_upright is not None:
            turned_from, k_best = k_best, k_upright
            best = ranked[k_best][0]
            turn_note = (
                f"{'nothing' if resting_best == 0 else 'little'} rests on it ({resting_best} points within "
                f"{_RESTING_M * 100:.0f} cm of it, against {ranked[k_best][1]} on the support): a face with things "
                "before it, seen as a rolled camera's table"
            )
    _, fit, above, below = best
    chosen_standing = abs(above - below)
    chosen_why = "the most points standing on it"
    turned: dict[int, str] = {}
    if settings.support_by_standing and len(scored) > 1:
        surfaces = [Surface(f.plane.normal, f.plane.offset, f.basis, f.origin, f.polygon_2d) for f, _, _ in scored]
        best_k = next(k for k, (f, _, _) in enumerate(scored) if f is fit)
        band_m = settings.prism_min_height_m + _NOISE_PER_M2 * loose_range2
        every_band_m = settings.prism_min_height_m + _NOISE_PER_M2 * sample_range2
        choice = choose(
            surfaces,
            best_k,
            loose,
            band_m,
            sample,
            every_band_m,
            min_obj,
            settings.mat_below_seen_max_share,
            settings.raised_below_seen_max_share,
            frozenset(k for k, at in enumerate(mat_at) if at >= 0),
        )
        if choice is not None and choice.index == best_k:
            turned = choice.rejected_why  # it stays; the concave surfaces turned down say why
        elif choice is not None:
            fit = scored[choice.index][0]
            chosen_why, turned = choice.why, choice.rejected_why
            on = standing_on(surfaces[choice.index], loose, band_m)
            above, below = int(on.sum()), 0
            chosen_standing = scored[choice.index][1]
    if behind_note:
        turned[k_behind] = behind_note
    if turn_note:
        turned[turned_from] = turn_note
    verdicts = [
        PlaneVerdict(
            _tuple(f.plane.normal),
            f.plane.offset,
            area,
            standing,
            f is fit,
            chosen_why + origin_note
            if f is fit
            else turned.get(k, f"fewer points standing on it ({standing} against {chosen_standing})"),
        )
        for k, (f, standing, area) in enumerate(scored)
        if mat_at[k] < 0 or f is fit
    ]
    verdicts.sort(key=lambda v: not v.chosen)
    # the mats not chosen keep their verdict as planes smaller than a table, with why the
    # mat rule turned them down where it did; the one chosen is not listed twice
    chosen_mat = -1
    for k, at in enumerate(mat_at):
        if at < 0:
            continue
        if scored[k][0] is fit:
            chosen_mat = at
        elif k in turned:
            small[at] = replace(small[at], why=f"{small[at].why}; as a mat: {turned[k]}")
    small = [v for i, v in enumerate(small) if i != chosen_mat]
    fit = replace(fit, planes=tuple(verdicts + far + small))

    # Seen from below: what stands on the table is on the far side from the camera (the
    # camera side of a table's underside holds nothing inside its hull), or, for a camera
    # image, "up" (the table normal towards the camera) points down the image.
    if fit.camera_is_origin and below > max(above, min_obj):
        raise SceneError(
            f"{where}no usable table: the best support plane ({fit.plane.offset:.2f} m from the "
            "camera) has more points behind it than standing on it; the table is seen from "
            f"below, or there is no table in view (surfaces considered: {_considered(fit.planes)})"
        )
    if upright_check and organized and fit.camera_is_origin and fit.plane.normal[1] > 0.5:
        raise SceneError(
            f"{where}the table is seen from below: its top faces down the image "
            f"(normal {np.round(fit.plane.normal, 2).tolist()} in the optical frame); "
            "segmentation needs a view from above the table"
        )
    return fit


def squared_range(points: np.ndarray) -> np.ndarray:
    """(M,) squared distance of each point from the sensor (the origin)."""
    return np.einsum("ij,ij->i", points, points)


@dataclass(frozen=True, eq=False)
class Lift:
    """The part of `table_and_prism` that reads the fit's plane and in-plane axes but not
    its hull: worked out once a frame and read again when the hull is drawn anew (the
    table without what lies beyond its edge: the same plane, basis and origin) and by
    the exclusion step (what lies above the support outside the prism is among the
    candidates, with its in-plane coordinates)."""

    heights: np.ndarray  # (M,) height of each point above the plane
    near: np.ndarray  # (M,) bool: within the plane distance
    band: np.ndarray  # (M,) bool: between the prism's heights (its floor growing with range)
    cand: np.ndarray  # (C,) sorted indices of the points near or in the band
    x: np.ndarray  # (C,) the candidates' in-plane coordinates: ``fit.to_2d``'s columns, the same bits
    y: np.ndarray
    basis: np.ndarray  # the fit's basis and origin they were taken in
    origin: np.ndarray

    def serves(self, fit: TableFit) -> bool:
        """Were these values taken in ``fit``'s plane coordinates (a fit `replace` made
        from the same one, only its hull drawn anew)?"""
        return self.basis is fit.basis and self.origin is fit.origin


def lift(points: np.ndarray, fit: TableFit, settings: SegmentSettings, range2: np.ndarray | None = None) -> Lift:
    """`Lift` of ``points`` (M, 3) against ``fit`` (``range2``: their `squared_range`,
    when the caller has it)."""
    h = fit.plane.height_of(points)
    # one (M,) scratch array for |h|, the prism's floor and the two projections in turn:
    # each fresh whole-frame temporary costs its pages' first touch too (issue 39)
    scratch = np.abs(h)
    near = scratch <= settings.plane_distance_m
    min_h: float | np.ndarray = settings.prism_min_height_m
    if fit.camera_is_origin and settings.prism_noise_per_m2 > 0:
        # min_h + noise * range2, in place (a product and a sum commute: the same floats)
        np.multiply(squared_range(points) if range2 is None else range2, settings.prism_noise_per_m2, out=scratch)
        scratch += min_h
        min_h = scratch
    band = h >= min_h
    band &= h <= settings.prism_max_height_m
    near_or_band = np.logical_or(near, band)
    cand = np.flatnonzero(near_or_band)
    # one matrix-vector product per in-plane axis over all the points, then the
    # candidates' entries: a row's product does not depend on the rows around it (the
    # same bits as projecting a copy of the candidates' rows, which cost several times more)
    # (in two columns: the raster reads them so, and stacking them cost as much as the projection)
    x, y = (np.take(np.matmul(points, a, out=scratch), cand) for a in fit.basis)
    ox, oy = (fit.origin @ fit.basis.T).tolist()
    x -= ox
    y -= oy
    return Lift(h, near, band, cand, x, y, fit.basis, fit.origin)


def table_and_prism(
    points: np.ndarray,
    fit: TableFit,
    settings: SegmentSettings,
    range2: np.ndarray | None = None,
    lifted: Lift | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stage 2b: (table mask, prism mask, heights) over ``points`` (M, 3).

    Table: within plane distance and inside the hull grown by ``hull_margin_m``. Prism:
    between the prism heights (the lower one growing with range, as depth noise does)
    and inside the grown hull. ``range2``: `squared_range` of ``points`` when the
    caller has it already; ``lifted``: their `lift` against ``fit`` (or a fit of the
    same plane coordinates) when the caller has it: only the hull is read anew.
    """
    if lifted is None or not lifted.serves(fit):
        lifted = lift(points, fit, settings, range2)
    inside = np.zeros(points.shape[0], dtype=bool)
    inside[lifted.cand] = _inside_raster_xy(
        lifted.x, lifted.y, fit.polygon_2d, settings.hull_margin_m, _RASTER_CELL_M, None, fit.rasters
    )
    # near and band lie within cand: two whole-array ands, not a gather and a scatter each
    return inside & lifted.near, inside & lifted.band, lifted.heights


def beyond_the_edge(
    points: np.ndarray,
    shape: tuple[int, int],
    table_pixels: np.ndarray,
    plane: TablePlane,
    settings: SegmentSettings,
    heights: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Two (T,) bool masks over ``table_pixels`` (flat pixel indices of the table's points
    in the organized ``points`` of ``shape``, a camera frame; ``heights``: theirs above
    ``plane`` when the caller has them): the pieces of the plane
    that lie beyond a gap the camera sees through, which are not the table; and the
    pieces that are (the largest and those judged to stay), whose hull is the table's
    when something was dropped (stray pixels between pieces do not stretch it).

    A chair's seat, a second table or a shelf behind the table can lie within a
    centimetre of the table's plane and within ``table_join_gap_m`` of it: the plane
    alone takes it for table, the hull grows over it, and the chair's back becomes an
    object. On the pixel grid the table's points fall into pieces where the range jumps
    (as in edges.py). Between the largest piece and another one lies the area their
    joint hull adds to the largest piece's hull. Where that area is table hidden by
    objects, the pixel looking at a point of it shows something nearer (a mug in front
    of the table behind it); where it is no table, the pixel looks through it to
    something farther (the floor under a gap). A piece is beyond the
    edge when, of those looks (one per ``table_cell_m`` cell of the added area), at least
    ``_EDGE_MIN_CELLS`` see through and at least ``_EDGE_RATIO`` times as many see
    through as see something nearer. Pieces smaller than ``_EDGE_MIN_PIECE_PX`` are left
    alone (noise)."""
    height, width = shape
    drop = np.zeros(table_pixels.shape[0], dtype=bool)
    if table_pixels.size == 0:
        return drop, ~drop
    pts = points.reshape(height, width, 3)
    # the rows of the table's pixels and one more each side (where the image has them):
    # a jump cuts a table pixel off only from its neighbours, so the pieces are those of
    # this band alone, the same cells labelled in the same raster order (the rows above a
    # mOSD table, a sixth of the image, are no longer scanned, issue 39)
    top = max(int(table_pixels.min()) // width - 1, 0)
    bottom = min(int(table_pixels.max()) // width + 2, height)
    rows = bottom - top
    at = table_pixels - top * width  # the table's pixels, flat in the band
    # depth along the optical axis (NaN where none): a jump in it is a jump in range
    # to within the pixel's angle off the axis, and it costs no square roots (a
    # contiguous copy: the passes below over a strided view cost twice as much)
    band = np.ascontiguousarray(pts[top:bottom, :, 2])
    # the pieces' cells: table pixels without a jump to a neighbour, flat, then (rows, width)
    keep: np.ndarray = np.zeros(rows * width, dtype=bool)
    keep[at] = True
    # ... and not well under the plane: the top of a face beyond a narrow gap (a bench's
    # front seen over the table's edge) lies within the plane's band, under the plane,
    # and joined the bench's top to the table's pixel by pixel
    if heights is None:
        heights = plane.height_of(np.take(points.reshape(-1, 3), table_pixels, axis=0).astype(np.float64))
    keep[at[heights < -_EDGE_UNDER_M]] = False
    keep = keep.reshape(rows, width)
    rel = settings.depth_edge_rel
    # a table pixel with a jump to its right or lower neighbour belongs to no piece: both
    # sides of a jump are left out, so no 8-neighbour path crosses it. The two directions'
    # differences, limits and verdicts in the same three buffers: fresh frame-sized
    # temporaries cost their pages' first touch as well (issue 39). Each direction's
    # pairs as two flat, contiguous runs of the band, a pixel and the one a step after it
    # (raster.flat_step; a pair that wraps to the next row is no pair, and is let
    # through): the same pairs and floats as the 2D views, whose row-by-row strides cost
    # half as much again
    size = rows * width
    flat_depth, flat_keep = band.ravel(), keep.ravel()
    diff_buf, limit_buf = np.empty(size, dtype=band.dtype), np.empty(size, dtype=band.dtype)
    smooth_buf = np.empty(size, dtype=bool)
    with np.errstate(invalid="ignore"):
        for step, wrap_col in (flat_step(offset, width) for offset in ((0, 1), (1, 0))):
            if step >= size:
                continue
            a, b = flat_depth[:-step], flat_depth[step:]
            diff, limit, smooth = diff_buf[: size - step], limit_buf[: size - step], smooth_buf[: size - step]
            # |a - b| <= rel min(a, b) (NaN: a jump), in place: no temporary per operation;
            # a cell stays when no jump touches it (ANDs of the verdicts: the same cells
            # as table and not the OR of the jumps, without negating either)
            np.subtract(a, b, out=diff)
            np.abs(diff, out=diff)
            np.minimum(a, b, out=limit)
            limit *= rel
            np.less_equal(diff, limit, out=smooth)
            if wrap_col >= 0:
                smooth[wrap_col::width] = True  # a row's last pixel and the next row's first
            flat_keep[:-step] &= smooth
            flat_keep[step:] &= smooth
    pieces, n = label_8(keep)
    if n < 2:
        return drop, ~drop
    # each table point's piece (0: on a jump): the pieces lie on the table's pixels only, so
    # their sizes are counted over those, not over the whole image
    piece_of = np.take(pieces.ravel(), at)
    sizes = np.bincount(piece_of, minlength=n + 1)
    sizes[0] = 0
    main = int(sizes.argmax())
    others = [k for k in range(1, n + 1) if k != main and sizes[k] >= _EDGE_MIN_PIECE_PX]
    if not others:
        return drop, ~drop
    rng = np.ascontiguousarray(pts[..., 2])  # the whole image's depth: the looks may fall anywhere
    camera = _pinhole_of(pts, rng)
    if camera is None:
        return drop, ~drop
    basis = plane_basis(plane.normal)
    origin = -plane.offset * plane.normal
    cell = settings.table_cell_m
    # each table point's plane coordinates once (a row's product does not depend on the
    # rows around it: the same bits as projecting each piece's rows apart), taken per
    # piece in raster order
    on_table = np.take(points.reshape(-1, 3), table_pixels, axis=0).astype(np.float64)  # take: faster than a[idx]
    table_u, table_v = (on_table @ a for a in basis)

    ou, ov = (origin @ basis.T).tolist()

    def cells(k: int) -> np.ndarray:
        # column by column, in place: the same operations on each element as on the
        # stacked (N, 2) rows, without their temporaries
        mine = piece_of == k
        columns = []
        for coordinate, offset in ((table_u, ou), (table_v, ov)):
            c = np.compress(mine, coordinate)
            c -= offset
            c /= cell
            np.floor(c, out=c)
            columns.append(c)
        return unique_cells(np.stack(columns, axis=1).astype(np.int64))

    main_hull = convex_hull_2d(_rim_cells(cells(main), cell))
    gone: list[int] = []
    for k in others:
        own = cells(k)
        own_rim = _rim_cells(own, cell)
        # the joint hull from the main piece's hull vertices (its cells' centres, the same
        # floats) and the piece's cells: the same hull as of every cell of both, without
        # the main piece's thousands of cells sifted again for each piece
        both = convex_hull_2d(np.vstack([main_hull, own_rim]))
        lo = np.floor(both.min(axis=0) / cell).astype(np.int64)
        hi = np.ceil(both.max(axis=0) / cell).astype(np.int64)
        gx, gy = np.meshgrid(np.arange(lo[0], hi[0] + 1), np.arange(lo[1], hi[1] + 1), indexing="ij")
        grid = np.column_stack([gx.ravel(), gy.ravel()])
        centres = (grid + 0.5) * cell
        added = inside_convex(centres, both) & ~inside_convex(centres, main_hull, cell)
        if added.any():  # not the piece's own cells (one integer key per cell, not a set of tuples)
            (grid_keys, own_keys), _, _ = _packed(grid, own)
            added &= ~np.isin(grid_keys, own_keys)
        looks = origin + centres[added] @ basis  # points of the plane in the added area
        through = nearer = 0
        if looks.shape[0]:
            u, v = camera(looks)
            ok = (u >= 0) & (u < width) & (v >= 0) & (v < height)
            seen = rng[v[ok], u[ok]]
            want = looks[ok, 2]
            hidden = seen < want * (1.0 - rel)
            if settings.beyond_edge_own_load and hidden.any():
                # what hides a look and stands over the other piece itself (clutter on a
                # bench behind) is that piece's load: it tells nothing of table in between
                over = pts[v[ok][hidden], u[ok][hidden]].astype(np.float64) @ basis.T - origin @ basis.T
                hidden[np.flatnonzero(hidden)[inside_convex(over, convex_hull_2d(own_rim), -cell)]] = False
            nearer = int(hidden.sum())
            # farther than the plane: nothing stands there. A pixel with no depth tells
            # nothing (a shadow behind an object is one too)
            through = int((seen > want * (1.0 + rel)).sum())
        if through >= _EDGE_MIN_CELLS and through >= _EDGE_RATIO * nearer:
            gone.append(k)
    dropped = np.isin(piece_of, gone)
    return dropped, (piece_of == main) | np.isin(piece_of, others) & ~dropped


def _rim_cells(cells: np.ndarray, cell_m: float) -> np.ndarray:
    """The centres of the grid ``cells`` (distinct rows in `unique_cells`'s order, not
    empty) that can lie on their hull: the lowest and highest of each column, and every
    cell of the first and last columns. A cell between two of its own column (the same
    x, to the bit) lies inside the hull unless that column is an extreme one, where it
    lies on the hull's side: the same hull from a few hundred cells, not thousands."""
    u = cells[:, 0]
    edge = np.empty(u.size, dtype=bool)  # the first or the last of its column
    edge[0] = True
    np.not_equal(u[1:], u[:-1], out=edge[1:])
    edge[:-1] |= edge[1:].copy()
    edge[-1] = True
    edge |= (u == u[0]) | (u == u[-1])
    return (np.compress(edge, cells, axis=0) + 0.5) * cell_m  # rows by a mask: compress is faster


def _pinhole_of(pts: np.ndarray, depth: np.ndarray) -> Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]] | None:
    """The pixel of a point, as a function of (N, 3) points -> (columns, rows), fitted to
    an organized cloud's own points (column = fx X/Z + cx, row = fy Y/Z + cy, least
    squares on a sample); None when the cloud is not a pinhole image (a fit off by more
    than a pixel). ``depth``: the points' z, (height, width), contiguous (the caller's
    copy: a strided pass over the cloud's third column cost several times more)."""
    flat = np.flatnonzero(np.isfinite(depth) & (depth > 0))  # np.nonzero's pixels in its order, as one array
    if flat.size < 100:
        return None
    pick = np.linspace(0, flat.size - 1, 2000).astype(np.int64)
    rows, cols = np.divmod(flat[pick], pts.shape[1])
    p = pts[rows, cols].astype(np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        x, y = p[:, 0] / p[:, 2], p[:, 1] / p[:, 2]
    ok = np.isfinite(x) & np.isfinite(y)
    if not ok.all():  # a damaged cloud (x or y infinite where z is not): no SVD of inf
        if int(ok.sum()) < 100:
            return None
        x, y, rows, cols = x[ok], y[ok], rows[ok], cols[ok]
    fu, *_ = np.linalg.lstsq(np.column_stack([x, np.ones_like(x)]), cols.astype(np.float64), rcond=None)
    fv, *_ = np.linalg.lstsq(np.column_stack([y, np.ones_like(y)]), rows.astype(np.float64), rcond=None)
    err = max(np.abs(fu[0] * x + fu[1] - cols).max(), np.abs(fv[0] * y + fv[1] - rows).max())
    if not np.isfinite(err) or err > 1.0:
        return None

    def pixel(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        z = np.where(q[:, 2] > 1e-6, q[:, 2], np.nan)
        with np.errstate(invalid="ignore"):
            u = np.floor(fu[0] * q[:, 0] / z + fu[1] + 0.5)
            v = np.floor(fv[0] * q[:, 1] / z + fv[1] + 0.5)
        bad = ~(np.isfinite(u) & np.isfinite(v))
        u[bad], v[bad] = -1, -1
        return u.astype(np.int64), v.astype(np.int64)

    return pixel
