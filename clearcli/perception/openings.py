"""What segmentation tells the grasps beyond the thesis's top-down pinch (ours):

* **Open containers and their rims.** A bowl, a mug or a cup is taken by its rim, one
  finger inside the wall and one outside. `rim_of` says, from an object's points,
  whether it is an open container and where its rim is. In the table frame (heights
  above the support plane):

  1. the top band: points within ``RIM_BAND_M`` of the object's top (its 98th height
     percentile: one stray point does not lift it);
  2. a circle fitted to the band's footprint (algebraic least squares, Kasa's fit, then
     the radii of the band about its centre): the rim, when the band lies on it
     (median radial residual at most ``max(3 mm, 8 % of the radius)``) and goes around
     at least ``RIM_MIN_ARC_DEG`` of it (a box's top edge is a rectangle: it fails the
     residual; half a ring seen past a neighbour still passes);
  3. open, when the points inside the circle (well within the wall) lie mostly below
     the rim: a closed cylinder (a can) shows its lid there at the rim's height, a bowl
     its inner wall and floor, lower. At least ``RIM_MIN_INSIDE`` points inside are
     needed to tell (a rim seen so edge-on that nothing inside shows is "hidden");
  4. the wall's thickness: the spread of the radii of the band's topmost points (the
     rim's upper face is an annulus as wide as the wall), 5th to 95th percentile;
  5. how deep the inside is seen: the rim's height less the lowest inside point's.

  A shape that is not a container gets ``None`` and a reason (for the grasps' "why
  not"); pure geometry, no settings: the thresholds are shape facts of rims, not of a
  data set.

* **Table edges seen as edges.** A flat box is slid to the table's edge and pinched
  there: only where the camera sees the table end. `seen_edges` walks each side of the
  table polygon and looks just beyond it (``EDGE_PROBE_M`` outward, on the plane) through
  the camera: a pixel showing something farther than the table would be (the floor) or
  nothing at all (no return: nothing at the table's height there) is a drop; a pixel
  on the plane means the table goes on (the polygon stopped at clutter); a pixel
  nearer than the plane means something stands at the edge (a wall, a person); a
  probe outside the image means the view ends there, which is not an edge. A side is
  seen when at least ``EDGE_MIN_SHARE`` of its probes are drops. The camera is the
  organized grid's own pinhole, fitted from its pixels (``u = fx x/z + cx``): no
  intrinsics file is needed. Unorganized clouds have no pixels to look through: no
  side is seen (the slide is not offered, and says why).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from clearcli.perception.filters import finite_mask
from clearcli.perception.types import TablePlane

RIM_BAND_M = 0.008
RIM_MIN_ARC_DEG = 200.0
RIM_MIN_INSIDE = 12
RIM_MAX_POINTS = 4000
RIM_MIN_RADIUS_M = 0.02
RIM_MAX_RADIUS_M = 0.20
# the inside must lie this much below the rim for most of its points to call it open
RIM_INSIDE_DROP_M = 0.01

EDGE_PROBE_M = 0.03
EDGE_SAMPLES_PER_M = 40
EDGE_MIN_SHARE = 0.7
EDGE_DROP_M = 0.02  # a probe's pixel this much farther than the plane: a drop
EDGE_MIN_LENGTH_M = 0.05
EDGE_MERGE_DEG = 12.0


@dataclass(frozen=True)
class Rim:
    """The rim of an open container, in the sensor frame."""

    center: np.ndarray  # (3,) the rim circle's centre, at the rim's height
    radius_m: float  # to the middle of the wall
    height_m: float  # the rim above the table
    wall_m: float  # the wall's thickness where seen
    inside_depth_m: float  # how far below the rim the inside is seen
    arc_deg: float  # how much of the circle the rim's points cover


@dataclass(frozen=True)
class Opening:
    """One object's verdict: its rim, or why it has none."""

    rim: Rim | None
    why: str  # "" when rim is set


@dataclass(frozen=True)
class TableEdge:
    """One side of the table polygon (sensor frame) and whether the camera sees it end."""

    start: np.ndarray  # (3,)
    end: np.ndarray  # (3,)
    seen: bool
    why: str  # "drop beyond it" | "the view ends there" | "the table goes on" | ...


def _table_axes(plane: TablePlane) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return _axes_of(*(float(x) for x in plane.normal))


@functools.lru_cache(maxsize=8)
def _axes_of(nx: float, ny: float, nz: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The table's in-plane axes and normal, once a frame (not once an object); read
    only."""
    n = np.array([nx, ny, nz])
    a = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = a - (a @ n) * n
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    return e1, e2, n


def _fit_circle(xy: np.ndarray) -> tuple[np.ndarray, float]:
    # Kasa: x^2 + y^2 = 2 a x + 2 b y + c, linear in (a, b, c)
    A = np.column_stack([2.0 * xy, np.ones(len(xy))])
    rhs = (xy**2).sum(axis=1)
    sol, *_ = np.linalg.lstsq(A, rhs, rcond=None)
    centre = sol[:2]
    r2 = float(sol[2] + centre @ centre)
    return centre, float(np.sqrt(max(r2, 0.0)))


def _quantile(values: np.ndarray, q: float) -> float:
    """``np.quantile(values, q)`` of finite 1-D ``values`` (its linear rule, the same
    arithmetic on the same two order statistics), from one partition instead of its
    general machinery (most of its time on an object's few thousand points)."""
    n = values.shape[0]
    v = (n - 1) * q  # NumPy's virtual index, in float64 as there
    below = math.floor(v)
    if v >= n - 1:
        return float(values.max())
    part = np.partition(values, (below, below + 1))
    lo, hi = float(part[below]), float(part[below + 1])
    g = v - below
    step = hi - lo
    # NumPy's _lerp: from the lower value below the middle, from the upper one above
    return hi - step * (1 - g) if g >= 0.5 else lo + step * g


def rim_of(points_camera: np.ndarray, plane: TablePlane) -> Opening:
    """Whether the points (one object's, sensor frame) are an open container, and its rim."""
    p = np.asarray(points_camera)
    if len(p) > RIM_MAX_POINTS:  # an even sample: a rim is a shape, not a count
        p = p[:: -(-len(p) // RIM_MAX_POINTS)]
    p = np.asarray(p, dtype=float)
    p = np.compress(finite_mask(p), p, axis=0)  # rows by a mask: compress is several times faster
    if len(p) < 30:
        return Opening(None, "too few points to see a rim")
    e1, e2, n = _table_axes(plane)
    h = p @ n + float(plane.offset)
    xy = np.column_stack([p @ e1, p @ e2])
    top = _quantile(h, 0.98)
    band = h >= top - RIM_BAND_M
    if int(band.sum()) < 12:
        return Opening(None, "too few points at the top to see a rim")
    band_xy = np.compress(band, xy, axis=0)  # rows by a mask: compress is several times faster
    centre, radius = _fit_circle(band_xy)
    if not RIM_MIN_RADIUS_M <= radius <= RIM_MAX_RADIUS_M:
        return Opening(None, f"its top is no rim (a circle of {radius:.3f} m radius fits it)")
    rb = np.linalg.norm(band_xy - centre, axis=1)
    if float(np.mean(rb < 0.6 * radius)) > 0.1:
        return Opening(None, "closed: its top is covered inside its outline (a lid, a top face)")
    residual = float(np.median(np.abs(rb - radius)))
    if residual > max(0.003, 0.08 * radius):
        return Opening(None, "its top is not round (no rim)")
    ang = np.degrees(np.arctan2(*(band_xy - centre).T[::-1]))
    hist = np.histogram(ang, bins=36, range=(-180.0, 180.0))[0]
    arc = 10.0 * int(np.count_nonzero(hist))
    if arc < RIM_MIN_ARC_DEG:
        return Opening(None, f"its rim is seen over {arc:.0f} deg only (hidden)")
    # the rim's upper face: an annulus as wide as the wall
    rt = np.linalg.norm(np.compress(h >= top - 0.0025, xy, axis=0) - centre, axis=1)
    wall = _quantile(rt, 0.9) - _quantile(rt, 0.1) if len(rt) >= 8 else float("nan")
    # inside: below the rim and within the wall's middle (the far inner wall, the floor;
    # the near outer wall lies outside it)
    r_all = np.linalg.norm(xy - centre, axis=1)
    inner = (r_all < radius - 0.001) & (h < top - RIM_INSIDE_DROP_M)
    if int(inner.sum()) < RIM_MIN_INSIDE:
        return Opening(None, "nothing inside the rim is seen (the rim is hidden, or seen edge-on)")
    if not np.isfinite(wall) or wall > 0.02:
        return Opening(None, "the rim's wall is not thin enough to grasp across (or not seen)")
    depth = float(top - np.min(h[inner]))
    centre3 = centre[0] * e1 + centre[1] * e2 - float(plane.offset) * n + top * n
    return Opening(Rim(centre3, radius, top, max(wall, 0.001), depth, float(arc)), "")


def _pinhole(points: np.ndarray, shape: tuple[int, int]) -> tuple[float, float, float, float] | None:
    """fx, fy, cx, cy of an organized cloud, from its own pixels."""
    hgt, wid = shape
    # a regular sample of the pixels is plenty for four numbers (and costs no pass over
    # the whole frame)
    step = max(1, (hgt * wid) // 20000)
    idx = np.arange(0, hgt * wid, step)
    p = np.asarray(points[: hgt * wid : step], dtype=float)  # the rows of idx, by a slice (no gather)
    ok = np.all(np.isfinite(p), axis=1)
    ok[ok] = p[ok, 2] > 1e-3
    idx, p = idx[ok], np.compress(ok, p, axis=0)  # rows by a mask: compress is several times faster
    if len(idx) < 100:
        return None
    v, u = np.divmod(idx, wid)
    x = p[:, 0] / p[:, 2]
    y = p[:, 1] / p[:, 2]
    fu = np.linalg.lstsq(np.column_stack([x, np.ones_like(x)]), u.astype(float), rcond=None)[0]
    fv = np.linalg.lstsq(np.column_stack([y, np.ones_like(y)]), v.astype(float), rcond=None)[0]
    if fu[0] <= 0 or fv[0] <= 0:
        return None
    return float(fu[0]), float(fv[0]), float(fu[1]), float(fv[1])


def _straight_sides(poly: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """The polygon's sides, consecutive ones turning less than ``EDGE_MERGE_DEG`` joined
    (a hull of noisy points has many short, nearly straight pieces along one edge)."""
    k = len(poly)
    d = np.roll(poly, -1, axis=0) - poly
    ang = np.arctan2(d[:, 1], d[:, 0])  # any two axes do: the turn is what counts
    # start at the sharpest corner so no run wraps around the start
    turn = np.abs((ang - np.roll(ang, 1) + np.pi) % (2 * np.pi) - np.pi)
    start = int(np.argmax(turn))
    cos_lim = np.cos(np.radians(EDGE_MERGE_DEG))
    sides: list[tuple[np.ndarray, np.ndarray]] = []
    a = poly[start]
    run = d[start] / max(np.linalg.norm(d[start]), 1e-12)
    for j in range(1, k + 1):
        i = (start + j) % k
        if j == k:
            sides.append((a, poly[i]))
            break
        u = d[i] / max(np.linalg.norm(d[i]), 1e-12)
        if float(u @ run) < cos_lim:
            sides.append((a, poly[i]))
            a, run = poly[i], u
    return sides


def seen_edges(
    points: np.ndarray, shape: tuple[int, int] | None, plane: TablePlane, polygon: np.ndarray
) -> tuple[TableEdge, ...]:
    """Each side of the table polygon (sensor frame, in order) and whether it is seen to end."""
    poly = np.asarray(polygon, dtype=float).reshape(-1, 3)
    if len(poly) < 3:
        return ()
    sides = _straight_sides(poly)
    if shape is None:
        return tuple(TableEdge(a, b, False, "an unorganized cloud: no image to see the edge in") for a, b in sides)
    pts = points
    cam = _pinhole(pts, shape)
    if cam is None:
        return tuple(TableEdge(a, b, False, "too few pixels to place the camera") for a, b in sides)
    fx, fy, cx, cy = cam
    hgt, wid = shape
    n = np.asarray(plane.normal, dtype=float)
    middle = poly.mean(axis=0)
    out = []
    for a, b in sides:
        length = float(np.linalg.norm(b - a))
        if length < EDGE_MIN_LENGTH_M:
            out.append(TableEdge(a, b, False, "too short a side to slide to"))
            continue
        along = (b - a) / length
        outward = np.cross(along, n)
        if outward @ (a - middle) < 0:
            outward = -outward
        m = max(3, int(length * EDGE_SAMPLES_PER_M))
        t = (np.arange(m) + 0.5) / m
        probes = a + t[:, None] * (b - a) + EDGE_PROBE_M * outward
        z = probes[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.round(fx * probes[:, 0] / z + cx).astype(np.int64)
            v = np.round(fy * probes[:, 1] / z + cy).astype(np.int64)
        inside = (z > 1e-3) & (u >= 2) & (u < wid - 2) & (v >= 2) & (v < hgt - 2)
        # every probe's pixel at once: no return, farther than the plane (a drop),
        # nearer (something stands there), or on it (the table goes on)
        j = np.flatnonzero(inside)
        q = np.asarray(pts[v[j] * wid + u[j]], dtype=float)
        finite = np.all(np.isfinite(q), axis=1)
        rng_q = np.linalg.norm(np.where(finite[:, None], q, 0.0), axis=1)
        rng_p = np.linalg.norm(probes[j], axis=1)
        drops = int(np.count_nonzero(~finite | (rng_q > rng_p + EDGE_DROP_M)))
        nearer = int(np.count_nonzero(finite & (rng_q < rng_p - EDGE_DROP_M)))
        table = int(j.size) - drops - nearer
        if int(inside.sum()) < 0.5 * m:
            out.append(TableEdge(a, b, False, "the view ends there"))
        elif drops >= EDGE_MIN_SHARE * m:
            out.append(TableEdge(a, b, True, "a drop beyond it"))
        elif nearer > table:
            out.append(TableEdge(a, b, False, "something stands beyond it"))
        else:
            out.append(TableEdge(a, b, False, "the table goes on beyond it"))
    return tuple(out)


__all__ = ["Opening", "Rim", "TableEdge", "rim_of", "seen_edges"]
