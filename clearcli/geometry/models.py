"""Object models for the predicates: hulls, principal directions, oriented extents.

All geometry is built in a table-aligned frame ``{table}`` (see `TableFrame`): z along the
table normal (up), x along the sensor's viewing direction projected onto the table (away
from the camera), origin under the sensor. Heights are then plain z, footprints plain xy.
Results handed to other stages are transformed back to the sensor frame.

An object's solid (thesis 4.2, "Objects Modelling") is the convex hull of its points
together with their projection onto the table plane: the camera sees mostly the top and
one or two sides, the projection fills in the hidden sides.

Principal directions: the sides of the smallest-area rectangle holding the object's
footprint (its projected convex hull), the first along the longer side. The thesis takes
the PCA of the footprint; for a box these agree except when the footprint is nearly
square, where the PCA points anywhere (push directions 30-45 degrees off the faces).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from clearcli.perception.types import TablePlane

if TYPE_CHECKING:
    from clearcli.settings.geometry import PredicateSettings


def _apply(T: np.ndarray, points: np.ndarray) -> np.ndarray:
    """T applied to (N, 3) points (or one (3,) point). Written per column: an (N, 3) x
    (3, 3) matmul goes through BLAS, whose threads make it slower, not faster, here."""
    p = np.asarray(points)  # float32 input is promoted by the float64 transform
    if p.ndim == 1:
        return T[:3, :3] @ p + T[:3, 3]
    R = T[:3, :3]
    return p[:, 0:1] * R[:, 0] + p[:, 1:2] * R[:, 1] + p[:, 2:3] * R[:, 2] + T[:3, 3]


@dataclass(frozen=True, eq=False)
class TableFrame:
    """The table-aligned frame. ``T_table_camera`` maps sensor points to table points."""

    T_table_camera: np.ndarray
    T_camera_table: np.ndarray

    @staticmethod
    def from_plane(table: TablePlane) -> TableFrame:
        n = np.asarray(table.normal, dtype=float)
        n = n / np.linalg.norm(n)
        # the sensor's forward axis, flattened onto the table: "away from the camera"
        x = np.array([0.0, 0.0, 1.0]) - n[2] * n
        if np.linalg.norm(x) < 0.1:  # camera looking straight down: image "up" instead
            x = np.array([0.0, -1.0, 0.0]) - (-n[1]) * n
        x = x / np.linalg.norm(x)
        y = np.cross(n, x)
        R_camera_table = np.column_stack([x, y, n])
        origin = -float(table.offset) * n / float(n @ n)  # the sensor origin's foot point
        T_camera_table = np.eye(4)
        T_camera_table[:3, :3] = R_camera_table
        T_camera_table[:3, 3] = origin
        T_table_camera = np.eye(4)
        T_table_camera[:3, :3] = R_camera_table.T
        T_table_camera[:3, 3] = -R_camera_table.T @ origin
        return TableFrame(T_table_camera=T_table_camera, T_camera_table=T_camera_table)

    def to_table(self, points_camera: np.ndarray) -> np.ndarray:
        return _apply(self.T_table_camera, points_camera)

    def to_camera(self, points_table: np.ndarray) -> np.ndarray:
        return _apply(self.T_camera_table, points_table)

    def vector_to_camera(self, vectors_table: np.ndarray) -> np.ndarray:
        return np.asarray(vectors_table, dtype=float) @ self.T_camera_table[:3, :3].T

    def pose_to_camera(self, T_table_x: np.ndarray) -> np.ndarray:
        """T_camera_x from T_table_x."""
        return self.T_camera_table @ T_table_x


@dataclass(frozen=True, eq=False)
class ObjectGeometry:
    """One object's model in the table frame.

    axes2d: (2, 2) rows: first and second principal direction on the table (unit; row 1 is
            row 0 turned +90 deg about the table normal); the sign rule is in `_fix_sign`.
    center: (3,) centre of the oriented box (footprint centre, half height).
    extents: (3,) full sizes along axes2d[0], axes2d[1] and the normal.
    """

    segment_index: int
    n_points: int  # points given (the model keeps one per footprint cell)
    centroid: np.ndarray  # (3,) mean of the points
    hull_vertices: np.ndarray  # (V, 3)
    hull_faces: np.ndarray  # (F, 3) int, outward
    footprint: np.ndarray  # (K, 2) counter-clockwise convex polygon
    projected_xy: np.ndarray  # (M, 2) the points projected onto the table, one per cell
    column_heights: np.ndarray  # (M,) height of the highest point of each of those cells
    axes2d: np.ndarray
    center: np.ndarray
    extents: np.ndarray
    top_height_m: float
    bottom_height_m: float  # 2nd percentile of the points' heights: > 0 when lifted
    top_centroid: np.ndarray  # (3,) centroid of the top-surface points
    top_normal: np.ndarray  # (3,) third principal axis of the top surface, pointing up
    aabb: np.ndarray  # (2, 3) min, max of the hull
    fcl_object: Any = None  # fcl.CollisionObject of the hull

    @property
    def principal_axes3(self) -> np.ndarray:
        """(3, 3) rows: first, second principal direction on the table, table normal."""
        a = np.zeros((3, 3))
        a[:2, :2] = self.axes2d
        a[2, 2] = 1.0
        return a


class DegenerateObject(ValueError):
    """An object that cannot be given a solid model (too few points, a line)."""


def _hull(points: np.ndarray) -> Any:
    from scipy.spatial import ConvexHull, QhullError

    try:
        return ConvexHull(points)
    except QhullError:
        try:
            return ConvexHull(points, qhull_options="QJ")
        except QhullError as exc:
            raise DegenerateObject(f"no convex hull ({str(exc).splitlines()[0]})") from None


def fcl_convex(vertices: np.ndarray, faces: np.ndarray | None = None) -> Any:
    """fcl.CollisionObject of a convex polytope (identity pose).

    Without ``faces`` the shape carries one dummy triangle: fcl's GJK-based collision and
    distance queries on a Convex only use its vertices (support function), and handing
    python-fcl the faces costs ~0.3 ms per solid."""
    import fcl

    verts = np.ascontiguousarray(vertices, dtype=float)
    if faces is None:
        return fcl.CollisionObject(fcl.Convex(verts, 1, np.array([3, 0, 1, 2])), fcl.Transform())
    flat = np.hstack([np.full((len(faces), 1), 3, dtype=np.int64), faces.astype(np.int64)]).ravel()
    return fcl.CollisionObject(fcl.Convex(verts, len(faces), flat), fcl.Transform())


def convex_solid(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) and outward faces (F, 3) of the convex hull of ``points``."""
    hull = _hull(points)
    used = hull.vertices
    remap = np.full(len(points), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    faces = remap[hull.simplices]
    vertices = points[used]
    # qhull's simplices are not consistently oriented: turn each face outward
    inside = vertices.mean(axis=0)
    a, b, c = vertices[faces[:, 0]], vertices[faces[:, 1]], vertices[faces[:, 2]]
    u, w = (b - a).T, (c - a).T
    # the cross product written out (np.cross costs ~30 us of overhead per call)
    normal = np.stack([u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]], axis=1)
    flip = np.einsum("ij,ij->i", normal, a - inside) < 0
    faces[flip] = faces[flip][:, ::-1]
    return vertices, faces


def _polygon_moments(poly: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """Area, centroid (2,) and second central moments (2, 2) of a CCW polygon."""
    x, y = poly[:, 0], poly[:, 1]
    nxt = np.concatenate([poly[1:], poly[:1]])  # np.roll(poly, -1), without its overhead
    xn, yn = nxt[:, 0], nxt[:, 1]
    cross = x * yn - xn * y
    area = cross.sum() / 2.0
    if abs(area) < 1e-12:
        raise DegenerateObject("footprint has no area (the points lie on a line)")
    cx = ((x + xn) * cross).sum() / (6.0 * area)
    cy = ((y + yn) * cross).sum() / (6.0 * area)
    ixx = ((x * x + x * xn + xn * xn) * cross).sum() / 12.0
    iyy = ((y * y + y * yn + yn * yn) * cross).sum() / 12.0
    ixy = ((x * yn + 2 * x * y + 2 * xn * yn + xn * y) * cross).sum() / 24.0
    c = np.array([cx, cy])
    cov = np.array([[ixx, ixy], [ixy, iyy]]) / area - np.outer(c, c)
    return float(area), c, cov


def _min_area_rect_axis(poly: np.ndarray) -> np.ndarray:
    """Long-side direction of the smallest-area rectangle holding the convex polygon
    (K, 2): one of its sides lies on a polygon edge. For a box these are its faces,
    where the PCA of a nearly square footprint points anywhere (two touching 6.6 cm
    boxes got push directions 30 degrees off their faces, every push then blocked)."""
    edges = np.roll(poly, -1, axis=0) - poly
    lengths = np.linalg.norm(edges, axis=1)
    keep = lengths > 1e-12
    u = edges[keep] / lengths[keep, None]
    v = np.column_stack([-u[:, 1], u[:, 0]])
    wu = np.ptp(poly @ u.T, axis=0)
    wv = np.ptp(poly @ v.T, axis=0)
    k = int(np.argmin(wu * wv))
    return u[k] if wu[k] >= wv[k] else v[k]


def _fix_sign(axis: np.ndarray) -> np.ndarray:
    """The documented sign rule for dir1: the first principal direction points away from
    the camera (positive table x); exactly sideways, it points to table +y."""
    if axis[0] < -1e-9 or (abs(axis[0]) <= 1e-9 and axis[1] < 0):
        return -axis
    return axis


def _quantile(values: np.ndarray, fraction: float) -> float:
    """A plain order statistic (np.percentile costs ~0.1 ms of overhead per call)."""
    k = min(len(values) - 1, max(0, int(round(fraction * (len(values) - 1)))))
    return float(np.partition(values, k)[k])


def column_tops(q: np.ndarray, cell_m: float) -> np.ndarray:
    """The highest point (table frame) of each ``cell_m`` square of the footprint."""
    if cell_m <= 0.0 or len(q) == 0:
        return q
    cells = np.floor(q[:, :2] / cell_m).astype(np.int64)
    cells -= cells.min(axis=0)
    key = cells[:, 0] * (int(cells[:, 1].max()) + 1) + cells[:, 1]
    # highest z per cell without sorting all points (ufunc.at is linear)
    top = np.full(int(key.max()) + 1, -np.inf)
    np.maximum.at(top, key, q[:, 2])
    idx = np.nonzero(q[:, 2] >= top[key])[0]
    first = np.full(len(top), len(q), dtype=np.int64)
    np.minimum.at(first, key[idx], idx)  # one per cell among ties
    return q[first[first < len(q)]]


@dataclass(frozen=True, eq=False)
class Columns:
    """What the model needs of an object's points (table frame): their number, centroid,
    lowest heights (2nd percentile) and the highest point of each footprint cell.

    ``coarse_tops`` (the highest of ``tops`` per cell of ``coarse_cell_m``, as
    `column_tops` gives them) is filled by `object_columns` for all objects in one pass;
    without it `build_from_columns` computes the same per object."""

    n_points: int
    centroid: np.ndarray
    bottom_height_m: float
    tops: np.ndarray  # (M, 3)
    coarse_tops: np.ndarray | None = None
    coarse_cell_m: float = 0.0


def _segment_starts(counts: np.ndarray) -> np.ndarray:
    return np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)


def _grouped_tops(
    z: np.ndarray, counts: np.ndarray, cells_x: np.ndarray, cells_y: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Index of the highest point (first among ties) of each occupied cell, for points
    grouped by object (``counts`` per group, in order), sorted by group, then by cell
    (x index major), as `column_tops` orders them: one dense cell grid per group. Also
    the number of those cells per group."""
    present = counts > 0
    starts = _segment_starts(counts)[present]
    lo_x, lo_y = np.zeros(len(counts), np.int64), np.zeros(len(counts), np.int64)
    hi_x, hi_y = np.zeros(len(counts), np.int64), np.zeros(len(counts), np.int64)
    lo_x[present], lo_y[present] = np.minimum.reduceat(cells_x, starts), np.minimum.reduceat(cells_y, starts)
    hi_x[present], hi_y[present] = np.maximum.reduceat(cells_x, starts), np.maximum.reduceat(cells_y, starts)
    span_y = hi_y - lo_y + 1
    size = np.where(present, (hi_x - lo_x + 1) * span_y, 0)
    offset = _segment_starts(size)
    # per-group constants spread with repeat (cheaper than indexing by an owner array)
    key = cells_x * np.repeat(span_y, counts)
    key += cells_y
    key += np.repeat(offset - lo_x * span_y - lo_y, counts)
    top = np.full(int(size.sum()), -np.inf)
    np.maximum.at(top, key, z)  # highest z per cell without sorting (ufunc.at is linear)
    cand = np.nonzero(z >= top[key])[0]
    # one point per cell (the first of ties); reading the dense per-cell array in order
    # sorts them by key, that is by group (np.unique would sort, ten times slower)
    first = np.full(len(top), len(z), dtype=np.int64)
    np.minimum.at(first, key[cand], cand)
    occupied = first < len(z)
    per_group = np.zeros(len(counts), dtype=np.int64)
    per_group[present] = np.add.reduceat(occupied, offset[present], dtype=np.int64)
    return first[occupied], per_group


def table_rows(points_camera: np.ndarray, idx: np.ndarray, T_table_camera: np.ndarray) -> np.ndarray:
    """(3, N) rows x, y, z in the table frame of ``points_camera[idx]``: the transform
    column by column on contiguous float64 copies, the same products and sums, in the
    same order, as `TableFrame.to_table` (bit-identical), at half its cost. A non-finite
    input point gives non-finite coordinates (no warning); callers drop them."""
    P = np.asarray(points_camera)
    src = [P[:, i].take(idx).astype(np.float64) for i in range(3)]
    T = T_table_camera
    q = np.empty((3, len(idx)))
    tmp = np.empty(len(idx))
    with np.errstate(invalid="ignore", over="ignore"):
        for j in range(3):
            col = q[j]
            np.multiply(src[0], T[j, 0], out=col)
            np.multiply(src[1], T[j, 1], out=tmp)
            col += tmp
            np.multiply(src[2], T[j, 2], out=tmp)
            col += tmp
            col += T[j, 3]
    return q


def groups_table_rows(points_camera: np.ndarray, groups: list[np.ndarray], T_table_camera: np.ndarray) -> np.ndarray:
    """`table_rows` of the groups' point indices end to end (3, N)."""
    idx = np.concatenate([np.asarray(g, dtype=np.int64) for g in groups])
    return table_rows(points_camera, idx, T_table_camera)


def object_columns(
    points_camera: np.ndarray,
    groups: list[np.ndarray],
    frame: TableFrame,
    cell_m: float,
    rows: np.ndarray | None = None,
) -> list[Columns | None]:
    """`Columns` of each group of point indices, in one vectorised pass over all of them
    (per-object NumPy calls cost more than the arithmetic here). None for a group without
    finite points. ``rows``: the groups' points end to end in the table frame
    (`table_rows`), where the caller has them (read, not changed)."""
    n_g = len(groups)
    sizes = np.array([len(g) for g in groups], dtype=np.int64)
    if n_g == 0 or sizes.sum() == 0:
        return [None] * n_g
    if rows is None:
        q = groups_table_rows(points_camera, groups, frame.T_table_camera)
    else:
        q = rows.copy()  # its heights are clamped in place below
    # a non-finite coordinate makes every transformed coordinate non-finite (nan or inf,
    # no finite input overflows in float64), so the table height alone tells
    finite = np.isfinite(q[2])
    counts = sizes
    if not finite.all():
        owner = np.repeat(np.arange(n_g), sizes)[finite]
        q = q[:, finite]
        counts = np.bincount(owner, minlength=n_g)
    qx, qy, qz = q
    np.maximum(qz, 0.0, out=qz)  # noise below the table: the solid starts at the table
    starts = _segment_starts(counts)
    present = counts > 0
    inv = 1.0 / cell_m
    keep, t_counts = _grouped_tops(qz, counts, np.floor(qx * inv).astype(np.int64), np.floor(qy * inv).astype(np.int64))
    tops = np.column_stack([qx[keep], qy[keep], qz[keep]])
    cut = np.concatenate([[0], np.cumsum(t_counts)])
    # the coarse tops of the solid (`column_tops` on cells twice as coarse, per object)
    coarse_m = 2.0 * cell_m
    cx = np.floor(tops[:, 0] / coarse_m).astype(np.int64)
    cy = np.floor(tops[:, 1] / coarse_m).astype(np.int64)
    coarse_idx, c_counts = _grouped_tops(tops[:, 2], t_counts, cx, cy)
    coarse = tops[coarse_idx]
    c_cut = np.concatenate([[0], np.cumsum(c_counts)])
    out: list[Columns | None] = []
    for k in range(n_g):
        if not present[k]:
            out.append(None)
            continue
        s, e = starts[k], starts[k] + counts[k]
        # the mean of (n, 3) points sums row after row; a cumulative sum along each
        # coordinate adds in the same order (bit-identical) in one call per object
        centroid = np.cumsum(q[:, s:e], axis=1)[:, -1] / counts[k]
        out.append(
            Columns(
                n_points=int(counts[k]),
                centroid=centroid,
                bottom_height_m=_quantile(qz[s:e], 0.02),
                tops=tops[cut[k] : cut[k + 1]],
                coarse_tops=coarse[c_cut[k] : c_cut[k + 1]],
                coarse_cell_m=coarse_m,
            )
        )
    return out


def build_object(
    points_camera: np.ndarray,
    frame: TableFrame,
    segment_index: int,
    settings: PredicateSettings,
    *,
    with_fcl: bool = True,
) -> ObjectGeometry:
    """Model one object from its points (sensor frame) as [predicates] says (its
    min_object_points, min_object_height_m, top_surface_band_m, model_cell_m). Raises
    DegenerateObject."""
    pts = np.asarray(points_camera, dtype=float)
    cols = object_columns(pts, [np.arange(len(pts))], frame, settings.model_cell_m)[0]
    if cols is None:
        raise DegenerateObject(f"0 points (fewer than {settings.min_object_points})")
    return build_from_columns(cols, segment_index, settings, with_fcl=with_fcl)


def build_from_columns(
    cols: Columns,
    segment_index: int,
    settings: PredicateSettings,
    *,
    with_fcl: bool = True,
) -> ObjectGeometry:
    """Model one object from its `Columns` as [predicates] says. Raises DegenerateObject."""
    min_points, min_height_m = settings.min_object_points, settings.min_object_height_m
    top_band_m, cell_m = settings.top_surface_band_m, settings.model_cell_m
    from scipy.spatial import ConvexHull, QhullError

    if cols.n_points < min_points:
        raise DegenerateObject(f"{cols.n_points} points (fewer than {min_points})")
    # one point per footprint cell, the highest: a point under another one of its column
    # is inside the solid anyway, and the cell counts measure areas independent of how
    # densely the camera sampled each face
    q = cols.tops
    centroid, bottom = cols.centroid, cols.bottom_height_m
    if len(q) < 3:
        raise DegenerateObject("footprint has no area (the points lie on a line)")
    xy = q[:, :2]
    try:
        fp_hull = ConvexHull(xy)
    except QhullError:
        raise DegenerateObject("footprint has no area (the points lie on a line)") from None
    footprint = xy[fp_hull.vertices]  # scipy: counter-clockwise in 2D
    rim = q[fp_hull.vertices]  # the column tops on the footprint's border
    area, _, cov = _polygon_moments(footprint)
    if area < 1e-6:  # under 1 cm^2
        raise DegenerateObject(f"footprint of {area * 1e4:.2f} cm^2")
    a1 = _fix_sign(_min_area_rect_axis(footprint))
    a2 = np.array([-a1[1], a1[0]])
    axes2d = np.vstack([a1, a2])

    # top surface: its centroid (grasp point) and normal (grasp approach)
    top = _quantile(q[:, 2], 0.99)
    top = max(top, min_height_m)
    band = q[q[:, 2] >= top - top_band_m]
    if len(band) < 3:
        band = q
    top_centroid = band.mean(axis=0)
    top_normal = np.array([0.0, 0.0, 1.0])
    if len(band) >= 10:
        centred = band - top_centroid
        _, _, vt = np.linalg.svd(centred, full_matrices=False)
        nrm = vt[2]
        top_normal = nrm if nrm[2] >= 0 else -nrm

    # solid: the column tops (on cells twice as coarse: the hull does not need every one)
    # plus the tops on the footprint's border (exact where the sides are vertical) plus
    # the footprint on the table
    coarse = cols.coarse_tops if cols.coarse_tops is not None and cols.coarse_cell_m == 2.0 * cell_m else None
    upper = np.vstack([column_tops(q, 2.0 * cell_m) if coarse is None else coarse, rim])
    if float(q[:, 2].max()) < min_height_m:  # flat: give it a thickness
        upper[:, 2] = min_height_m
    lower = np.column_stack([footprint, np.zeros(len(footprint))])
    vertices, faces = convex_solid(np.vstack([upper, lower]))

    s1 = vertices[:, :2] @ a1
    s2 = vertices[:, :2] @ a2
    zmax = float(vertices[:, 2].max())
    lo = np.array([s1.min(), s2.min(), 0.0])
    hi = np.array([s1.max(), s2.max(), zmax])
    mid = (lo + hi) / 2.0
    center = np.array([*(mid[0] * a1 + mid[1] * a2), mid[2]])
    aabb = np.vstack([vertices.min(axis=0), vertices.max(axis=0)])
    return ObjectGeometry(
        segment_index=segment_index,
        n_points=cols.n_points,
        centroid=centroid,
        hull_vertices=vertices,
        hull_faces=faces,
        footprint=footprint,
        projected_xy=xy,
        column_heights=q[:, 2].copy(),
        axes2d=axes2d,
        center=center,
        extents=hi - lo,
        top_height_m=zmax,
        bottom_height_m=bottom,
        top_centroid=top_centroid,
        top_normal=top_normal,
        aabb=aabb,
        fcl_object=fcl_convex(vertices) if with_fcl else None,
    )


def hull_mesh(vertices: np.ndarray, faces: np.ndarray) -> Any:
    """trimesh.Trimesh of a hull (for rendering and export)."""
    import trimesh

    return trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
