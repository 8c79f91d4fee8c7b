"""Grasp and push poses of one object (thesis 4.3), in the table frame.

Gripper frame as in `clearcli.geometry.gripper`: closing point at the origin, approach
+z, closing direction x. A pose is ``T_table_gripper`` (4x4). The gripper is symmetric
under a half-turn about its approach axis, so every pose has two candidates (x, y) and
(-x, -y); the IK check may pick either.

Grasp: the closing direction is across the footprint's narrowest width (the thesis: across
the first principal direction; for a nearly square footprint that can be its diagonal),
with the other yaw (a quarter turn) as an alternative when that side fits the opening,
and (``offcentre_fraction``) the centred grasp moved towards either end of the object;
pushes carry the other gripper yaw as an alternative too, and the predicates stage keeps,
per action, the yaw the neighbours block least. The approach
follows the top surface's third principal axis pointing into the table (straight down for
an object lying flat, or when that axis tilts more than ``max_grasp_tilt_deg``); the
closing point is the top-surface centroid moved along the approach by half the
closing-region height, raised where needed so that the fingertips stay
``fingertips_above_table_m`` above the table. Pre-grasp: ``approach_m`` back along the
approach; lift: ``approach_m`` straight up from the grasp.

Push directions: dir1 = +first principal direction (sign rule in
`clearcli.geometry.models._fix_sign`: away from the camera), dir2 = -dir1,
dir3 = dir1 turned +90 deg about the table normal, dir4 = -dir3.
Push pose (thesis 4.3.1, Fig. 4.12): approach straight down; closing direction parallel to
the push for dir1/dir2 (the narrow side of the closed finger pair leads, so the gripper
does not also push a neighbour beside a long object), orthogonal for dir3/dir4; fingertips
``fingertips_above_table_m`` above the table; the fingers ``gripper_behind_m`` behind the
object's rear face along the push, centred on the object across it. Alternatives: the
other yaw, and (``lateral_shift``) the contact moved towards either end of the rear face,
``contact_edge_margin_m`` short of it: beside a tall neighbour the wrist may clear it
there; and the same push with the contact raised (``raised_fingertips_m``, where the
object stays upright, `raised_contact_lifts`): beside a tall neighbour the arm's wrist
clears it only then. Pre-push: ``approach_m`` above the push pose. Push length: ``pushing_step`` times the object's extent
along the direction, at most ``push_length_limit_m``; the gripper path is cut into steps of
at most ``path_resolution_m``; retreat: ``approach_m`` above the end.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from clearcli.geometry.gripper import GripperModel
from clearcli.geometry.models import ObjectGeometry
from clearcli.settings.geometry import PushSettings
from clearcli.transforms import cross3

DIRECTION_NAMES: tuple[str, ...] = ("dir1", "dir2", "dir3", "dir4")
UP = np.array([0.0, 0.0, 1.0])
# a raised push contact must still meet this much of the object's rear face (m)
MIN_CONTACT_BAND_M = 0.015


def _pose(x: np.ndarray, z: np.ndarray, origin: np.ndarray) -> np.ndarray:
    y = cross3(z, x)
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = x, y, z, origin
    return T


def _half_turns(x: np.ndarray, z: np.ndarray, origin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return _pose(x, z, origin), _pose(-x, z, origin)


def _moved(T: np.ndarray, offset: np.ndarray) -> np.ndarray:
    out = T.copy()
    out[:3, 3] = out[:3, 3] + offset
    return out


@dataclass(frozen=True, eq=False)
class GraspGeometry:
    candidates: tuple[tuple[np.ndarray, ...], ...]  # per half-turn: pre-grasp, grasp, lift
    closing_dir: np.ndarray  # (3,) x of the first candidate
    approach: np.ndarray  # (3,)
    width_m: float  # the object's size across the closing direction
    # The same grasp with the gripper turned a quarter turn about its approach (closing
    # across the other side of the footprint), when that side fits the opening; the
    # predicates stage keeps whichever of the two the neighbours block least.
    alternatives: tuple[GraspGeometry, ...] = ()

    @property
    def T_grasp(self) -> np.ndarray:
        return self.candidates[0][1]


@dataclass(frozen=True, eq=False)
class PushGeometry:
    direction: str
    unit: np.ndarray  # (3,) on the table
    length_m: float
    object_translations: np.ndarray  # (n, 3) along the path, the last is the end
    candidates: tuple[tuple[np.ndarray, ...], ...]  # per half-turn: pre, start, ..., end, retreat
    # The same push with the gripper turned a quarter turn about the vertical (closing
    # direction across the push instead of along it, or the reverse): the base box is
    # 0.11 m one way and 0.06 m the other, so beside a tall neighbour one yaw often
    # fits where the other does not. The predicates stage keeps the one the neighbours
    # block least.
    alternatives: tuple[PushGeometry, ...] = ()

    @property
    def T_start(self) -> np.ndarray:
        return self.candidates[0][1]


def grasp_geometry(
    obj: ObjectGeometry,
    gripper: GripperModel,
    push: PushSettings,
    max_tilt_deg: float,
    offcentre_fraction: float = 0.0,
) -> GraspGeometry:
    half = gripper.settings.closing_region_height_m / 2.0
    tilt = math.degrees(math.acos(float(np.clip(obj.top_normal @ UP, -1.0, 1.0))))
    approach = -obj.top_normal if tilt <= max_tilt_deg else -UP
    point = obj.top_centroid + half * approach
    tip_height = float((point + half * approach)[2])
    if tip_height < push.fingertips_above_table_m:
        # raise it back along the approach until the fingertips clear the table
        point = point - approach * (push.fingertips_above_table_m - tip_height) / (-approach[2])
    # Close across the footprint's narrowest width (rotating calipers), not across the
    # first principal direction: for a nearly square footprint, or a box seen corner on,
    # the principal directions point anywhere and the width across them can be 40 % too
    # large (a 5.9 x 6.3 cm box measured 8.2 cm wide, "too wide for the gripper").
    across2 = min_width_direction(obj.footprint)
    grasps = []
    for turn in (0, 1):
        d2 = across2 if turn == 0 else np.array([-across2[1], across2[0]])
        x3 = np.array([d2[0], d2[1], 0.0])
        x = x3 - float(x3 @ approach) * approach  # orthogonal to a tilted approach
        x = x / np.linalg.norm(x)
        # the object's width across the closing direction, measured on the footprint: a
        # tilted approach must not add the object's height to it
        width = float(np.ptp(obj.footprint @ d2))
        if turn == 1 and width > gripper.settings.opening_width_m:
            break  # the other side does not fit: no alternative
        cands = []
        for T in _half_turns(x, approach, point):
            pre = _moved(T, -push.approach_m * approach)
            lift = _moved(T, push.approach_m * UP)
            cands.append((pre, T, lift))
        grasps.append(GraspGeometry(candidates=tuple(cands), closing_dir=x, approach=approach, width_m=width))
    # Off-centre grasps: the fingers moved along the object's length, closing across the
    # same width, up to ``offcentre_fraction`` of the length from the middle and no
    # closer than 5 mm to an end: a short neighbour against one part of a long box's
    # side blocks the centred grasp but not the other end.
    along2 = np.array([-across2[1], across2[0]])
    length = float(np.ptp(obj.footprint @ along2))
    reach = min(offcentre_fraction * length, length / 2.0 - gripper.settings.finger_width_m / 2.0 - 0.005)
    if offcentre_fraction > 0.0 and reach >= 0.01:
        centred = grasps[0]
        a3 = np.array([along2[0], along2[1], 0.0])
        a3 = a3 - float(a3 @ approach) * approach
        a3 = a3 / np.linalg.norm(a3)
        for sign in (1.0, -1.0):
            offset = sign * reach * a3
            moved = tuple(tuple(_moved(T, offset) for T in seq) for seq in centred.candidates)
            grasps.append(dataclasses.replace(centred, candidates=moved))
    return dataclasses.replace(grasps[0], alternatives=tuple(grasps[1:]))


def min_width_direction(footprint: np.ndarray) -> np.ndarray:
    """Unit 2D direction across which the convex polygon (K, 2) is narrowest: the width
    between two parallel supporting lines is least when one of them holds an edge."""
    edges = np.roll(footprint, -1, axis=0) - footprint
    lengths = np.linalg.norm(edges, axis=1)
    keep = lengths > 1e-12
    normals = np.column_stack([-edges[keep, 1], edges[keep, 0]]) / lengths[keep, None]
    widths = np.ptp(footprint @ normals.T, axis=0)
    return normals[int(np.argmin(widths))]


def direction_vectors(obj: ObjectGeometry) -> dict[str, np.ndarray]:
    """The four push directions (3,) in the table frame."""
    a1 = np.array([obj.axes2d[0, 0], obj.axes2d[0, 1], 0.0])
    a2 = np.array([obj.axes2d[1, 0], obj.axes2d[1, 1], 0.0])
    return {"dir1": a1, "dir2": -a1, "dir3": a2, "dir4": -a2}


def push_geometry(obj: ObjectGeometry, gripper: GripperModel, push: PushSettings) -> dict[str, PushGeometry]:
    out: dict[str, PushGeometry] = {}
    # what meets the object: the closed finger pair, or a cup tool's cup
    # (`GripperModel.push_contact`), its lowest point ``fingertips_above_table_m`` up
    part = gripper.push_contact
    height = push.fingertips_above_table_m + part.tip_z_m
    hull_xy = obj.hull_vertices[:, :2]
    c = obj.center.copy()
    c[2] = 0.0
    up_approach = push.approach_m * UP
    # half size of the closed finger pair along the push: its width across the fingers
    # (dir1/dir2, closing direction along the push) or a finger's width (dir3/dir4); a
    # cup's radius both ways
    half_parallel = part.half_x_m
    half_across = part.half_y_m
    for name, d in direction_vectors(obj).items():
        parallel = name in ("dir1", "dir2")
        rear = float((hull_xy @ d[:2]).min())
        lateral = c - (c @ d) * d
        extent = float(obj.extents[0] if parallel else obj.extents[1])
        length = min(push.pushing_step * extent, push.push_length_limit_m)
        n = max(1, math.ceil(length / push.path_resolution_m - 1e-9))
        steps = length * np.arange(1, n + 1) / n
        translations = steps[:, None] * d[None, :]
        # the rear face's half width across the push, for contact points off its middle
        side = cross3(UP, d)
        across = hull_xy @ side[:2]
        face_half = float(np.ptp(across)) / 2.0
        centre_across = float((across.max() + across.min()) / 2.0 - c[:2] @ side[:2])
        # every variant's gripper start, in the order the alternatives keep: per yaw (the
        # documented one first) the centred push, its raised contacts, its shifted ones;
        # then their sequences built together (`_push_sequences`)
        xs: list[np.ndarray] = []
        starts: list[np.ndarray] = []
        kinds: list[str] = []  # "yaw", "raised" or "shifted", per variant
        lifts = raised_contact_lifts(push, part.band_m, extent, obj.top_height_m)
        for along in (parallel, not parallel):  # the documented yaw first, then the other
            x = d if along else cross3(UP, d)
            half_along = half_parallel if along else half_across
            # half the contact's width across the push: a finger's width, or the pair's
            contact_half = half_across if along else half_parallel
            reach = face_half - contact_half - push.contact_edge_margin_m
            offsets = [0.0]
            if push.lateral_shift and reach >= push.contact_edge_margin_m:
                offsets += [reach, -reach]
            for k, offset in enumerate(offsets):
                across_m = (centre_across if k > 0 else 0.0) + offset
                start = lateral + (rear - push.gripper_behind_m - half_along) * d + across_m * side
                start[2] = height
                xs.append(x)
                starts.append(start)
                kinds.append("yaw" if k == 0 else "shifted")
                if k == 0:
                    for lift in lifts:
                        xs.append(x)
                        starts.append(start + np.array([0.0, 0.0, lift]))
                        kinds.append("raised")
        sequences = _push_sequences(np.array(xs), np.array(starts), up_approach, translations, n)
        made: dict[str, list[PushGeometry]] = {"yaw": [], "raised": [], "shifted": []}
        for kind, seq_pose in zip(kinds, sequences, strict=True):
            made[kind].append(
                PushGeometry(
                    direction=name, unit=d, length_m=length, object_translations=translations, candidates=seq_pose
                )
            )
        yaws, raised, shifted = made["yaw"], made["raised"], made["shifted"]
        out[name] = dataclasses.replace(yaws[0], alternatives=tuple(yaws[1:] + raised + shifted))
    return out


def raised_contact_lifts(
    push: PushSettings, closing_region_m: float, extent_along_m: float, height_m: float
) -> list[float]:
    """How far above the standard push each raised push contact is (m): fingertips at
    each of ``raised_fingertips_m`` where the fingers still meet at least
    ``MIN_CONTACT_BAND_M`` of the object's rear face and the object stays upright. A box
    pushed at height h_c (the middle of the contact band) by a horizontal force, with
    table friction mu, tips over its front edge when mu h_c exceeds half its length
    along the push; so h_c stays under that length / (2 mu). Beside a tall neighbour the
    arm's wrist, 0.115 m above the closing point, clears it only when the contact is
    higher (the thesis's pushes were all at the table)."""
    base = push.fingertips_above_table_m
    out = []
    for tips in push.raised_fingertips_m:
        band_top = min(tips + closing_region_m, height_m)
        contact = (tips + band_top) / 2.0
        if tips <= base or band_top - tips < MIN_CONTACT_BAND_M or contact * push.table_friction > extent_along_m / 2.0:
            continue
        out.append(float(tips - base))
    return out


def _push_sequence(
    x: np.ndarray, start: np.ndarray, up_approach: np.ndarray, translations: np.ndarray, n: int
) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]:
    """Both half-turn candidates of a push from ``start`` with closing direction ``x``:
    pre, start, path points, retreat."""
    return _push_sequences(x[None, :], start[None, :], up_approach, translations, n)[0]


def _push_sequences(
    xs: np.ndarray, starts: np.ndarray, up_approach: np.ndarray, translations: np.ndarray, n: int
) -> list[tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]]:
    """`_push_sequence` of each row of ``xs`` and ``starts`` (m, 3), in one set of array
    operations for all m: the same floats as one call each (each entry is made by the
    same operations on the same numbers), for a fraction of the calls. An object's four
    directions have 6 to 16 variants each (two yaws, raised and shifted contacts), and
    building them one at a time was ~85 small-array calls a frame (issue 39)."""
    down = -UP
    m = xs.shape[0]
    # each pose's rotation: columns x, z cross x, z with z down; the half-turned one -x, z cross -x, z
    y = cross3(np.broadcast_to(down, xs.shape), xs)
    y_turned = cross3(np.broadcast_to(down, xs.shape), -xs)
    seq = np.zeros((m, n + 3, 4, 4))
    seq[:, :, :3, 0] = xs[:, None, :]
    seq[:, :, :3, 1] = y[:, None, :]
    seq[:, :, :3, 2] = down
    seq[:, :, 3, 3] = 1.0
    position = seq[:, :, :3, 3]  # a view
    position[:] = starts[:, None, :]
    position[:, 0] += up_approach
    position[:, 2:-1] += translations
    position[:, -1] += translations[-1] + up_approach
    # the half-turned candidate: the same positions, its own rotation
    turned = seq.copy()
    turned[:, :, :3, 0] = -xs[:, None, :]
    turned[:, :, :3, 1] = y_turned[:, None, :]
    return [(tuple(seq[i]), tuple(turned[i])) for i in range(m)]
