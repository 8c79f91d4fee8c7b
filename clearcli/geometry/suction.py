"""A suction cup's contact on an object, judged from the object's own points (table frame).

Where a cup can seal (`contacts`): candidate centres on the faces the camera saw, from
above (the top) and from the side (the faces across the object's footprint axes). Each
is judged on the points within the cup's disc, in the frame of the face:

* **covered**: every sample of the disc (a grid half ``gap_m`` apart, and a ring near the
  rim) has a point of the object within ``gap_m`` of it, seen from along the normal: no hole, no edge inside the cup;
* **alone**: no other object's point within the disc and within the bellows' stroke of
  the face (the cup would seal on two objects, or on none);
* **flat**: a quadric z = f(u, v) fitted to the points; its bending over the disc (the
  largest sag of its second-order part below the tangent plane) and the points' spread
  about it (the 90th percentile of |residual|) must both be within the bellows'
  compliance. A quadric, not a plane: its bending is what a curved face has and sensor
  noise has not (noise averages out of a least-squares fit over ~100 points), so a
  cylinder of radius 2 cm under a 30 mm cup (sag 6.8 mm) is told from a flat face seen
  by a Kinect (noise ~1.5 mm); the spread catches ribs and grooves deeper than the lip
  can follow;
* **facing**: the fitted normal within ``max_tilt_deg`` of the approach (straight down
  for the top, horizontal for a side).

The load (`load_margin`): the object's weight from its modelled volume and a density,
held against the cup's force with a safety factor: the pull along the cup's axis against
the holding force, the pull across it against the friction of the lip, and the moment of
the weight about the contact (the centre of mass off the cup's axis peels the lip)
against the holding force at the cup's radius. One utilisation, summed linearly (each
term uses up a share of the same seal): 1 - utilisation is the load's margin.

A candidate's margin is the smallest of its seal margins and its load margin; the best
candidate is kept. Margins, not booleans: a candidate within rounding of a limit is
never preferred to one well inside it.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

GRAVITY_M_S2 = 9.81
UP = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class CupSpec:
    """The cup and its load limits (the [suction] settings, in SI units)."""

    diameter_m: float
    compliance_m: float  # the bellows' stroke: how far the lip follows the surface
    holding_force_n: float  # the vacuum's pull on a sealed cup
    safety_factor: float
    lip_friction: float  # shear the lip holds, as a share of the holding force
    max_tilt_deg: float  # the fitted normal's largest angle from the approach
    gap_m: float = 0.004  # a disc sample farther than this from every point is a hole

    @property
    def radius_m(self) -> float:
        return self.diameter_m / 2.0


@dataclass(frozen=True)
class Contact:
    """One place the cup may take an object (table frame), judged."""

    face: str  # "top" or "side"
    point: np.ndarray  # (3,) the disc's centre on the fitted surface
    normal: np.ndarray  # (3,) outward, unit: the cup approaches along -normal
    covered: float  # share of the disc's samples with a point of the object
    sag_m: float  # the fitted surface's bending below its tangent plane over the disc
    spread_m: float  # 90th percentile of the points' distances to the fitted surface
    tilt_deg: float  # the normal's angle from the approach's nominal direction
    others: int  # other objects' points inside the cup's disc
    seal_margin: float  # min of the seal tests' margins (> 0: seals)
    why: str = ""  # the first seal test that fails ("" when it seals)
    load_margin: float = math.nan
    load_why: str = ""

    @property
    def margin(self) -> float:
        return min(self.seal_margin, self.load_margin) if not math.isnan(self.load_margin) else self.seal_margin


@dataclass(frozen=True)
class Judged:
    """Every candidate of one object, and the best (None: none seals and holds)."""

    contacts: tuple[Contact, ...] = field(default_factory=tuple)
    best: Contact | None = None

    def why_not(self, spec: CupSpec) -> str:
        """Why no candidate is kept, from the one that came closest."""
        if self.best is not None:
            return ""
        if not self.contacts:
            return f"no face of {1000 * spec.diameter_m:.0f} mm seen (the object is smaller than the cup)"
        closest = max(self.contacts, key=lambda c: c.margin)
        if closest.seal_margin <= 0:
            return f"no flat patch of {1000 * spec.diameter_m:.0f} mm: {closest.why}"
        return closest.load_why


def disc_samples(radius_m: float, spacing_m: float) -> np.ndarray:
    """(K, 2) points of the disc in its own plane: a square grid ``spacing_m`` apart
    within 95 % of the radius, and a ring of them there (a sample on the rim itself
    would test the lip's outside, which may overhang an edge by the lip's own width)."""
    r = 0.95 * radius_m
    n = int(math.floor(r / spacing_m))
    g = spacing_m * np.arange(-n, n + 1)
    u, v = np.meshgrid(g, g)
    inside = u * u + v * v <= r * r
    k = max(int(math.ceil(2.0 * math.pi * r / spacing_m)), 6)
    a = 2.0 * math.pi * np.arange(k) / k
    ring = np.stack([r * np.cos(a), r * np.sin(a)], axis=1)
    return np.concatenate([np.stack([u[inside], v[inside]], axis=1), ring])


def _frame(normal: np.ndarray) -> np.ndarray:
    """(3, 3) rows: two unit vectors across ``normal``, then ``normal``."""
    n = normal / np.linalg.norm(normal)
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    a = np.cross(n, helper)
    a /= np.linalg.norm(a)
    return np.stack([a, np.cross(n, a), n])


def fit_quadric(uvw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least squares w = c0 + c1 u + c2 v + c3 u^2 + c4 u v + c5 v^2 over (N, 3) points;
    the coefficients and the residuals."""
    u, v, w = uvw[:, 0], uvw[:, 1], uvw[:, 2]
    A = np.stack([np.ones_like(u), u, v, u * u, u * v, v * v], axis=1)
    coef, *_ = np.linalg.lstsq(A, w, rcond=None)
    return coef, w - A @ coef


def sag_over_disc(coef: np.ndarray, radius_m: float) -> float:
    """The bending of the fitted quadric over a disc of ``radius_m``: the largest
    distance of its second-order part from its tangent plane at the centre, on the rim
    (|largest principal curvature term| r^2, from the 2x2 Hessian's eigenvalues)."""
    H = np.array([[coef[3], coef[4] / 2.0], [coef[4] / 2.0, coef[5]]])
    return float(np.max(np.abs(np.linalg.eigvalsh(H)))) * radius_m**2


def judge_disc(
    own: np.ndarray,
    others: np.ndarray,
    centre: np.ndarray,
    normal: np.ndarray,
    nominal: np.ndarray,
    face: str,
    spec: CupSpec,
) -> Contact | None:
    """The cup at ``centre`` facing ``normal`` (outward), judged on the object's points
    ``own`` and the other objects' ``others`` (all table frame, (N, 3)). ``nominal``: the
    approach's outward direction (up for the top, the face's axis for a side). None when
    too few points lie under the disc to judge it (no face there)."""
    R = _frame(normal)
    rel = (own - centre) @ R.T
    r = spec.radius_m
    # the points under the disc, within a slab deep enough for a bent face (at most
    # twice the cup's radius in front of or behind the centre)
    near = (rel[:, 0] ** 2 + rel[:, 1] ** 2 <= r * r) & (np.abs(rel[:, 2]) <= 2.0 * r)
    pts = rel[near]
    if len(pts) < 12:
        return None
    coef, resid = fit_quadric(pts)
    # the fitted surface's own normal at the centre (gradient of w at u = v = 0)
    n_local = np.array([-coef[1], -coef[2], 1.0])
    n_local /= np.linalg.norm(n_local)
    n_table = n_local @ R
    point = centre + float(coef[0]) * R[2]
    tilt = math.degrees(math.acos(float(np.clip(n_table @ nominal, -1.0, 1.0))))
    sag = sag_over_disc(coef, r)
    spread = float(np.percentile(np.abs(resid), 90))
    # coverage: each disc sample's nearest point of the object, across the normal
    samples = disc_samples(r, spec.gap_m / 2.0)
    d2 = ((samples[:, None, :] - pts[None, :, :2]) ** 2).sum(axis=2)
    nearest = np.sqrt(d2.min(axis=1))
    covered = float(np.mean(nearest <= spec.gap_m))
    worst_gap = float(nearest.max())
    # other objects inside the disc, within the bellows' stroke of the surface (farther in
    # front of it they are in the way of the approach, not in the seal: blockers)
    n_others = 0
    if len(others):
        orel = (others - point) @ R.T
        inside = (orel[:, 0] ** 2 + orel[:, 1] ** 2 <= r * r) & (np.abs(orel[:, 2]) <= spec.compliance_m)
        n_others = int(inside.sum())
    tests = (
        (1.0 - worst_gap / spec.gap_m, f"a hole or an edge under the cup (a gap of {1000 * worst_gap:.1f} mm)"),
        (1.0 - sag / spec.compliance_m, f"the {face} is curved (it bends {1000 * sag:.1f} mm under the cup)"),
        (
            1.0 - spread / (0.6 * spec.compliance_m),
            f"the {face} is rough (points spread {1000 * spread:.1f} mm about it)",
        ),
        (1.0 - tilt / spec.max_tilt_deg, f"the {face} is tilted {tilt:.0f} deg from the approach"),
        (-1.0 if n_others else 1.0, f"another object lies under the cup ({n_others} points)"),
    )
    margin = min(m for m, _ in tests)
    why = next((w for m, w in tests if m <= 0), "")
    return Contact(
        face=face,
        point=point,
        normal=n_table,
        covered=covered,
        sag_m=sag,
        spread_m=spread,
        tilt_deg=tilt,
        others=n_others,
        seal_margin=float(margin),
        why=why,
    )


def load_margin(contact: Contact, mass_kg: float, com_table: np.ndarray, spec: CupSpec) -> tuple[float, str]:
    """1 - the load's utilisation of the cup, and why it fails ("" when it holds)."""
    W = mass_kg * GRAVITY_M_S2
    up = float(np.clip(contact.normal @ UP, -1.0, 1.0))
    tension = W * max(up, 0.0)  # the weight pulls the face off the cup
    shear = W * math.sqrt(max(1.0 - up * up, 0.0))  # ...or slides it along the lip
    arm = com_table - contact.point
    moment = W * float(np.hypot(arm[0], arm[1]))  # |arm x gravity| / |gravity| * W
    F = spec.holding_force_n
    use = spec.safety_factor * (tension / F + shear / (spec.lip_friction * F) + moment / (F * spec.radius_m))
    margin = 1.0 - use
    if margin > 0:
        return margin, ""
    parts = []
    if tension > 0.05 * W:
        parts.append(f"pull {tension:.1f} N")
    if shear > 0.05 * W:
        parts.append(f"shear {shear:.1f} N")
    parts.append(f"moment {moment:.2f} N m")
    return margin, (
        f"too heavy for the cup: ~{mass_kg:.2f} kg ({', '.join(parts)}) against {F:.0f} N "
        f"with a safety factor of {spec.safety_factor:g}"
    )


def hull_volume_and_centroid(vertices: np.ndarray, faces: np.ndarray) -> tuple[float, np.ndarray]:
    """A closed, outward triangle mesh's volume and centre of volume (the divergence
    theorem over tetrahedra from the origin)."""
    a, b, c = vertices[faces[:, 0]], vertices[faces[:, 1]], vertices[faces[:, 2]]
    v6 = np.einsum("ij,ij->i", a, np.cross(b, c))
    vol6 = float(v6.sum())
    if vol6 <= 0:
        return 0.0, vertices.mean(axis=0)
    centroid = ((a + b + c) * v6[:, None]).sum(axis=0) / (4.0 * vol6)
    return vol6 / 6.0, centroid


def _grid(lo: np.ndarray, hi: np.ndarray, step: float) -> np.ndarray:
    """(K, 2) centres of a grid over the box lo..hi, centred so it is symmetric in it."""
    axes = []
    for a, b in zip(lo, hi):
        n = max(int(math.floor((b - a) / step)) + 1, 1)
        start = (a + b) / 2.0 - (n - 1) * step / 2.0
        axes.append(start + step * np.arange(n))
    gu, gv = np.meshgrid(*axes, indexing="ij")
    return np.stack([gu.ravel(), gv.ravel()], axis=1)


def candidate_faces(
    points: np.ndarray, axes2d: np.ndarray, top_height_m: float, spec: CupSpec, min_height_m: float
) -> list[tuple[str, np.ndarray, np.ndarray, np.ndarray]]:
    """(face, centre, normal guess, nominal direction) for each candidate: a grid of
    centres a cup's radius apart over the top, seen from above, and over each seen side
    across the footprint's axes (centres at least ``min_height_m`` above the table: the
    cup's rim must clear it)."""
    r = spec.radius_m
    step = r
    out: list[tuple[str, np.ndarray, np.ndarray, np.ndarray]] = []
    band = max(spec.compliance_m, 0.01)
    top = points[points[:, 2] >= top_height_m - band]
    if len(top):
        lo, hi = top[:, :2].min(axis=0) + r * 0.5, top[:, :2].max(axis=0) - r * 0.5
        if np.all(hi >= lo):
            for uv in _grid(lo, hi, step):
                centre = np.array([uv[0], uv[1], top_height_m])
                out.append(("top", centre, UP.copy(), UP.copy()))
    for axis in (axes2d[0], axes2d[1], -axes2d[0], -axes2d[1]):
        u = np.array([axis[0], axis[1], 0.0])
        u /= np.linalg.norm(u)
        depth = points @ u
        face = points[depth >= depth.max() - band]
        if len(face) < 12:
            continue
        across = np.array([-u[1], u[0], 0.0])
        s = face @ across
        z = face[:, 2]
        lo = np.array([s.min() + r * 0.5, max(z.min(), min_height_m)])
        hi = np.array([s.max() - r * 0.5, min(z.max(), top_height_m - r)])
        if np.any(hi < lo):
            continue
        d = float(np.median(depth[depth >= depth.max() - band]))
        for sv in _grid(lo, hi, step):
            centre = d * u + sv[0] * across + np.array([0.0, 0.0, sv[1]])
            out.append(("side", centre, u.copy(), u.copy()))
    return out


def judge_object(
    own: np.ndarray,
    others: np.ndarray,
    axes2d: np.ndarray,
    top_height_m: float,
    mass_kg: float,
    com_table: np.ndarray,
    spec: CupSpec,
    min_height_m: float,
) -> Judged:
    """Every candidate contact of one object, judged; the best by its margin (seal and
    load), the first in grid order on a tie."""
    contacts = []
    for face, centre, guess, nominal in candidate_faces(own, axes2d, top_height_m, spec, min_height_m):
        c = judge_disc(own, others, centre, guess, nominal, face, spec)
        if c is None:
            continue
        if c.seal_margin > 0:
            lm, why = load_margin(c, mass_kg, com_table, spec)
            c = dataclasses.replace(c, load_margin=lm, load_why=why)
        contacts.append(c)
    kept = [c for c in contacts if c.margin > 0]
    best = max(kept, key=lambda c: c.margin) if kept else None
    return Judged(tuple(contacts), best)
