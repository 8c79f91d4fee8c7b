"""Identity over time and execution monitoring: pure functions over small frozen values.

The thesis replans on every fresh frame and names objects o0..oN-1 anew each time, so
"the object pushed last frame" means nothing to it (its section 7.2). Here each segmented
object becomes an `Observation` (centroid and sorted box sizes, sensor frame, metres),
and `update` matches observations to the `Track`s of earlier frames with the Hungarian
method on a cost of centroid distance plus size difference, gated so that an object that
jumped further than any action could move it gets a new id instead of a wrong old one.

The previous frame's first action tells where an object should have gone: a pushed
object (and anything in its swept path) is predicted anywhere on the segment from where
it was to where the full push would put it, since a real push may stop short at a
contact. `check_execution` then says whether that action did what it should.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from clearcli.settings.replay import TrackingParams  # [tracking]: defaults and ranges

Vec3 = tuple[float, float, float]


def vec3(values: Iterable[float]) -> Vec3:
    """A hashable (x, y, z) of plain floats from any 3-vector."""
    x, y, z = (float(v) for v in values)
    return (x, y, z)


def shape_signature(extents_m: Iterable[float]) -> Vec3:
    """Box sizes sorted largest first: independent of which axis PCA calls first, so an
    object that turned while it was pushed keeps its signature."""
    a, b, c = sorted((float(v) for v in extents_m), reverse=True)
    return (a, b, c)


@dataclass(frozen=True)
class Observation:
    """One object as segmented in one frame (sensor frame, metres)."""

    centroid: Vec3
    extents_m: Vec3  # shape_signature of the object's box
    name: str = ""  # its name in this frame's state (o0..), "" when there is no state


@dataclass(frozen=True)
class Track:
    """An object as remembered across frames."""

    track_id: int
    centroid: Vec3
    extents_m: Vec3
    last_seen: int  # frame index of the last observation
    first_seen: int


@dataclass(frozen=True)
class ExpectedEffect:
    """What the first action of the previous frame's plan should do to the world."""

    kind: str  # "grasp" | "push"
    track_id: int
    start_centroid: Vec3
    action: str = ""  # for reports, with the track id: "(push #3 dir1)"
    unit_vector: Vec3 | None = None  # push direction on the table, sensor frame
    push_length_m: float = 0.0
    extents_m: Vec3 = (0.0, 0.0, 0.0)  # the pushed object's box, for its swept path
    grasp_kind: str = "pinch"  # a grasp's kind (clearcli/predicates/grasps)
    grasp_face: str = ""  # the face it took the object by, for a kind with faces ("top", "side")


@dataclass(frozen=True)
class TrackerState:
    tracks: tuple[Track, ...] = ()
    next_id: int = 0


@dataclass(frozen=True)
class Assignment:
    """Result of one `update`: which track each observation became."""

    ids: tuple[int, ...]  # track id per observation, in observation order
    new: tuple[int, ...]  # ids created in this frame
    gone: tuple[int, ...]  # ids seen in the previous frame and not in this one
    costs: tuple[float, ...] = field(default=())  # match cost per observation (0 for new)

    def id_of(self, index: int) -> int:
        return self.ids[index]


@dataclass(frozen=True)
class ExecutionReport:
    """Whether the previous first action did what it should."""

    action: str
    track_id: int
    outcome: str  # "done" | "failed"
    detail: str
    moved_along_m: float | None = None
    moved_across_m: float | None = None
    # a failed grasp: how far its object is from where it was (m); not in the JSON
    moved_m: float | None = None


def _point_segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N,) distances from points (N, 3) to the segment a-b."""
    ab = b - a
    denom = float(ab @ ab)
    if denom <= 1e-12:
        return np.linalg.norm(points - a, axis=1)
    t = np.clip((points - a) @ ab / denom, 0.0, 1.0)
    return np.linalg.norm(points - (a + t[:, None] * ab), axis=1)


def predicted_segments(tracks: Sequence[Track], effect: ExpectedEffect | None) -> tuple[np.ndarray, np.ndarray]:
    """Per track, the segment (start, end) where it is expected now, (T, 3) each.

    Unmoved tracks get a zero-length segment at their centroid. With a push, the pushed
    track and every track whose centroid lies in the pushed object's swept path get the
    segment of the push: it may have shoved them along (the world's contacts).
    """
    start = np.array([t.centroid for t in tracks], dtype=float).reshape(-1, 3)
    end = start.copy()
    if effect is None or effect.kind != "push" or effect.unit_vector is None or not len(tracks):
        return start, end
    u = np.asarray(effect.unit_vector, dtype=float)
    travel = u * float(effect.push_length_m)
    a = np.asarray(effect.start_centroid, dtype=float)
    sizes = np.array([t.extents_m for t in tracks], dtype=float)
    own_half = 0.5 * max(effect.extents_m)
    # a neighbour is in the way when its centre is within both half-sizes of the path
    reach = own_half + 0.5 * sizes[:, 0]
    in_path = _point_segment_distance(start, a, a + travel) < reach
    for k, t in enumerate(tracks):
        if t.track_id == effect.track_id or in_path[k]:
            end[k] = start[k] + travel
    return start, end


def cost_matrix(
    tracks: Sequence[Track],
    observations: Sequence[Observation],
    effect: ExpectedEffect | None,
    params: TrackingParams,
) -> np.ndarray:
    """(T, O) matching costs in metres; np.inf where the gate forbids a match."""
    n_t, n_o = len(tracks), len(observations)
    if n_t == 0 or n_o == 0:
        return np.full((n_t, n_o), np.inf)
    obs_c = np.array([o.centroid for o in observations], dtype=float)
    obs_e = np.array([o.extents_m for o in observations], dtype=float)
    trk_e = np.array([t.extents_m for t in tracks], dtype=float)
    start, end = predicted_segments(tracks, effect)
    pos = np.empty((n_t, n_o))
    gate = np.full(n_t, params.gate_m)
    for k in range(n_t):
        pos[k] = _point_segment_distance(obs_c, start[k], end[k])
        if not np.allclose(start[k], end[k]):
            gate[k] += params.push_slack_m
    shape = np.linalg.norm(trk_e[:, None, :] - obs_e[None, :, :], axis=2)
    cost = pos + params.shape_weight * shape
    if effect is not None and effect.kind == "grasp":
        for k, t in enumerate(tracks):
            if t.track_id == effect.track_id:
                cost[k] += params.grasped_penalty_m
    cost[cost > gate[:, None]] = np.inf
    return cost


def update(
    state: TrackerState,
    observations: Sequence[Observation],
    frame_index: int,
    effect: ExpectedEffect | None = None,
    params: TrackingParams = TrackingParams(),
) -> tuple[TrackerState, Assignment]:
    """Match this frame's observations to the remembered tracks; new ids for the rest."""
    from scipy.optimize import linear_sum_assignment

    tracks = state.tracks
    cost = cost_matrix(tracks, observations, effect, params)
    ids: list[int | None] = [None] * len(observations)
    costs = [0.0] * len(observations)
    if cost.size and np.isfinite(cost).any():
        # a big finite stand-in for inf: the solver needs a finite matrix, and any pair
        # it picks at that cost is dropped below
        big = 1e6
        rows, cols = linear_sum_assignment(np.where(np.isfinite(cost), cost, big))
        for r, c in zip(rows, cols):
            if np.isfinite(cost[r, c]):
                ids[c] = tracks[r].track_id
                costs[c] = float(cost[r, c])
    _rematch(tracks, observations, ids, costs, params)
    next_id = state.next_id
    new: list[int] = []
    assigned: list[int] = []  # ids, a new one for each observation no track took
    for given in ids:
        if given is None:
            given = next_id
            new.append(next_id)
            next_id += 1
        assigned.append(given)
    seen = {int(i) for i in assigned}
    by_id = {t.track_id: t for t in tracks}
    kept: list[Track] = []
    for i, obs in enumerate(observations):
        tid = int(assigned[i])
        old = by_id.get(tid)
        kept.append(
            Track(
                track_id=tid,
                centroid=obs.centroid,
                extents_m=obs.extents_m,
                last_seen=frame_index,
                first_seen=old.first_seen if old else frame_index,
            )
        )
    previous_frame = max((t.last_seen for t in tracks), default=None)
    gone = tuple(sorted(t.track_id for t in tracks if t.track_id not in seen and t.last_seen == previous_frame))
    for t in tracks:
        if t.track_id not in seen and frame_index - t.last_seen <= params.max_missing_frames:
            kept.append(t)
    kept.sort(key=lambda t: t.track_id)
    assignment = Assignment(
        ids=tuple(int(i) for i in assigned),
        new=tuple(new),
        gone=gone,
        costs=tuple(costs),
    )
    return TrackerState(tracks=tuple(kept), next_id=next_id), assignment


def _rematch(
    tracks: Sequence[Track],
    observations: Sequence[Observation],
    ids: list[int | None],
    costs: list[float],
    params: TrackingParams,
) -> None:
    """Match leftover observations to leftover tracks of the latest frame that moved
    further than the gate but kept their size (in place: fills ``ids`` and ``costs``)."""
    from scipy.optimize import linear_sum_assignment

    taken = {i for i in ids if i is not None}
    latest = max((t.last_seen for t in tracks), default=None)
    free_t = [t for t in tracks if t.track_id not in taken and t.last_seen == latest]
    free_o = [k for k, i in enumerate(ids) if i is None]
    if not free_t or not free_o:
        return
    tc = np.array([t.centroid for t in free_t], dtype=float)
    te = np.array([t.extents_m for t in free_t], dtype=float)
    oc = np.array([observations[k].centroid for k in free_o], dtype=float)
    oe = np.array([observations[k].extents_m for k in free_o], dtype=float)
    dist = np.linalg.norm(tc[:, None, :] - oc[None, :, :], axis=2)
    shape = np.abs(te[:, None, :] - oe[None, :, :]).max(axis=2)
    allowed = (dist <= params.rematch_distance_m) & (shape <= params.rematch_shape_m)
    if not allowed.any():
        return
    rows, cols = linear_sum_assignment(np.where(allowed, dist, 1e6))
    for r, c in zip(rows, cols):
        if allowed[r, c]:
            ids[free_o[c]] = free_t[r].track_id
            costs[free_o[c]] = float(dist[r, c])


def check_execution(
    effect: ExpectedEffect,
    observations: Sequence[Observation],
    assignment: Assignment,
    params: TrackingParams = TrackingParams(),
) -> ExecutionReport:
    """Did the previous first action happen? A grasp: its object is gone. A push: its
    object moved along the push direction by a meaningful part of the push length."""
    index = next((i for i, tid in enumerate(assignment.ids) if tid == effect.track_id), None)
    if effect.kind == "grasp":
        if index is None:
            return ExecutionReport(effect.action, effect.track_id, "done", "object gone from the table")
        moved = float(np.linalg.norm(np.subtract(observations[index].centroid, effect.start_centroid)))
        return ExecutionReport(
            effect.action,
            effect.track_id,
            "failed",
            f"object still on the table ({moved:.3f} m from where it was)",
            moved_m=moved,
        )
    if index is None:
        return ExecutionReport(
            effect.action, effect.track_id, "failed", "pushed object not found afterwards (fell or lost)"
        )
    u = np.asarray(effect.unit_vector if effect.unit_vector is not None else (0.0, 0.0, 0.0))
    delta = np.subtract(observations[index].centroid, effect.start_centroid)
    along = float(delta @ u)
    across = float(np.linalg.norm(delta - along * u))
    needed = params.push_done_fraction * effect.push_length_m
    if along >= needed:
        return ExecutionReport(
            effect.action,
            effect.track_id,
            "done",
            f"moved {along:.3f} m along the push (planned {effect.push_length_m:.3f} m)",
            along,
            across,
        )
    return ExecutionReport(
        effect.action,
        effect.track_id,
        "failed",
        f"moved only {along:.3f} m along the push (needed {needed:.3f} m of {effect.push_length_m:.3f} m)",
        along,
        across,
    )
