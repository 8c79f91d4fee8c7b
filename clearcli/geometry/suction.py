"""A suction cup's contact on an object, judged from the object's own points (table frame).

Where a cup can seal (`judge_object`): every place on the faces the camera saw, from
above (the top) and from the side (the faces across the object's footprint axes). A face
is a height map: the object's points binned in cells ``gap_m`` across, in the face's own
frame (two directions along it, one out of it), each cell the mean of its points.
The cup's disc over a cell is judged on the cells under it, for every cell of the face at
once (one matrix product: the disc's cells sit at the same offsets everywhere):

* **covered**: no two neighbouring cells under the disc (within 95 % of its radius: the
  lip may overhang an edge by its own width) without a point: no hole and no edge wider
  than a cell (a lone empty cell is a pixel the sensor missed: filled from its
  neighbours);
* **alone**: no cell under the disc holds another object's outermost point within the
  bellows' stroke of the face (the cup would seal on two objects, or on none; farther
  out, the other object is in the approach's way: a blocker, not a leak);
* **flat**: a quadric w = f(u, v) fitted to the cells; its bending over the disc (the
  largest sag of its second-order part below the tangent plane) and the cells' spread
  about it (the 90th percentile of |residual|) within the bellows' compliance and 0.6 of
  it. A quadric, not a plane: its bending is what a curved face has and sensor noise has
  not (noise averages out of a least-squares fit over ~50 cells), so a cylinder of radius
  2 cm under a 30 mm cup (sag 6.8 mm) is told from a flat face seen by a Kinect (noise
  ~1.5 mm); the spread catches ribs and grooves deeper than the lip can follow;
* **facing**: the fitted normal within ``max_tilt_deg`` of the face's direction (straight
  up for the top, horizontal for a side).

The load (`load_margins`): the object's weight from its modelled volume and a density,
held against the cup's force with a safety factor: the pull along the cup's axis against
the holding force, the pull across it against the friction of the lip, and the moment of
the weight about the contact (the centre of mass off the cup's axis peels the lip)
against the holding force at the cup's radius. One utilisation, summed linearly (each
term uses up a share of the same seal): 1 - utilisation is the load's margin.

A place's margin is the smallest of its seal margins and its load margin; the best place
is kept, the first in the face's cell order on a tie. Margins, not booleans: a place
within rounding of a limit is never preferred to one well inside it.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass

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
    gap_m: float = 0.004  # the height maps' cell: an empty cell under the cup is a hole

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


@dataclass(frozen=True, eq=False)
class Judged:
    """One object's places: the best (None: none seals and holds), the closest to it
    (the best, or the one that came nearest: its reason), and up to 8 kept places, best
    first (the kind picks the least blocked of them)."""

    closest: Contact | None = None
    best: Contact | None = None
    n_kept: int = 0  # places that seal and hold
    # the kept places' order (best first, at most 8) and how to make one a Contact: built
    # when asked for (the kind usually needs the first only)
    order: tuple[int, ...] = ()
    make: Callable[[int], Contact] | None = None
    # the kept places' cup centres and outward normals, in ``order`` (each as its
    # `Contact` has it): what the kind checks the tool's volume at, none built
    points: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 3)))
    normals: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 3)))

    def iter_ranked(self) -> Iterator[Contact]:
        """The kept places, best first, each built as it is reached."""
        for k in self.order:
            assert self.make is not None
            yield self.make(k)

    @property
    def ranked(self) -> tuple[Contact, ...]:
        return tuple(self.iter_ranked())

    def why_not(self, spec: CupSpec) -> str:
        """Why no place is kept, from the one that came closest."""
        if self.best is not None:
            return ""
        if self.closest is None:
            return f"no face of {1000 * spec.diameter_m:.0f} mm seen (the object is smaller than the cup)"
        if self.closest.seal_margin <= 0:
            return f"no flat patch of {1000 * spec.diameter_m:.0f} mm: {self.closest.why}"
        return self.closest.load_why


PLACE_STRIDE = 2
MAX_POINTS = 8000


def disc_cells(radius_m: float, cell_m: float) -> np.ndarray:
    """(K, 2) integer offsets of the cells whose centres lie within 95 % of the disc's
    radius, the centre cell first."""
    n = int(math.floor(0.95 * radius_m / cell_m))
    g = np.arange(-n, n + 1)
    di, dj = np.meshgrid(g, g, indexing="ij")
    inside = (di * di + dj * dj) * cell_m * cell_m <= (0.95 * radius_m) ** 2
    offsets = np.stack([di[inside], dj[inside]], axis=1)
    order = np.lexsort((offsets[:, 1], offsets[:, 0], (offsets**2).sum(axis=1)))
    return offsets[order]


def disc_neighbours(offsets: np.ndarray) -> np.ndarray:
    """(K, 4) for each of the disc's cells the indices of its four neighbours among them
    (-1 where a neighbour lies outside the disc)."""
    where = {(int(a), int(b)): k for k, (a, b) in enumerate(offsets)}
    steps = ((1, 0), (-1, 0), (0, 1), (0, -1))
    return np.array([[where.get((int(a) + da, int(b) + db), -1) for da, db in steps] for a, b in offsets])


@dataclass(frozen=True, eq=False)
class Disc:
    """The cup's disc on a grid of cells: its cells' offsets, their neighbours among
    them, and the least squares of a quadric over them (the same for every place)."""

    offsets: np.ndarray  # (K, 2)
    neighbours: np.ndarray  # (K, 4)
    design: np.ndarray  # (K, 6)
    pinv: np.ndarray  # (6, K)

    @functools.cached_property
    def pad(self) -> int:
        """The height maps' margin: one cell beyond the disc's reach."""
        return int(np.abs(self.offsets).max()) + 1

    @functools.cached_property
    def steps(self) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
        """Per direction of `disc_neighbours` (in its order): the disc's cells whose
        neighbour that way lies in the disc, and those neighbours."""
        out = []
        for j in range(self.neighbours.shape[1]):
            k_in = np.flatnonzero(self.neighbours[:, j] >= 0)
            out.append((k_in, self.neighbours[k_in, j]))
        return tuple(out)


@functools.lru_cache(maxsize=16)
def disc(radius_m: float, cell_m: float) -> Disc:
    """The disc of a cup of ``radius_m`` on cells of ``cell_m``, built once per pair
    (every face of every object uses the same)."""
    offsets = disc_cells(radius_m, cell_m)
    A = quadric_design((offsets * cell_m).astype(float))
    return Disc(offsets, disc_neighbours(offsets), A, np.linalg.pinv(A))


def quadric_design(uv: np.ndarray) -> np.ndarray:
    """(K, 6) rows 1, u, v, u^2, u v, v^2."""
    u, v = uv[:, 0], uv[:, 1]
    return np.stack([np.ones_like(u), u, v, u * u, u * v, v * v], axis=1)


def sags(coef: np.ndarray, radius_m: float) -> np.ndarray:
    """(N,) the bending of each fitted quadric (rows of ``coef``) over a disc of
    ``radius_m``: its second-order part's largest |eigenvalue| times r^2."""
    a, b, c = coef[:, 3], coef[:, 4] / 2.0, coef[:, 5]
    mid, half = (a + c) / 2.0, np.sqrt(((a - c) / 2.0) ** 2 + b * b)
    return np.maximum(np.abs(mid + half), np.abs(mid - half)) * radius_m**2


@dataclass(frozen=True)
class FaceFrame:
    """A face's frame in the table frame: ``e1``, ``e2`` along it, ``n`` out of it."""

    name: str  # "top" or "side"
    e1: np.ndarray
    e2: np.ndarray
    n: np.ndarray

    @functools.cached_property
    def basis(self) -> np.ndarray:
        """(2, 3) e1 and e2."""
        return np.stack([self.e1, self.e2])


def bounds(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(3,) the smallest and largest coordinates of (n, 3) ``points``, per column: this
    NumPy's reduction along axis 0 of an (n, 3) array is ~15 times slower."""
    return (
        np.array([points[:, 0].min(), points[:, 1].min(), points[:, 2].min()]),
        np.array([points[:, 0].max(), points[:, 1].max(), points[:, 2].max()]),
    )


def in_box(points: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(n,) which of (n, 3) ``points`` lie in the box [lo, hi] (per column, as `bounds`)."""
    x, y, z = points[:, 0], points[:, 1], points[:, 2]
    return (x >= lo[0]) & (x <= hi[0]) & (y >= lo[1]) & (y <= hi[1]) & (z >= lo[2]) & (z <= hi[2])


def _outermost(keys: np.ndarray, values: np.ndarray, size: int) -> np.ndarray:
    """(size,) per key of ``0..size-1`` the largest of its values (-inf where none): one
    unbuffered maximum on the dense grid, no sort."""
    out = np.full(size, -np.inf)
    np.maximum.at(out, keys, values)
    return out


def _mean_per_key(keys: np.ndarray, values: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """The keys present (of ``0..size-1``, ascending) and, per key, the mean of its
    values (counted on the dense grid: no sort)."""
    n = np.bincount(keys, minlength=size)
    total = np.bincount(keys, weights=values, minlength=size)
    k = np.flatnonzero(n)
    return k, total[k] / n[k]


def _face_plane(height: np.ndarray, ij: np.ndarray, cell: float) -> np.ndarray:
    """(3,) w = a + b u + c v fitted to the height map's cells (``ij`` their indices),
    refitted on those within 5 mm of the first fit (the object's sides, seen edge-on,
    fall in the top's border cells lower than its face)."""
    A = np.column_stack([np.ones(len(ij)), (ij + 0.5) * cell])
    keep = np.ones(len(ij), dtype=bool)
    coef = np.zeros(3)
    for _ in range(2):
        if keep.sum() < 3:
            break
        coef = np.linalg.lstsq(A[keep], height[keep], rcond=None)[0]
        keep = np.abs(A @ coef - height) <= 0.005
    return coef


def _median(values: np.ndarray) -> float:
    """`np.median` of finite (n,) ``values``, bit for bit (the middle one, or the two
    middle ones' sum halved as its mean takes it), without its generic machinery's cost."""
    h = len(values) // 2
    if len(values) % 2:
        return float(np.partition(values, h)[h])
    part = np.partition(values, (h - 1, h))
    return float((part[h - 1] + part[h]) / 2.0)


def hidden_cells(
    height: np.ndarray,
    shape: np.ndarray,
    lo: np.ndarray,
    cell: float,
    frame: FaceFrame,
    hidden_by: np.ndarray,
    T_camera_table: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The empty cells of a face's height map (flat, ``shape``) that the camera cannot
    see because ``hidden_by`` (table-frame points of what stands on the object) lies in
    front of them, within the face's outline (covered cells on both sides along its row
    or its column); and the candidate cells' heights on the face's plane, to fill them
    with (NaN elsewhere).

    Seen from the camera: each candidate cell's point on the plane and the points in
    front are binned by direction (x/z, y/z of the camera frame) at 1.5 cells over the
    face's median range, the occluder's bins grown by one; a cell is hidden where an
    occluder's bin holds a point nearer the camera than the cell."""
    rows, cols = int(shape[0]), int(shape[1])
    grid = np.isfinite(height).reshape(rows, cols)
    r_idx, c_idx = np.arange(rows), np.arange(cols)
    big = rows + cols + 1
    row_lo = np.where(grid, c_idx[None, :], big).min(axis=1)
    row_hi = np.where(grid, c_idx[None, :], -1).max(axis=1)
    col_lo = np.where(grid, r_idx[:, None], big).min(axis=0)
    col_hi = np.where(grid, r_idx[:, None], -1).max(axis=0)
    # between covered cells along its row or along its column (what stands on the
    # object may hide the face from itself to the face's far edge: one way is bounded)
    inside = (
        ~grid
        & (
            ((c_idx[None, :] >= row_lo[:, None]) & (c_idx[None, :] <= row_hi[:, None]))
            | ((r_idx[:, None] >= col_lo[None, :]) & (r_idx[:, None] <= col_hi[None, :]))
        )
    ).ravel()
    plane = np.full(rows * cols, np.nan)  # filled where a cell is a candidate
    hidden = np.zeros(rows * cols, dtype=bool)
    cand = np.flatnonzero(inside)
    if not len(cand) or not len(hidden_by):
        return hidden, plane
    seen = np.flatnonzero(grid.ravel())
    coef = _face_plane(height[seen], np.stack(np.divmod(seen, cols), axis=1) + lo, cell)
    uv = (np.stack(np.divmod(cand, cols), axis=1) + lo + 0.5) * cell
    plane[cand] = coef[0] + uv @ coef[1:]
    P = uv[:, :1] * frame.e1 + uv[:, 1:2] * frame.e2 + plane[cand, None] * frame.n
    R, t = T_camera_table[:3, :3], T_camera_table[:3, 3]
    Pc = P @ R.T + t
    Qc = hidden_by @ R.T + t
    qz = Qc[:, 2]
    ahead = qz > 1e-6
    if not ahead.any() or not (Pc[:, 2] > 1e-6).all():
        return hidden, plane
    step = 1.5 * cell / _median(Pc[:, 2])
    pb = np.floor(Pc[:, :2] / Pc[:, 2:3] / step).astype(np.int64)
    # only the occluder's points whose bin is within one of a candidate's can hide it;
    # its bins per column on all its points (the same divisions, element by element, as
    # on those in front alone), the points behind the camera masked, not copied out
    p_lo = np.array([pb[:, 0].min(), pb[:, 1].min()]) - 1
    p_hi = np.array([pb[:, 0].max(), pb[:, 1].max()]) + 1
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        q0 = np.floor(Qc[:, 0] / qz / step)
        q1 = np.floor(Qc[:, 1] / qz / step)
        near = ahead & (q0 >= p_lo[0]) & (q0 <= p_hi[0]) & (q1 >= p_lo[1]) & (q1 <= p_hi[1])
    if not near.any():
        return hidden, plane
    qb = np.stack([q0[near], q1[near]], axis=1).astype(np.int64)
    qz = qz[near]
    # the bins on a dense grid over the candidates' bins and one around (the occluder's
    # kept points fall in it): the nearest point of each bin, then each candidate's
    # nearest over its bin and the eight around it (the occluder's bins grown by one)
    width = int(p_hi[1] - p_lo[1] + 3)
    rows = int(p_hi[0] - p_lo[0] + 3)
    nearest = np.full(rows * width, np.inf)
    np.minimum.at(nearest, (qb[:, 0] - p_lo[0] + 1) * width + (qb[:, 1] - p_lo[1] + 1), qz)
    pk = (pb[:, 0] - p_lo[0] + 1) * width + (pb[:, 1] - p_lo[1] + 1)
    grow = np.array([dr * width + dc for dr in (-1, 0, 1) for dc in (-1, 0, 1)])
    front = nearest[pk[None, :] + grow[:, None]].min(axis=0)
    hidden[cand[front < Pc[:, 2]]] = True
    return hidden, plane


@dataclass(frozen=True)
class FaceJob:
    """One face to judge (`judge_faces`): the object's points, the others' near it, the
    face's frame, the cup centre's e2 range, and what hides the face from the camera."""

    own: np.ndarray
    others: np.ndarray
    frame: FaceFrame
    e2_range: tuple[float, float] = (-math.inf, math.inf)
    hidden_by: np.ndarray | None = None
    T_camera_table: np.ndarray | None = None


_Grids = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def _in_frame(points: np.ndarray, frame: FaceFrame) -> tuple[np.ndarray, np.ndarray]:
    """(n, 2) u, v and (n,) w of table-frame ``points`` in a face's frame. The top's
    frame is the table's: its u, v, w are x, y, z, exactly what the products give."""
    if frame is TOP_FRAME:
        return points[:, :2], points[:, 2]
    return points @ frame.basis.T, points @ frame.n


def _grids(jobs: list[FaceJob], spec: CupSpec, d: Disc) -> _Grids | None:
    """Every face's height map, all binned at once (each face's cells are a block of
    one grid; each face's own points and the others' in its frame, by `_in_frame`): the
    heights (a cell's the mean of its points: the face at the cell's centre, the
    sensor's noise averaged; the outermost point would flatten a curved face by a
    cell's slope), the cells seen, the others' outermost point per cell, the places'
    windows (into the whole), their cell centres (u, v), and each face's count of
    places (None: no face has one). A place is every other cell (8 mm apart, on the grid
    of the face's frame itself, so a shifted object does not shift its places: a
    quarter of the work, and a cup of 30 mm loses nothing between them) whose centre's
    e2 lies in the job's range; where ``hidden_by`` hides the face (`hidden_cells`) its
    plane fills the cells, and they are places too."""
    cell = spec.gap_m
    pad = d.pad
    valid = [k for k, job in enumerate(jobs) if len(job.own) >= 3]
    if not valid:
        return None
    mine = [_in_frame(jobs[k].own, jobs[k].frame) for k in valid]
    n_pts = np.array([len(w) for _, w in mine])
    UV = np.concatenate([uv for uv, _ in mine])
    W = np.concatenate([w for _, w in mine])
    starts = np.r_[0, np.cumsum(n_pts)[:-1]]
    i0 = np.floor(UV[:, 0] / cell).astype(np.int64)
    i1 = np.floor(UV[:, 1] / cell).astype(np.int64)
    lo0 = np.minimum.reduceat(i0, starts) - pad
    lo1 = np.minimum.reduceat(i1, starts) - pad
    rows = np.maximum.reduceat(i0, starts) - lo0 + pad + 1
    cols = np.maximum.reduceat(i1, starts) - lo1 + pad + 1
    sizes = rows * cols
    base = np.r_[0, np.cumsum(sizes)]
    total = int(base[-1])
    # each face's key of a cell: its block's start, then row by row (integers: exact in
    # any order), per point by repeats, not gathers
    keys = i0 * np.repeat(cols, n_pts)
    keys += i1
    keys += np.repeat(base[:-1] - lo0 * cols - lo1, n_pts)
    # a cell's value: the mean of its points (each face's cells are its own keys)
    cells, tops = _mean_per_key(keys, W, total)
    height = np.full(total, np.nan)
    height[cells] = tops
    seen = np.zeros(total, dtype=bool)
    seen[cells] = True
    for v, k in enumerate(valid):
        job = jobs[k]
        if job.hidden_by is not None and job.T_camera_table is not None and len(job.hidden_by):
            block = height[base[v] : base[v + 1]]  # a view: the hidden cells are filled in place
            hidden, plane = hidden_cells(
                block,
                np.array([rows[v], cols[v]]),
                np.array([lo0[v], lo1[v]]),
                cell,
                job.frame,
                job.hidden_by,
                job.T_camera_table,
            )
            block[hidden] = plane[hidden]
    # the others' outermost point per cell of each face's grid (those within it)
    theirs = np.full(total, -np.inf)
    theirs_in = [_in_frame(jobs[k].others, jobs[k].frame) for k in valid if len(jobs[k].others)]
    if theirs_in:
        QUV = np.concatenate([uv for uv, _ in theirs_in])
        QW = np.concatenate([w for _, w in theirs_in])
        tid = np.repeat([v for v, k in enumerate(valid) if len(jobs[k].others)], [len(w) for _, w in theirs_in])
        o0 = np.floor(QUV[:, 0] / cell).astype(np.int64) - lo0[tid]
        o1 = np.floor(QUV[:, 1] / cell).astype(np.int64) - lo1[tid]
        inside = (o0 >= 0) & (o1 >= 0) & (o0 < rows[tid]) & (o1 < cols[tid])
        if inside.any():
            theirs = _outermost(base[tid[inside]] + o0[inside] * cols[tid[inside]] + o1[inside], QW[inside], total)
    cells = np.flatnonzero(np.isfinite(height))  # a hidden cell is a place too
    face = np.searchsorted(base, cells, side="right") - 1
    ci, cj = np.divmod(cells - base[face], cols[face])
    keep = ((ci + lo0[face]) % PLACE_STRIDE == 0) & ((cj + lo1[face]) % PLACE_STRIDE == 0)
    e2_lo = np.array([jobs[k].e2_range[0] for k in valid])
    e2_hi = np.array([jobs[k].e2_range[1] for k in valid])
    if np.isfinite(e2_lo).any() or np.isfinite(e2_hi).any():
        e2 = (cj + lo1[face] + 0.5) * cell  # the centre's e2, as centre_uv has it below
        keep &= (e2 >= e2_lo[face]) & (e2 <= e2_hi[face])
    keep = np.flatnonzero(keep)
    if not len(keep):
        return None
    ci, cj, face = ci[keep], cj[keep], face[keep]
    centre_uv = (np.stack([ci + lo0[face], cj + lo1[face]], axis=1) + 0.5) * cell
    offsets = d.offsets
    window = (
        (ci[:, None] + offsets[None, :, 0]) * cols[face][:, None]
        + (cj[:, None] + offsets[None, :, 1])
        + base[face][:, None]
    )
    n_places = np.zeros(len(jobs), dtype=np.int64)
    n_places[valid] = np.bincount(face, minlength=len(valid))
    return height, seen, theirs, window, centre_uv, n_places


def judge_face(
    own: np.ndarray,
    others: np.ndarray,
    frame: FaceFrame,
    spec: CupSpec,
    e2_range: tuple[float, float] = (-math.inf, math.inf),
    hidden_by: np.ndarray | None = None,
    T_camera_table: np.ndarray | None = None,
) -> FacePlaces | None:
    """Every place of one face: the cup centred on each cell of the object's height map
    in ``frame`` (``own``, ``others``: table-frame points), the cells whose centre's e2
    lies in ``e2_range`` (a side's heights the tool may take). Judged as the module
    says; the load is not judged here. Where ``hidden_by`` (what stands on the object,
    taken first) hides the face from the camera (``T_camera_table``), the face is taken
    to go on as its plane: those cells are neither holes nor edges (`hidden_cells`)."""
    return judge_faces([FaceJob(own, others, frame, e2_range, hidden_by, T_camera_table)], spec)[0]


def judge_faces(jobs: list[FaceJob], spec: CupSpec) -> list[FacePlaces | None]:
    """`judge_face` of many faces at once: the faces' height maps binned together
    (`_grids`), then every place of every face judged in one pass (the matrix products
    per face, as one face alone has them: a product's rounding depends on its rows'
    count)."""
    r = spec.radius_m
    d = disc(r, spec.gap_m)
    out: list[FacePlaces | None] = [None] * len(jobs)
    grids = _grids(jobs, spec, d)
    if grids is None:
        return out
    # the faces' height maps end to end, each face's windows into its own
    height, seen_all, theirs, window, centre_uv, n_places = grids
    live = [k for k in range(len(jobs)) if n_places[k] > 0]
    counts = [int(n_places[k]) for k in live]
    ends = np.cumsum([0] + counts)
    slices = [slice(int(a), int(b)) for a, b in zip(ends[:-1], ends[1:])]
    frames = [jobs[k].frame for k in live]
    E1 = np.repeat(np.array([f.e1 for f in frames]), counts, axis=0)
    E2 = np.repeat(np.array([f.e2 for f in frames]), counts, axis=0)
    EN = np.repeat(np.array([f.n for f in frames]), counts, axis=0)
    H: np.ndarray = height[window]  # (N, K)
    covered = np.isfinite(H)  # a point there, or hidden by what stands on the object
    share = covered.mean(axis=1)
    # a hole: an empty cell beside another empty one under the disc (a gap of two cells,
    # 8 mm: hole_gap_m's "twice this"); a lone empty cell is a pixel the sensor missed,
    # filled with the mean of its neighbours for the fit
    # per direction (one (N, K) gather each: an (N, K, 4) one and its reduction along the
    # last axis cost ~10 times more), each direction's cells only where that neighbour is
    # in the disc
    empty = ~covered
    gappy = np.flatnonzero(empty.any(axis=1))  # most places have no empty cell: only these
    hole_cells = np.zeros_like(empty)
    filled = H  # H is read no more below (the gappy rows' heights are copied out)
    if len(gappy):
        eg = empty[gappy]
        Hg = H[gappy]
        H0 = np.where(eg, 0.0, Hg)  # empty cells add 0
        nb_sum = np.zeros(eg.shape)
        nb_n = np.zeros(eg.shape)
        nb_any = np.zeros_like(eg)
        for k_in, nb_k in d.steps:  # the disc's cells with that neighbour, and it
            nb_any[:, k_in] |= eg[:, nb_k]
            # in the neighbours' order (sums of up to four heights, added in one order)
            nb_sum[:, k_in] += H0[:, nb_k]
            nb_n[:, k_in] += ~eg[:, nb_k]
        hole_cells[gappy] = eg & nb_any
        filled[gappy] = np.where(eg & (nb_n > 0), nb_sum / np.maximum(nb_n, 1), Hg)
    full = ~hole_cells.any(axis=1)
    covered_or_filled = np.isfinite(filled)
    A = d.design  # cell centres relative to the centre cell's
    pinv = d.pinv  # (6, K): the same least squares for every full window
    Hf = np.where(covered_or_filled, filled, 0.0)
    coef = np.empty((len(Hf), pinv.shape[0]))
    fitted = np.empty_like(Hf)
    for sl in slices:  # per face: see the docstring
        coef[sl] = Hf[sl] @ pinv.T
        fitted[sl] = coef[sl] @ A.T
    # the spread only over what the camera saw (a hidden cell sits on the plane)
    measured = seen_all[window]
    resid = Hf - fitted
    np.abs(resid, out=resid)
    resid *= measured  # |residual|, 0 where unseen (finite: times 0 is 0)
    # the 90th percentile by nearest rank (a partition, not a sort)
    rank = int(math.ceil(0.9 * resid.shape[1])) - 1
    resid.partition(rank, axis=1)
    spread = resid[:, rank]
    sag = sags(coef, r)
    grad = coef[:, 1:3]
    normal = EN - grad[:, :1] * E1 - grad[:, 1:2] * E2
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    along = np.empty(len(normal))
    slope = np.empty_like(Hf)
    for sl, f in zip(slices, frames):
        along[sl] = normal[sl] @ f.n
        slope[sl] = grad[sl] @ A[:, 1:3].T
    tilt = np.degrees(np.arccos(np.clip(along, -1.0, 1.0)))
    # another object under the disc: its outermost point within the bellows' stroke of
    # the fitted face (farther out it is in the way of the approach: a blocker)
    surface = coef[:, :1] + slope
    off = theirs[window]
    off -= surface
    np.abs(off, out=off)
    intruders = (off <= spec.compliance_m).sum(axis=1)
    gaps = empty.sum(axis=1)
    m_cover = np.where(full, 1.0, -np.maximum(hole_cells.sum(axis=1), 1) / covered.shape[1])
    m_sag = 1.0 - sag / spec.compliance_m
    m_spread = 1.0 - spread / (0.6 * spec.compliance_m)
    m_tilt = 1.0 - tilt / spec.max_tilt_deg
    m_alone = np.where(intruders > 0, -1.0, 1.0)
    margins = np.stack([m_cover, m_sag, m_spread, m_tilt, m_alone], axis=1)
    points = centre_uv[:, :1] * E1 + centre_uv[:, 1:2] * E2 + coef[:, :1] * EN
    for k, sl, f in zip(live, slices, frames):
        out[k] = FacePlaces(
            frame=f,
            points=points[sl],
            normals=normal[sl],
            covered=share[sl],
            empty=gaps[sl],
            full=full[sl],
            sag_m=sag[sl],
            spread_m=spread[sl],
            tilt_deg=tilt[sl],
            intruders=intruders[sl],
            margins=margins[sl],
            cell_m=spec.gap_m,
        )
    return out


@dataclass(frozen=True, eq=False)
class FacePlaces:
    """Every place of one face, judged (arrays, one row a place)."""

    frame: FaceFrame
    points: np.ndarray  # (N, 3) the disc's centre on the fitted face
    normals: np.ndarray  # (N, 3)
    covered: np.ndarray  # (N,) share of the disc's cells holding a point
    empty: np.ndarray  # (N,) how many are empty
    full: np.ndarray  # (N,) bool: none is
    sag_m: np.ndarray
    spread_m: np.ndarray
    tilt_deg: np.ndarray
    intruders: np.ndarray  # (N,) cells of another object within the stroke
    margins: np.ndarray  # (N, 5) cover, sag, spread, tilt, alone
    cell_m: float

    def __len__(self) -> int:
        return len(self.points)

    @functools.cached_property
    def seal(self) -> np.ndarray:
        """(N,) the smallest of each place's margins (once: it is asked for twice)."""
        return self.margins.min(axis=1)

    def contact(self, k: int, load: tuple[float, str] | None = None) -> Contact:
        """Place ``k`` as a `Contact`, with why it does not seal (and ``load``: its load
        margin and why it fails, `load_margin`, where judged)."""
        face, m = self.frame.name, self.margins[k]
        # the reason of the first test that fails, worded only for it (most places built
        # are the best, which seals)
        first = next((t for t, mk in enumerate(m.tolist()) if mk <= 0), None)
        whys = (
            lambda: (
                f"a hole or an edge under the cup ({self.empty[k]} of its cells of {1000 * self.cell_m:.0f} mm "
                "hold no point)"
            ),
            lambda: f"the {face} is curved (it bends {1000 * self.sag_m[k]:.1f} mm under the cup)",
            lambda: f"the {face} is rough (points spread {1000 * self.spread_m[k]:.1f} mm about it)",
            lambda: f"the {face} is tilted {self.tilt_deg[k]:.0f} deg from the approach",
            lambda: f"another object lies under the cup ({self.intruders[k]} cells)",
        )
        full = bool(self.full[k])
        return Contact(
            face=face,
            point=self.points[k],
            normal=self.normals[k],
            covered=float(self.covered[k]),
            sag_m=float(self.sag_m[k]) if full else math.nan,
            spread_m=float(self.spread_m[k]) if full else math.nan,
            tilt_deg=float(self.tilt_deg[k]) if full else math.nan,
            others=int(self.intruders[k]),
            seal_margin=float(m.min()),
            why=whys[first]() if first is not None else "",
            load_margin=math.nan if load is None else load[0],
            load_why="" if load is None else load[1],
        )


def _load(
    normals: np.ndarray, points: np.ndarray, mass_kg: float, com_table: np.ndarray, spec: CupSpec
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per place ((N, 3) outward normals and contact points): the weight's pull along
    the cup's axis, its shear along the lip, its moment about the contact, and the
    margin 1 - the cup's utilisation."""
    return _load_terms(normals @ UP, points, mass_kg * GRAVITY_M_S2, com_table[None, :], spec)


def _load_terms(
    up: np.ndarray, points: np.ndarray, W: float | np.ndarray, com: np.ndarray, spec: CupSpec
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """`_load` from each place's normal's upward part ``up``, the weight ``W`` (N) and
    the centre of mass ``com`` ((1, 3) or (N, 3)): elementwise, so many objects' places
    at once are each as alone."""
    up = np.clip(up, -1.0, 1.0)
    tension = W * np.maximum(up, 0.0)  # the weight pulls the face off the cup
    shear = W * np.sqrt(np.maximum(1.0 - up * up, 0.0))  # ...or slides it along the lip
    arm = com - points
    moment = W * np.hypot(arm[:, 0], arm[:, 1])  # |arm x gravity| / |gravity| * W
    F = spec.holding_force_n
    use = spec.safety_factor * (tension / F + shear / (spec.lip_friction * F) + moment / (F * spec.radius_m))
    return tension, shear, moment, 1.0 - use


def load_margins(places: FacePlaces, mass_kg: float, com_table: np.ndarray, spec: CupSpec) -> np.ndarray:
    """(N,) `load_margin` of every place at once."""
    return _load(places.normals, places.points, mass_kg, com_table, spec)[3]


def load_margin(contact: Contact, mass_kg: float, com_table: np.ndarray, spec: CupSpec) -> tuple[float, str]:
    """1 - the load's utilisation of the cup, and why it fails ("" when it holds)."""
    return load_margin_at(contact.normal, contact.point, mass_kg, com_table, spec)


def load_margin_at(
    normal: np.ndarray, point: np.ndarray, mass_kg: float, com_table: np.ndarray, spec: CupSpec
) -> tuple[float, str]:
    """`load_margin` of a contact at ``point`` with the outward ``normal``."""
    W = mass_kg * GRAVITY_M_S2
    F = spec.holding_force_n
    t, sh, mo, m = _load(normal[None, :], point[None, :], mass_kg, com_table, spec)
    tension, shear, moment, margin = float(t[0]), float(sh[0]), float(mo[0]), float(m[0])
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
    # b x c per column (np.cross's own products, without its ~20 us of set-up)
    bxc = np.stack(
        [
            b[:, 1] * c[:, 2] - b[:, 2] * c[:, 1],
            b[:, 2] * c[:, 0] - b[:, 0] * c[:, 2],
            b[:, 0] * c[:, 1] - b[:, 1] * c[:, 0],
        ],
        axis=1,
    )
    v6 = np.einsum("ij,ij->i", a, bxc)
    vol6 = float(v6.sum())
    if vol6 <= 0:
        return 0.0, vertices.mean(axis=0)
    centroid = ((a + b + c) * v6[:, None]).sum(axis=0) / (4.0 * vol6)
    return vol6 / 6.0, centroid


def volume_above(
    vertices: np.ndarray, faces: np.ndarray, footprint: np.ndarray, bottom_m: float
) -> tuple[float, np.ndarray]:
    """The volume and centre of an object's modelled solid above ``bottom_m``: the solid
    stands on the table (its footprint extruded down to z = 0), so for an object that
    stands on another the prism of its footprint below its bottom is the other's, not
    its own (a box's weight is not a stack's). Where the solid is narrower than its
    footprint low down (nothing would be left), the prism of its footprint from its
    bottom to its top stands for it."""
    volume, centre = hull_volume_and_centroid(vertices, faces)
    if bottom_m <= 0 or len(footprint) < 3 or volume <= 0:
        return volume, centre
    x, y = footprint[:, 0], footprint[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    area = float(cross.sum()) / 2.0
    if area <= 0:
        return volume, centre
    c_xy = np.array([((x + xn) * cross).sum(), ((y + yn) * cross).sum()]) / (6.0 * area)
    below = area * bottom_m
    if volume - below <= 0:
        top_m = float(vertices[:, 2].max())
        return area * max(top_m - bottom_m, 0.0), np.array([c_xy[0], c_xy[1], (top_m + bottom_m) / 2.0])
    c_below = np.array([c_xy[0], c_xy[1], bottom_m / 2.0])
    return volume - below, (centre * volume - c_below * below) / (volume - below)


TOP_FRAME = FaceFrame("top", np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), UP.copy())


def side_frames(axes2d: np.ndarray) -> Iterator[FaceFrame]:
    """The four sides across the footprint's axes (outward), each made as it is reached
    (the sides are seldom searched)."""
    for axis in (axes2d[0], axes2d[1], -axes2d[0], -axes2d[1]):
        u = np.array([axis[0], axis[1], 0.0])
        u /= np.linalg.norm(u)
        yield FaceFrame("side", np.array([-u[1], u[0], 0.0]), UP.copy(), u)


def face_frames(axes2d: np.ndarray) -> Iterator[FaceFrame]:
    """The top, then the four sides across the footprint's axes (outward)."""
    yield TOP_FRAME
    yield from side_frames(axes2d)


@dataclass(frozen=True)
class ObjectJob:
    """One object to judge (`judge_objects`; the arguments of `judge_object`)."""

    own: np.ndarray
    others: np.ndarray
    axes2d: np.ndarray
    top_height_m: float
    mass_kg: float
    com_table: np.ndarray
    min_height_m: float
    hidden_by: np.ndarray | None = None
    T_camera_table: np.ndarray | None = None
    skip: frozenset[str] = frozenset()
    # the caller kept of ``others`` those within the seal test's reach of ``own``'s box
    # already (`judge_objects` would keep them all again)
    others_near: bool = False


def judge_object(
    own: np.ndarray,
    others: np.ndarray,
    axes2d: np.ndarray,
    top_height_m: float,
    mass_kg: float,
    com_table: np.ndarray,
    spec: CupSpec,
    min_height_m: float,
    hidden_by: np.ndarray | None = None,
    T_camera_table: np.ndarray | None = None,
    skip: frozenset[str] = frozenset(),
) -> Judged:
    """Every place on the object's top, and on its sides where no place on the top seals,
    judged; the best by its margin (seal and load). A side's places keep the cup's centre ``min_height_m`` above the table
    (the tool clears it) and a cup's radius below the top. Each side is judged on the
    points facing its way (those within 1 cm of its outermost), the top on all, where
    ``hidden_by`` (what stands on the object) hides it taken as its plane (`judge_face`);
    the faces named in ``skip`` ("top", "side") are not judged."""
    job = ObjectJob(
        own, others, axes2d, top_height_m, mass_kg, com_table, min_height_m, hidden_by, T_camera_table, skip
    )
    return judge_objects([job], spec)[0]


def judge_objects(jobs: list[ObjectJob], spec: CupSpec) -> list[Judged]:
    """`judge_object` of many objects at once: every top in one pass of `judge_faces`,
    then the sides of those whose top seals nowhere in another."""
    band = max(spec.compliance_m, 0.01)
    owns, others_near = [], []
    for job in jobs:
        # at most MAX_POINTS of the object's points, every k-th (by index: a stride moves
        # with no rounding): ~2 a cell on a 0.3 x 0.2 m top, which a Kinect at 1 m sees with 5
        own, others = job.own[:: max(1, math.ceil(len(job.own) / MAX_POINTS))], job.others
        if len(own) and len(others) and not job.others_near:
            # only the others near the object can be under a cup on it
            reach = spec.radius_m + spec.compliance_m + band
            lo, hi = bounds(own)
            others = others[in_box(others, lo - reach, hi + reach)]
        owns.append(own)
        others_near.append(others)
    faces: list[list[FacePlaces]] = [[] for _ in jobs]
    tops = [k for k, job in enumerate(jobs) if "top" not in job.skip]  # skipped: tried, no seal
    judged = judge_faces(
        [
            FaceJob(
                owns[k], others_near[k], TOP_FRAME, (-math.inf, math.inf), jobs[k].hidden_by, jobs[k].T_camera_table
            )
            for k in tops
        ],
        spec,
    )
    for k, places in zip(tops, judged):
        if places is not None and len(places):
            faces[k].append(places)
    sides: list[tuple[int, FaceJob]] = []
    for k, job in enumerate(jobs):
        if "side" in job.skip:
            continue
        if faces[k] and bool((faces[k][0].seal > 0).any()):
            # the top seals somewhere: it is the surer grasp (the weight pulls along the
            # cup's axis, not across its lip), and the sides are not searched
            continue
        e2_range = (job.min_height_m, job.top_height_m - spec.radius_m)
        if e2_range[1] < e2_range[0]:
            continue
        own = owns[k]
        for frame in side_frames(job.axes2d):
            depth = own @ frame.n
            mine = own[depth >= depth.max() - band] if len(own) else own
            sides.append((k, FaceJob(mine, others_near[k], frame, e2_range)))
    for (k, _), places in zip(sides, judge_faces([fj for _, fj in sides], spec)):
        if places is not None and len(places):
            faces[k].append(places)
    # the load of every object's sealing places at once (elementwise: each place's as
    # alone), read by `_judged` only where the cup seals
    seals = [np.concatenate([f.seal for f in fs]) if fs else np.zeros(0) for fs in faces]
    sealed = [np.flatnonzero(seal > 0) for seal in seals]
    loads: list[np.ndarray | None] = [None] * len(jobs)
    n_sealed = [len(x) for x in sealed]
    if sum(n_sealed):
        per = [(fs, x, job) for fs, x, job in zip(faces, sealed, jobs) if len(x)]
        # each object's normals' upward part by its own product (as `_load` has it)
        up = np.concatenate([np.concatenate([f.normals for f in fs])[x] @ UP for fs, x, _ in per])
        points = np.concatenate([np.concatenate([f.points for f in fs])[x] for fs, x, _ in per])
        W = np.repeat([job.mass_kg * GRAVITY_M_S2 for job in jobs], n_sealed)
        com = np.repeat(np.array([job.com_table for job in jobs], dtype=float).reshape(-1, 3), n_sealed, axis=0)
        margins = _load_terms(up, points, W, com, spec)[3]
        cuts = np.cumsum([0, *n_sealed])
        for k, x in enumerate(sealed):
            load = np.full(len(seals[k]), np.nan)
            load[x] = margins[cuts[k] : cuts[k + 1]]
            loads[k] = load
    return [_judged(faces[k], job.mass_kg, job.com_table, spec, (seals[k], loads[k])) for k, job in enumerate(jobs)]


def _judged(
    faces: list[FacePlaces],
    mass_kg: float,
    com_table: np.ndarray,
    spec: CupSpec,
    seal_load: tuple[np.ndarray, np.ndarray | None] | None = None,
) -> Judged:
    """One object's judged faces' places, ranked by their margins (seal and load;
    ``seal_load``: both, judged by the caller, the load NaN where the cup does not seal
    and None where it seals nowhere)."""
    if not faces:
        return Judged()
    if seal_load is not None:
        seal, given = seal_load
        load = given if given is not None else np.full(len(seal), np.nan)
    else:
        seal = np.concatenate([f.seal for f in faces])
        # the load only where the cup seals (it is read nowhere else): each place's on its own
        load = np.full(len(seal), np.nan)
        sealed = np.flatnonzero(seal > 0)
        if len(sealed):
            normals = np.concatenate([f.normals for f in faces])[sealed]
            points = np.concatenate([f.points for f in faces])[sealed]
            load[sealed] = _load(normals, points, mass_kg, com_table, spec)[3]
    margin = np.where(seal > 0, np.minimum(seal, load), seal)
    which = np.concatenate([np.full(len(f), i) for i, f in enumerate(faces)])
    index = np.concatenate([np.arange(len(f)) for f in faces])

    def contact(k: int) -> Contact:
        f, j = faces[int(which[k])], int(index[k])
        if seal[k] > 0:
            return f.contact(j, load_margin_at(f.normals[j], f.points[j], mass_kg, com_table, spec))
        return f.contact(j)

    built: dict[int, Contact] = {}

    def once(k: int) -> Contact:
        if k not in built:
            built[k] = contact(k)
        return built[k]

    k_best = int(np.argmax(margin))  # the first of the best on a tie
    best = once(k_best) if margin[k_best] > 0 else None
    # none kept, but some seal: the closest is the sealing place the load comes nearest
    # at, so the reason is the weight, not a hole elsewhere whose margin ran smaller
    k_close = k_best if best is not None or not (seal > 0).any() else int(np.argmax(np.where(seal > 0, load, -np.inf)))
    order = [int(k) for k in np.argsort(-margin, kind="stable")[:8] if margin[k] > 0]
    return Judged(
        closest=once(k_close),
        best=best,
        n_kept=int((margin > 0).sum()),
        order=tuple(order),
        make=once,
        points=np.array([faces[int(which[k])].points[int(index[k])] for k in order]).reshape(-1, 3),
        normals=np.array([faces[int(which[k])].normals[int(index[k])] for k in order]).reshape(-1, 3),
    )
