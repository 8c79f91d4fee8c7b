"""Which candidate plane is the support: the surface the objects stand on (issue 37).

table.find_table scores each candidate plane by the points standing on it (above it,
inside its hull, minus those below it) and takes the best. That is the largest surface
holding things, which is wrong in two ways this module corrects:

- a raised surface (a stool, a chair's writing arm, a board on a box) over a floor: the
  floor holds the raised surface's body and whatever else stands on the floor (bags,
  chair legs), often more points than the few objects on the raised top. A candidate
  that lies over the best one (its outline inside the best one's), is held up from it
  (its body seen between them) and holds objects itself is where the objects are.
- a mat or a board a centimetre or so above the table: the table's plane leaves the mat
  in the prism (a flat "object" under the real ones, which lose their bottoms). A
  parallel candidate just above the best one, over it and holding objects, is the
  support; the two are one support surface and the objects stand on the upper one. A
  mat may be smaller than a table (`MAT_MIN_AREA_M2`): such a plane is a candidate for
  this rule only (``mat_only``).

Each decision has a margin: a surface is "over" another when four fifths of its outline
is inside the other's (grown 5 cm), "parallel" within 15 degrees, "holds objects" with
at least ``min_points`` points standing on it, and a body is seen with as many points;
every threshold is far from where rounding-sized changes of the points could move it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_PARALLEL_COS = float(np.cos(np.radians(15.0)))
_OVER_SHARE = 0.8  # of the upper surface's outline within the lower one's (grown)
_OVER_GROW_M = 0.05
# the lower surface is hidden at a point when the camera's ray nearest to it (within
# this angle: the RANSAC sample's 30 000 rays over a Kinect's or a RealSense's view lie
# about 0.006 rad apart) meets something this much nearer (raised_surface(14) close up:
# the stool's front 0.50-0.54 m before the floor under its far corners; a surface's own
# noise is millimetres)
_RAY_NEAR_RAD = 0.02
_HIDDEN_M = 0.05
_MAT_MAX_M = 0.03  # a mat, a board, a cloth: at most this far above the table
# A mat is a support smaller than a table may be (``table_min_area_m2``, 0.1 m^2): a
# plane down to this area is a candidate for the mat rule alone, never a table of its
# own. The smallest common placemat is 35 x 25 cm (0.0875 m^2); the objects on a mat
# hide 11-14 % of it from a camera at 35-45 degrees (self-made mats, measured), so its
# plane shows 0.075 m^2 or more; an A4 notebook (0.062 m^2) or a 13-inch laptop
# (0.064 m^2) with a cup on it stays a thing with a thing on it.
MAT_MIN_AREA_M2 = 0.07
_MAT_MIN_M = 0.004  # nearer than this, RANSAC has one plane for both
_RAISED_MIN_M = 0.25  # a raised surface (a stool, furniture): this far above the floor; a box on a table is lower
_STAND_MAX_M = 0.4  # objects standing on a surface are at most this tall
_BODY_OUT_M = 0.01  # a body flush with its top's edge is seen just inside or outside it
_EDGE_IN_M = 0.02  # the band inside a surface's outline that shows its edge, not its load
# concave: a wall rises around the surface (a bowl's inside, a tray). Looked for in the
# band from `_WALL_IN_M` inside its outline to `_WALL_OUT_M` beyond it (its outline
# takes in the wall's foot), in `_SECTORS` sectors around its middle: a sector is walled
# when `_WALL_SHARE` of its band's points stand `_WALL_M` or more above the surface; a
# surface walled in `_WALLED_MIN` sectors is concave. A bowl's band is 18-64 % such
# points in every sector, a mat's 0-2 % (an object at its edge walls a sector or two).
_WALL_IN_M = 0.03
_WALL_OUT_M = 0.01
_WALL_M = 0.02
_WALL_SHARE = 0.1
_SECTORS = 8
_WALLED_MIN = 6


@dataclass(frozen=True)
class Surface:
    """One candidate plane, oriented (``normal`` towards the camera side), its outline."""

    normal: np.ndarray  # (3,)
    offset: float
    basis: np.ndarray  # (2, 3) in-plane axes
    origin: np.ndarray  # (3,)
    polygon_2d: np.ndarray  # (K, 2) counter-clockwise

    def height(self, points: np.ndarray) -> np.ndarray:
        return points @ self.normal + self.offset

    def to_2d(self, points: np.ndarray) -> np.ndarray:
        """(N, 2) the points in its plane's coordinates."""
        return np.stack([points @ a for a in self.basis], axis=1) - self.origin @ self.basis.T

    def inside(self, points: np.ndarray, margin_m: float) -> np.ndarray:
        return _inside_convex(self.to_2d(points), self.polygon_2d, margin_m)


def _inside_convex(xy: np.ndarray, poly: np.ndarray, *margins_m: float) -> np.ndarray:
    """(N,) bool: the points ``xy`` inside the counter-clockwise ``poly`` grown by the
    margin; given several margins, (len(margins), N), one row each: every edge's
    distances worked out once for all of them (the same comparisons as one call each)."""
    edges = np.roll(poly, -1, axis=0) - poly
    out = np.stack([edges[:, 1], -edges[:, 0]], axis=1)
    out /= np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-12)
    base = np.einsum("ij,ij->i", out, poly)
    limits = [base + m for m in margins_m]
    ok = np.ones((len(margins_m), xy.shape[0]), dtype=bool)
    for k in range(poly.shape[0]):
        d = xy @ out[k]
        for row, limit in zip(ok, limits, strict=True):
            row &= d <= limit[k]
    return ok[0] if len(margins_m) == 1 else ok


@dataclass(frozen=True)
class Choice:
    index: int  # the surface chosen
    why: str
    rejected_why: dict[int, str]  # index -> why it is not the support (only those this module turned down)


def _outline_3d(s: Surface) -> np.ndarray:
    return s.origin + s.polygon_2d @ s.basis


def _over(lower: Surface, outline: np.ndarray, rise: float, every: np.ndarray) -> float:
    """The share of ``outline`` (a surface ``rise`` above ``lower``) that lies over
    ``lower``: inside its outline grown `_OVER_GROW_M`, or where the camera does not
    see ``lower`` at all (its rays through ``every`` point do not reach there: a camera
    low over a stool sees no floor under the stool's near half, below the image's bottom
    edge), or where something nearer hides it (`_hidden`: a camera close over a stool
    sees the stool's front and top where the floor under its far half would be). Without
    a camera above ``lower`` (offset under `_MAT_MIN_M`), the outline only."""
    inside = lower.inside(outline, _OVER_GROW_M)
    if inside.all() or lower.offset < _MAT_MIN_M or every.shape[0] < 3:
        return float(inside.mean())
    from scipy.spatial import ConvexHull

    # where the camera's rays (from the origin through the points seen) meet the lower
    # plane: the part of it in view, whatever hides it
    reach = np.linalg.norm(every, axis=1)
    unit = every / np.maximum(reach, 1e-12)[:, None]  # `_hidden` reads them too
    down = unit @ lower.normal
    rays = unit[down < -1e-6]
    if rays.shape[0] < 3:
        return float(inside.mean())
    hits = rays * (-lower.offset / (rays @ lower.normal))[:, None]
    xy = np.stack([hits @ a for a in lower.basis], axis=1) - lower.origin @ lower.basis.T
    hull = xy[ConvexHull(xy).vertices]  # counter-clockwise in 2-D
    beneath = outline - rise * lower.normal  # the outline's foot on the lower plane
    foot = np.stack([beneath @ a for a in lower.basis], axis=1) - lower.origin @ lower.basis.T
    unseen = ~_inside_convex(foot, hull, 0.0)
    return float((inside | unseen | _hidden(beneath, unit, reach)).mean())


def _hidden(points: np.ndarray, rays: np.ndarray, every_reach: np.ndarray) -> np.ndarray:
    """(N,) bool: the camera at the origin sees something nearer than each of ``points``
    along its ray: of the points seen (their unit ``rays`` and ranges ``every_reach``),
    the one whose ray is nearest (within `_RAY_NEAR_RAD`) lies `_HIDDEN_M` or more
    nearer. No such ray: not known to be hidden."""
    from scipy.spatial import cKDTree

    reach = np.linalg.norm(points, axis=1)
    d, j = cKDTree(rays).query(points / np.maximum(reach, 1e-12)[:, None], distance_upper_bound=_RAY_NEAR_RAD)
    found = np.isfinite(d)
    out = np.zeros(points.shape[0], dtype=bool)
    out[found] = every_reach[j[found]] < reach[found] - _HIDDEN_M
    return out


def standing_on(s: Surface, loose: np.ndarray, band_m: np.ndarray) -> np.ndarray:
    """(N,) bool: ``loose`` points standing on ``s``: above it by more than ``band_m``
    (per point: the noise grows with range), at most `_STAND_MAX_M`, inside its outline
    off its edge band."""
    h = s.height(loose)
    cand = (h > band_m) & (h <= _STAND_MAX_M)
    out = np.zeros(loose.shape[0], dtype=bool)
    idx = np.flatnonzero(cand)
    out[idx] = s.inside(loose[idx], -_EDGE_IN_M)
    return out


def walled_sectors(s: Surface, every: np.ndarray, every_xy: np.ndarray | None = None) -> int:
    """In how many of `_SECTORS` sectors around the middle of ``s``'s outline a wall rises
    at its edge: see `_WALL_IN_M`. ``every_xy``: ``s.to_2d(every)``, when the caller has it."""
    if every_xy is None:
        every_xy = s.to_2d(every)
    outer, inner = _inside_convex(every_xy, s.polygon_2d, _WALL_OUT_M, -_WALL_IN_M)
    band = outer & ~inner
    pts = every[band]
    if not pts.shape[0]:
        return 0
    # the band's rows of the projection (a row's product does not depend on the rows around it)
    xy = every_xy[band]
    mid = s.polygon_2d.mean(axis=0)
    ang = np.arctan2(xy[:, 1] - mid[1], xy[:, 0] - mid[0])
    sector = np.minimum((ang + np.pi) * (_SECTORS / (2 * np.pi)), _SECTORS - 1).astype(np.int64)
    n = np.bincount(sector, minlength=_SECTORS)
    up = np.bincount(sector, weights=(s.height(pts) >= _WALL_M).astype(np.float64), minlength=_SECTORS)
    return int(((n > 0) & (up >= _WALL_SHARE * n)).sum())


def _below_seen_share(
    s: Surface, every: np.ndarray, rise: float, half_m: float, every_xy: np.ndarray | None = None
) -> float:
    """Of ``every`` point inside ``s``'s outline (off its edge band) at the level of ``s``
    or of the surface ``rise`` below it (within ``half_m`` of either), the share at the
    lower level: the lower surface seen through, or beneath, the upper one's outline.
    ``every_xy``: ``s.to_2d(every)``, when the caller has it."""
    inner = every[_inside_convex(s.to_2d(every) if every_xy is None else every_xy, s.polygon_2d, -_EDGE_IN_M)]
    if not inner.shape[0]:
        return 0.0
    h = s.height(inner)
    upper = int((np.abs(h) < half_m).sum())
    below = int((np.abs(h + rise) < half_m).sum())
    return below / max(upper + below, 1)


def choose(
    surfaces: list[Surface],
    best: int,
    loose: np.ndarray,
    band_m: np.ndarray,
    every: np.ndarray,
    every_band_m: np.ndarray,
    min_points: int,
    mat_seen_max_share: float = 1.0,
    raised_seen_max_share: float = 1.0,
    mat_only: frozenset[int] = frozenset(),
) -> Choice | None:
    """The surface the objects stand on instead of ``surfaces[best]`` (the one with the
    most points above it), or None when that one stays (a Choice of ``best`` itself when
    it stays and a concave surface was turned down, to say why): see the module's docstring.
    ``loose``: the points on no candidate plane (what stands on them), ``every``: all
    points (a raised surface's body is often a candidate plane itself, its front face);
    ``*band_m``: per point, the height above a surface that is off it (noise grows with
    range). ``mat_only``: the surfaces smaller than a table (`MAT_MIN_AREA_M2` and up),
    which only the mat rule may choose."""
    lower = surfaces[best]
    low_h = lower.height(every)
    picks: list[tuple[float, int, str, str]] = []
    concave: dict[int, str] = {}
    for k, s in enumerate(surfaces):
        if k == best or abs(float(s.normal @ lower.normal)) < _PARALLEL_COS:
            continue
        outline = _outline_3d(s)
        rise = float(np.median(lower.height(outline)))
        if rise <= _MAT_MIN_M or (k in mat_only and rise > _MAT_MAX_M):
            continue
        if _over(lower, outline, rise, every) < _OVER_SHARE:
            continue
        on = standing_on(s, loose, band_m)
        n_on = int(on.sum())
        if n_on < min_points:
            continue
        every_xy = s.to_2d(every)  # once: the walls' band and the levels seen within read it
        walled = walled_sectors(s, every, every_xy)
        if walled >= _WALLED_MIN:
            # a bowl's inside holds what is in the bowl, which stands on the bowl, and the
            # bowl on the surface below
            concave[k] = (
                f"concave: a wall rises around it ({walled} of {_SECTORS} sides), the inside of a bowl or a "
                "tray; what is in it stands in a container"
            )
            continue
        if rise <= _MAT_MAX_M:
            seen = _below_seen_share(s, every, rise, rise / 2, every_xy)
            if seen > mat_seen_max_share:
                concave[k] = (
                    f"no mat: the plane below shows within its outline ({seen:.0%} of the points at the two levels "
                    "there), things lying apart on it"
                )
                continue
            picks.append(
                (
                    rise,
                    k,
                    f"a mat or board {rise * 1000:.0f} mm above the plane below it, holding {n_on} "
                    "points: one support with it, and the objects stand on this one",
                    f"one support with the mat or board {rise * 1000:.0f} mm above it, on which the objects stand",
                )
            )
            continue
        if rise < _RAISED_MIN_M:
            continue
        # held up from the lower surface: its body seen between the two, inside its outline
        between = (s.height(every) < -every_band_m) & (low_h > every_band_m)
        idx = np.flatnonzero(between)
        body = int(s.inside(every[idx], _BODY_OUT_M).sum()) if idx.size else 0
        if body < min_points:
            continue
        seen = _below_seen_share(s, every, rise, _MAT_MAX_M / 2, every_xy)
        if seen > raised_seen_max_share:
            concave[k] = (
                f"no raised surface: the plane below goes on beneath it ({seen:.0%} of the points at the two "
                "levels within its outline), a shelf or a board held over the support"
            )
            continue
        picks.append(
            (
                rise,
                k,
                f"a raised surface {rise:.2f} m above the plane below it, held up from it ({body} points of "
                f"its body seen) and holding {n_on} points: the objects stand on it",
                f"the floor around a raised surface {rise:.2f} m above it that holds the objects",
            )
        )
    if not picks:
        # the best one stays; the concave surfaces turned down still say why
        return Choice(best, "the most points standing on it", concave) if concave else None
    # the highest such surface (a raised one over a mat on the floor is still raised)
    picks.sort(key=lambda p: (-p[0], p[1]))
    _, k, why, lower_why = picks[0]
    return Choice(k, why, {**concave, best: lower_why})
