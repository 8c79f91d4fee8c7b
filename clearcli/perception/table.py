"""Stage 2: the table. RANSAC planes, the support surface among them, its 2D convex hull
and the polygonal prism of points above it.

A frame that is not cropped to the table holds several planes (floor, walls, other
tables, big flat objects). The support surface is the candidate with the most points
standing on it (above it, inside its hull, within a hand's reach), after the points of
every candidate plane are set aside; a wall's "objects" are mostly the table, which is
itself a plane, and a book's hull holds little.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clearcli.errors import SceneError
from clearcli.settings.segment import SegmentSettings
from clearcli.perception.types import TablePlane

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
# Off-plane points within this of a candidate's hull boundary count neither as standing on
# it nor as behind it: they show its edge, not what it holds. The sides of a slab seen over
# its edge (a board as big as the table) lie there below its top, and the table in front
# of a wall (or of a big box's front face) lies there off the wall's bottom edge; both
# within a few mm. What stands on a table, or under one seen from below, is inside.
_EDGE_BAND_M = 0.02


@dataclass(frozen=True, eq=False)
class TableFit:
    plane: TablePlane
    polygon_2d: np.ndarray  # (K, 2) hull vertices, counter-clockwise, in (u, v) plane coordinates
    origin: np.ndarray  # (3,) a point on the plane, the 2D origin
    basis: np.ndarray  # (2, 3) rows u, v: in-plane unit axes; u x v = normal
    camera_is_origin: bool  # the cloud is in a camera frame (sensor at the origin, above the table)

    @property
    def polygon(self) -> np.ndarray:
        """(K, 3) hull vertices on the plane, in the sensor frame."""
        return self.origin + self.polygon_2d @ self.basis

    def to_2d(self, points: np.ndarray) -> np.ndarray:
        return project(points, self.basis) - self.origin @ self.basis.T

    def inside(self, points: np.ndarray, margin_m: float = 0.0) -> np.ndarray:
        return inside_convex_raster(self.to_2d(points), self.polygon_2d, margin_m)


def project(points: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """(N, K) coordinates of points along the K rows of ``axes``. One matrix-vector
    product per axis: (N, 3) @ (3, K) with a tiny inner size is several times slower."""
    return np.stack([points @ a for a in axes], axis=1)


def plane_basis(normal: np.ndarray) -> np.ndarray:
    """(2, 3) orthonormal in-plane axes u, v with u x v = normal."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(helper, normal)
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    return np.stack([u, v])


def fit_plane_lsq(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Least-squares plane (unit normal, offset) through points."""
    c = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - c, full_matrices=False)
    n = vt[2]
    return n, float(-n @ c)


def ransac_plane(
    points: np.ndarray, distance_m: float, iterations: int, rng: np.random.Generator
) -> tuple[np.ndarray, float]:
    """The plane with the most inliers among random triplets (scored on a subsample),
    refined by least squares on its inliers. Hypotheses are drawn in chunks and the
    search stops once enough were drawn to have hit an all-inlier triplet of the best
    plane so far with probability 0.999 (at most ``iterations``)."""
    n_pts = points.shape[0]
    ev = points[rng.integers(0, n_pts, size=min(_RANSAC_EVAL, n_pts))]
    best_count, best_n, best_d = -1, None, 0.0
    drawn = 0
    while drawn < iterations:
        chunk = min(_RANSAC_CHUNK, iterations - drawn)
        drawn += chunk
        tri = points[rng.integers(0, n_pts, size=(chunk, 3))]
        normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        norm = np.linalg.norm(normals, axis=1)
        ok = norm > 1e-9
        if not ok.any():
            continue
        normals = normals[ok] / norm[ok, None]
        offsets = -np.einsum("ij,ij->i", normals, tri[ok, 0])
        counts = (np.abs(ev @ normals.T + offsets) <= distance_m).sum(axis=0)
        k = int(np.argmax(counts))
        if counts[k] > best_count:
            best_count, best_n, best_d = int(counts[k]), normals[k], float(offsets[k])
        w = best_count / ev.shape[0]
        if w >= 1.0 or (w > 0 and drawn >= np.log(1e-3) / np.log(1.0 - w**3)):
            break
    if best_n is None:
        raise SceneError("no plane: the points are degenerate")
    n, d = best_n, best_d
    for _ in range(2):  # refine: least squares on inliers, twice to settle
        inl = np.abs(points @ n + d) <= distance_m
        if inl.sum() < 3:
            break
        n, d = fit_plane_lsq(points[inl])
    return n, d


def convex_hull_2d(points_2d: np.ndarray) -> np.ndarray:
    """(K, 2) hull vertices counter-clockwise."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        hull = ConvexHull(points_2d)
    except QhullError as exc:
        raise SceneError(f"no table: the table points are degenerate ({str(exc).splitlines()[0]})") from None
    return points_2d[hull.vertices]


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
    points_2d: np.ndarray, polygon_2d: np.ndarray, margin_m: float = 0.0, cell_m: float = 0.005
) -> np.ndarray:
    """`inside_convex` looked up in a raster of the polygon (cells of ``cell_m``): exact
    to within a cell near the boundary, and an order of magnitude faster for the
    hundreds of thousands of table points than testing every hull edge."""
    lo = polygon_2d.min(axis=0) - margin_m - cell_m
    hi = polygon_2d.max(axis=0) + margin_m + cell_m
    dims = np.ceil((hi - lo) / cell_m).astype(np.int64)
    if dims[0] * dims[1] > 2_000_000 or points_2d.shape[0] < dims[0] * dims[1] // 4:
        return inside_convex(points_2d, polygon_2d, margin_m)
    gx = lo[0] + (np.arange(dims[0]) + 0.5) * cell_m
    gy = lo[1] + (np.arange(dims[1]) + 0.5) * cell_m
    centers = np.stack(np.meshgrid(gx, gy, indexing="ij"), axis=-1).reshape(-1, 2)
    grid = inside_convex(centers, polygon_2d, margin_m).reshape(dims[0], dims[1])
    cx = np.floor((points_2d[:, 0] - lo[0]) / cell_m).astype(np.int64)
    cy = np.floor((points_2d[:, 1] - lo[1]) / cell_m).astype(np.int64)
    ok = (cx >= 0) & (cx < dims[0]) & (cy >= 0) & (cy < dims[1])
    out = np.zeros(points_2d.shape[0], dtype=bool)
    out[ok] = grid[cx[ok], cy[ok]]
    return out


def _label_grid(grid: np.ndarray) -> tuple[np.ndarray, int]:
    """8-connected components of a 2D bool grid: (labels (H, W), n), 0 off the grid's
    cells, 1..n numbered in raster order of each component's first cell, as
    scipy.ndimage.label numbers them (this replaces ndimage.label and binary_dilation:
    importing scipy.ndimage cost more than everything they did here)."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components

    h, w = grid.shape
    flat = np.flatnonzero(grid)  # raster order
    m = flat.size
    labels = np.zeros(grid.shape, dtype=np.int32)
    if m == 0:
        return labels, 0
    ids = np.full((h + 2, w + 2), -1, dtype=np.int32)  # cell -> node, -1 empty, a border of -1
    inner = ids[1:-1, 1:-1]
    inner[grid] = np.arange(m, dtype=np.int32)
    src: list[np.ndarray] = []
    dst: list[np.ndarray] = []
    for dy, dx in ((0, 1), (1, -1), (1, 0), (1, 1)):  # each neighbouring pair once
        nbr = ids[1 + dy : h + 1 + dy, 1 + dx : w + 1 + dx]
        hit = (inner >= 0) & (nbr >= 0)
        src.append(inner[hit])
        dst.append(nbr[hit])
    a, b = np.concatenate(src), np.concatenate(dst)
    graph = csr_matrix((np.ones(a.size, dtype=np.int8), (a, b)), shape=(m, m))
    n, comp = connected_components(graph, directed=False)
    first = np.full(n, m, dtype=np.int64)
    np.minimum.at(first, comp, np.arange(m))
    rank = np.empty(n, dtype=np.int32)
    rank[np.argsort(first)] = np.arange(1, n + 1, dtype=np.int32)
    labels.ravel()[flat] = rank[comp]
    return labels, int(n)


def _dilate(mask: np.ndarray, steps: int) -> np.ndarray:
    """``mask`` dilated ``steps`` times by a 3x3 square (ndimage.binary_dilation's
    ``iterations``), i.e. every cell within Chebyshev distance ``steps`` of a set cell:
    a box sum over (2 steps + 1) cells along each axis, by cumulative sums."""
    out = mask.astype(np.int32)
    width = 2 * steps + 1
    for axis in (0, 1):
        pad = [(0, 0), (0, 0)]
        pad[axis] = (steps + 1, steps)
        c = np.cumsum(np.pad(out, pad), axis=axis, dtype=np.int32)
        out = c[width:] - c[:-width] if axis == 0 else c[:, width:] - c[:, :-width]
    return out > 0


def largest_component(points_2d: np.ndarray, cell_m: float, join_gap_m: float = 0.0) -> tuple[np.ndarray, float]:
    """Mask of the points in the largest 8-connected piece of the occupied grid cells,
    together with every other piece within ``join_gap_m`` of it (objects standing on a
    table and their shadows cut its visible surface into pieces), and their area (m^2)."""
    cells = np.floor((points_2d - points_2d.min(axis=0)) / cell_m).astype(np.int64)
    dims = cells.max(axis=0) + 1
    if dims[0] * dims[1] > 4_000_000:  # a plane reaching far away: coarser cells
        scale = int(np.ceil(np.sqrt(dims[0] * dims[1] / 4_000_000)))
        cells //= scale
        cell_m *= scale
        dims = cells.max(axis=0) + 1
    grid = np.zeros(dims, dtype=bool)
    grid[cells[:, 0], cells[:, 1]] = True
    labels, n = _label_grid(grid)
    if n == 0:
        return np.zeros(points_2d.shape[0], dtype=bool), 0.0
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    best = int(np.argmax(sizes))
    chosen = np.zeros(n + 1, dtype=bool)
    chosen[best] = True
    steps = int(round(join_gap_m / cell_m))
    if steps > 0 and n > 1:
        near = _dilate(labels == best, steps)
        touched = np.unique(labels[near])
        touched = touched[(touched > 0) & (sizes[touched] >= 4)]  # not specks
        chosen[touched] = True
    return chosen[labels[cells[:, 0], cells[:, 1]]], float(sizes[chosen].sum()) * cell_m * cell_m


@dataclass
class _Candidate:
    normal: np.ndarray
    offset: float
    members: np.ndarray  # indices into the sample of the largest connected piece
    area_m2: float
    on_plane: np.ndarray  # bool over the sample: within distance of this plane


def find_table(points: np.ndarray, settings: SegmentSettings, organized: bool, source: str = "") -> TableFit:
    """Stage 2a: the support plane among up to ``plane_candidates`` RANSAC planes.

    ``points``: (M, 3) finite float64 points that survived outlier removal.
    Raises SceneError when no plane of at least ``table_min_area_m2`` exists, or when the
    objects are on the far side of the table (a table seen from below).
    """
    where = f"{source}: " if source else ""
    if points.shape[0] < 100:
        raise SceneError(f"{where}no table: only {points.shape[0]} usable points in the frame")
    rng = np.random.default_rng(0)  # fixed: the same frame always gives the same table
    step = max(1, points.shape[0] // _RANSAC_SAMPLE)
    sample = points[::step]
    dist = settings.plane_distance_m

    candidates: list[_Candidate] = []
    remaining = np.ones(sample.shape[0], dtype=bool)
    for _ in range(settings.plane_candidates):
        idx = np.flatnonzero(remaining)
        if idx.size < 50:
            break
        n, d = ransac_plane(sample[idx], dist, settings.ransac_iterations, rng)
        on_plane = np.abs(sample @ n + d) <= dist
        inl = np.flatnonzero(on_plane & remaining)
        remaining &= ~on_plane
        if inl.size < 30:
            continue
        basis = plane_basis(n)
        comp, area = largest_component(project(sample[inl], basis), settings.table_cell_m, settings.table_join_gap_m)
        if area < settings.table_min_area_m2:
            continue
        candidates.append(_Candidate(n, d, inl[comp], area, on_plane))
    if not candidates:
        raise SceneError(
            f"{where}no table: no plane of at least {settings.table_min_area_m2} m^2 in the frame; "
            "is a table in view?"
        )

    any_plane = np.zeros(sample.shape[0], dtype=bool)
    for c in candidates:
        any_plane |= c.on_plane
    loose = sample[~any_plane]  # points on none of the candidate planes
    loose_range2 = np.einsum("ij,ij->i", loose, loose)

    best: tuple[tuple[int, float], TableFit, int, int] | None = None
    for c in candidates:
        n, d = fit_plane_lsq(sample[c.members])
        camera_is_origin = abs(d) >= _MIN_CAMERA_HEIGHT_M
        if camera_is_origin and abs(d) > settings.table_max_distance_m:
            continue
        basis = plane_basis(n)
        origin = -d * n
        poly = convex_hull_2d(project(sample[c.members], basis) - origin @ basis.T)
        h = loose @ n + d
        # depth noise grows with the square of the range: far off-plane points are
        # noise of the plane itself, not things standing on it
        band = (np.abs(h) > settings.prism_min_height_m + _NOISE_PER_M2 * loose_range2) & (
            np.abs(h) <= _SCORE_HEIGHT_M
        )
        ins = np.zeros(loose.shape[0], dtype=bool)
        ins[band] = inside_convex(project(loose[band], basis) - origin @ basis.T, poly, -_EDGE_BAND_M)
        above = int((ins & (h > 0)).sum())
        below = int((ins & (h < 0)).sum())
        if camera_is_origin:
            if d < 0:  # orient the normal towards the camera
                n, d, above, below = -n, -d, below, above
        elif below > above:  # not a camera frame: "up" is where the objects are
            n, d, above, below = -n, -d, below, above
        basis = plane_basis(n)
        origin = -d * n
        poly = convex_hull_2d(project(sample[c.members], basis) - origin @ basis.T)
        fit = TableFit(TablePlane(normal=n, offset=float(d)), poly, origin, basis, camera_is_origin)
        # noise lies on both sides of a plane, objects on one: score the difference
        key = (abs(above - below), c.area_m2)
        if best is None or key > best[0]:
            best = (key, fit, above, below)
    if best is None:
        raise SceneError(
            f"{where}no table: every plane of table size is more than "
            f"{settings.table_max_distance_m} m from the camera; is a table in reach?"
        )
    _, fit, above, below = best

    # Seen from below: what stands on the table is on the far side from the camera (the
    # camera side of a table's underside holds nothing inside its hull), or, for a camera
    # image, "up" (the table normal towards the camera) points down the image.
    min_obj = max(20, int(0.001 * sample.shape[0]))
    if fit.camera_is_origin and below > max(above, min_obj):
        raise SceneError(
            f"{where}no usable table: the best support plane ({fit.plane.offset:.2f} m from the "
            "camera) has more points behind it than standing on it; the table is seen from "
            "below, or there is no table in view"
        )
    if organized and fit.camera_is_origin and fit.plane.normal[1] > 0.5:
        raise SceneError(
            f"{where}the table is seen from below: its top faces down the image "
            f"(normal {np.round(fit.plane.normal, 2).tolist()} in the optical frame); "
            "segmentation needs a view from above the table"
        )
    return fit


def table_and_prism(
    points: np.ndarray, fit: TableFit, settings: SegmentSettings
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stage 2b: (table mask, prism mask, heights) over ``points`` (M, 3).

    Table: within plane distance and inside the hull grown by ``hull_margin_m``. Prism:
    between the prism heights (the lower one growing with range, as depth noise does)
    and inside the grown hull.
    """
    h = fit.plane.height_of(points)
    near = np.abs(h) <= settings.plane_distance_m
    min_h = settings.prism_min_height_m
    if fit.camera_is_origin and settings.prism_noise_per_m2 > 0:
        min_h = min_h + settings.prism_noise_per_m2 * np.einsum("ij,ij->i", points, points)
    band = (h >= min_h) & (h <= settings.prism_max_height_m)
    cand = np.flatnonzero(near | band)
    # one matrix-vector product per in-plane axis, on the candidates only
    xy = project(points[cand], fit.basis) - fit.origin @ fit.basis.T
    ins = inside_convex_raster(xy, fit.polygon_2d, settings.hull_margin_m)
    table = np.zeros(points.shape[0], dtype=bool)
    prism = np.zeros(points.shape[0], dtype=bool)
    table[cand[ins & near[cand]]] = True
    prism[cand[ins & band[cand]]] = True
    return table, prism, h
