"""Kinematics of any serial arm from its URDF (Pinocchio): forward kinematics, a damped
least squares IK with restarts, and the arm's collision capsules from the URDF's
collision geometry. The WAM keeps its analytic solver (wam_kinematics.py); this serves the
other profiles and a user's own URDF, and runs as the WAM's fallback in a test that
compares the two.

Why by hand: the maintained IK packages on PyPI (TRAC-IK bindings, pin-pink) solve one
pose from one start; what the planner needs around them (a warm start from the previous
pose of a motion, deterministic restarts, a cache, joint-limit clipping, a fast "beyond
reach" answer, capsules for the collision check) is this module either way, and
Pinocchio's Jacobians are what they would call. benchmarks/ik.py measures it.

Frames: poses are ``T_base_tcp`` in the profile's base frame; the TCP is the gripper's
closing point (z = approach, x = closing direction), as for the WAM.
"""

from __future__ import annotations

import contextlib
import copy
import logging
import math
import os
import sys
import tempfile
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from clearcli.errors import SettingsError
from clearcli.robot.kinematics import IKStats, SolverAccess, cache_lookup, se3, within_tolerance
from clearcli.robot.urdf_joints import checked_urdf

# a step of damped least squares moves no joint more than this (rad): the linearisation
# stays honest far from the target
_MAX_STEP_RAD = 0.4
# a start is given up when its error (m^2, plus rad^2 weighted as 0.1 m a radian) has not
# fallen by 5 % in this many iterations
_STALL_ITERATIONS = 12
_PROGRESS = 0.95
_RAD_AS_M2 = 0.01
# the generic solver tries at least this many starts (the WAM's analytic solver needs
# none). Every start is paid in full by a pose with no solution (the arm's in-reach
# refusals, most of a plan stage's IK time); of 2,000 reachable tool-down Panda poses
# (FK of random in-limit configurations) 24 starts solved 100 % and 99.85 % on a second
# draw, against 100 % / 99.95 % with 40, for 0.6 times the refusal time
_MIN_STARTS = 24
# a solved pose within this (m, see _nearest_solved) gives the first start of a new one;
# the last _NEAR_KEEP solved poses are searched
_NEAR_M = 0.3
_NEAR_KEEP = 256
# URDFs whose missing meshes were warned about
_WARNED: set[Path] = set()


def _capsule_of(geometry: Any) -> tuple[np.ndarray, np.ndarray, float] | None:
    """(a, b, radius) of a collision shape in its own frame: a cylinder along its axis,
    a sphere as a point, a box or a mesh as the capsule round its longest axis."""
    g = geometry
    kind = type(g).__name__  # hppfcl's or coal's classes, whichever Pinocchio uses
    if kind in ("Cylinder", "Capsule"):
        h = float(g.halfLength)
        return np.array([0.0, 0.0, -h]), np.array([0.0, 0.0, h]), float(g.radius)
    if kind == "Sphere":
        return np.zeros(3), np.zeros(3), float(g.radius)
    if kind == "Box":
        half = np.asarray(g.halfSide, dtype=float)
        k = int(np.argmax(half))
        others = np.delete(half, k)
        a, b = np.zeros(3), np.zeros(3)
        a[k], b[k] = -half[k], half[k]
        return a, b, float(np.hypot(*others))
    vertices = getattr(g, "vertices", None)
    if callable(vertices):
        v = np.asarray(vertices(), dtype=float)
        if v.shape[0] >= 2:
            c = v.mean(axis=0)
            axis = np.linalg.svd(v - c, full_matrices=False)[2][0]
            t = (v - c) @ axis
            radial = np.linalg.norm((v - c) - np.outer(t, axis), axis=1)
            return c + t.min() * axis, c + t.max() * axis, float(radial.max())
    return None


def _without_missing_meshes(urdf: Path) -> tuple[str | None, int]:
    """(the URDF's text without the <collision> elements whose mesh file is not found,
    how many were dropped); (None, 0) when it cannot be read. A ``package://PKG/path``
    mesh is looked for as ``path`` beside the URDF and in its parent folders."""
    try:
        root = ET.parse(urdf).getroot()
    except (ET.ParseError, OSError):
        return None, 0

    def found(name: str) -> bool:
        rel = name.split("://", 1)[1].split("/", 1)[-1] if "://" in name else name
        return any((folder / rel).is_file() for folder in (urdf.parent, *urdf.parent.parents))

    dropped = 0
    for link in root.iter("link"):
        for col in list(link.findall("collision")):
            mesh = col.find("geometry/mesh")
            if mesh is not None and not found(mesh.get("filename", "")):
                link.remove(col)
                dropped += 1
    return ET.tostring(root, encoding="unicode"), dropped


def _without_covered(
    parts: list[tuple[int, np.ndarray, np.ndarray, float]],
) -> list[tuple[int, np.ndarray, np.ndarray, float]]:
    """The capsules without those inside another of the same joint: a description's
    cylinder capped by two spheres is one capsule (the Panda's links), not three."""
    keep = []
    for i, (j, a, b, r) in enumerate(parts):
        covered = False
        for k, (j2, a2, b2, r2) in enumerate(parts):
            if k == i or j2 != j or r2 < r or (r2 == r and k > i and np.allclose(a, a2) and np.allclose(b, b2)):
                continue
            # both ends of capsule i within capsule k, grown by the difference of the radii
            d = b2 - a2
            L2 = float(d @ d)
            ends_in = True
            for p in (a, b):
                t = 0.0 if L2 == 0 else min(1.0, max(0.0, float((p - a2) @ d) / L2))
                if float(np.linalg.norm(p - (a2 + t * d))) > r2 - r + 1e-9:
                    ends_in = False
                    break
            if ends_in:
                covered = True
                break
        if not covered:
            keep.append(parts[i])
    return keep


@contextlib.contextmanager
def _quiet_stderr() -> Iterator[list[str]]:
    """File descriptor 2 to a temporary file while a C++ library (urdfdom) talks on it:
    the user gets our one line, not its dump. Yields a list that holds, once the block
    ends, what was said (the reason a file was refused is only there)."""
    sys.stderr.flush()
    said: list[str] = []
    saved = os.dup(2)
    try:
        with tempfile.TemporaryFile() as sink:
            os.dup2(sink.fileno(), 2)
            try:
                yield said
            finally:
                os.dup2(saved, 2)
                sink.seek(0)
                said.append(sink.read().decode(errors="replace"))
    finally:
        os.close(saved)


def _first_error(said: list[str]) -> str:
    """urdfdom's first ``Error:`` line in what it said, without the prefix ("" if none)."""
    for line in "".join(said).splitlines():
        if line.strip().startswith("Error:"):
            return " ".join(line.strip()[len("Error:") :].split())
    return ""


def _chain_end(model: Any) -> str:
    """The last body frame of the longest chain of movable joints (the flange when the
    URDF has no gripper joints)."""
    depth = [0] * model.njoints
    for j in range(1, model.njoints):
        depth[j] = depth[model.parents[j]] + 1
    deepest = int(np.argmax(depth))
    bodies = [f for f in model.frames if f.parentJoint == deepest and f.type == model.frames[0].type.BODY]
    return bodies[-1].name if bodies else model.frames[-1].name


@dataclass(frozen=True)
class _ReachBounds:
    """What `UrdfKinematics.reachable` tests beyond the summed link lengths."""

    flange_m: float  # the flange's greatest distance from the shoulder (m)
    previous_m: float  # the origin of the joint before the last: its greatest distance
    axis: np.ndarray  # (3,) the last joint's axis in its own frame
    along_m: float  # where the joint before the last lies, seen from the last joint's
    radius_m: float  # frame: this far along its axis, this far from it
    flange_to_last: np.ndarray  # (4,4) the last joint's frame in the flange's


# measured bounds are a search's best, short of the true greatest distance by a little:
# this much is added (m), and a test checks them against forward kinematics
_BOUND_SLACK_M = 0.002
_bounds_cache: dict[tuple[Any, ...], _ReachBounds | None] = {}


def _reach_bounds(
    model: Any, shoulder: int, flange_id: int, lower: np.ndarray, upper: np.ndarray
) -> _ReachBounds | None:
    """The greatest distances from the shoulder joint's origin (joint ``shoulder``) of
    the flange and of the origin of the joint before the last, over the joint limits:
    random configurations, the best few then climbed to a local maximum within the
    limits (projected gradient ascent; scipy.optimize would cost its import, ~80 ms, on
    every run). None when the flange does not hang from the last joint, or the
    chain is too short for the second bound to mean anything. Kept per model (a batch
    builds the same arm for every frame)."""
    import pinocchio as pin

    last = model.njoints - 1
    previous = int(model.parents[last])
    placements = np.array([np.asarray(M.homogeneous) for M in model.jointPlacements]).round(9)
    key = (tuple(model.names), placements.tobytes(), shoulder, flange_id, lower.tobytes(), upper.tobytes())
    if key in _bounds_cache:
        return _bounds_cache[key]
    out = None
    flange = model.frames[flange_id]
    # a joint turning a whole turn or more (or without finite limits) is searched over
    # one turn: the distances repeat with it
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    whole = ~np.isfinite(upper - lower) | (upper - lower >= 2 * math.pi)
    lower, upper = np.where(whole, -math.pi, lower), np.where(whole, math.pi, upper)
    if flange.parentJoint == last and previous - shoulder >= 2:
        data = model.createData()
        world = pin.LOCAL_WORLD_ALIGNED

        def climbed(q: np.ndarray, k: int) -> tuple[float, np.ndarray]:
            """Distance k (0 the flange's, 1 the joint before the last's) at q, and its
            gradient in q."""
            pin.computeJointJacobians(model, data, q)
            pin.updateFramePlacements(model, data)
            o = data.oMi[shoulder].translation
            Jo = pin.getJointJacobian(model, data, shoulder, world)[:3]
            if k == 0:
                p, Jp = data.oMf[flange_id].translation, pin.getFrameJacobian(model, data, flange_id, world)[:3]
            else:
                p, Jp = data.oMi[previous].translation, pin.getJointJacobian(model, data, previous, world)[:3]
            d = np.asarray(p - o, dtype=float)
            n = float(np.linalg.norm(d))
            return n, (d / max(n, 1e-12)) @ np.asarray(Jp - Jo)

        def distances(q: np.ndarray) -> tuple[float, float]:
            pin.framesForwardKinematics(model, data, q)
            o = data.oMi[shoulder].translation
            return (
                float(np.linalg.norm(data.oMf[flange_id].translation - o)),
                float(np.linalg.norm(data.oMi[previous].translation - o)),
            )

        rng = np.random.default_rng(7)
        samples = rng.uniform(lower, upper, size=(256, model.nq))
        sampled = np.array([distances(q) for q in samples])
        best = []
        for k in range(2):
            found = sampled[:, k]
            top = float(found.max())
            for q in samples[np.argsort(-found)[:4]]:
                # projected gradient ascent within the limits, the step grown on success
                # and halved on failure
                val, grad = climbed(q, k)
                step = 0.2
                for _ in range(100):
                    if step < 1e-3:  # rad: at a maximum the distance is then within ~0.1 mm of it
                        break
                    norm = float(np.linalg.norm(grad))
                    if norm < 1e-12:
                        break
                    q_new = np.clip(q + step * grad / norm, lower, upper)
                    v_new, g_new = climbed(q_new, k)
                    if v_new > val:
                        q, val, grad, step = q_new, v_new, g_new, step * 1.5
                    else:
                        step *= 0.5
                top = max(top, val)
            best.append(top + _BOUND_SLACK_M)
        # the last joint's axis in its frame (its Jacobian column), and where the joint
        # before it lies seen from it
        q = np.clip(np.zeros(model.nq), lower, upper)
        pin.computeJointJacobians(model, data, q)
        J = pin.getJointJacobian(model, data, last, pin.LOCAL)
        axis = np.asarray(J[3:, model.joints[last].idx_v], dtype=float)
        axis = axis / np.linalg.norm(axis)
        before = np.asarray(model.jointPlacements[last].inverse().translation, dtype=float)
        along = float(before @ axis)
        radius = float(np.linalg.norm(before - along * axis))
        if all(np.isfinite([*best, along, radius])):
            out = _ReachBounds(
                best[0], best[1], axis, along, radius, np.asarray(flange.placement.inverse().homogeneous)
            )
    _bounds_cache[key] = out
    return out


def _read_model(urdf: Path) -> Any:
    """The URDF's whole model (every joint), or one line (SettingsError) saying why not:
    what urdfdom would refuse with its reason on stderr only, or take silently (lower
    limit above upper, a zero axis), is one line naming the joint; continuous joints come
    back as revolute ones over a stated range (urdf_joints.CONTINUOUS_RANGE_RAD)."""
    import pinocchio as pin

    text = checked_urdf(urdf)
    try:
        with _quiet_stderr() as said:
            return pin.buildModelFromXML(text)
    except Exception as exc:  # Pinocchio raises ValueError/RuntimeError on bad files
        reason = _first_error(said) or str(exc).splitlines()[0]
        raise SettingsError(f"{urdf}: not a URDF Pinocchio can read ({reason})") from None


def _arm_frames(full: Any, urdf: Path, base_frame: str, flange_frame: str, tcp_frame: str) -> tuple[str, str]:
    """(base frame, flange frame): as given, else the root link and the end of the longest
    chain; each a link of the URDF (frames are its links: Pinocchio's joint frames are not
    offered), ``tcp_frame`` (if given) a frame of it, the base not the flange."""
    import pinocchio as pin

    links = [f.name for f in full.frames if f.type == pin.FrameType.BODY]
    base_frame = base_frame or links[0]  # the root link
    flange_frame = flange_frame or _chain_end(full)
    for what, name in (("base_frame", base_frame), ("flange_frame", flange_frame)):
        if name not in links:
            raise SettingsError(f"{urdf}: no frame {name!r} ({what}); its frames (links): {', '.join(links)}")
    if tcp_frame and not full.existFrame(tcp_frame):
        raise SettingsError(f"{urdf}: no frame {tcp_frame!r} (tcp_frame); its frames (links): {', '.join(links)}")
    if base_frame == flange_frame:
        raise SettingsError(
            f"{urdf}: base_frame and flange_frame are both {base_frame!r}; the base is the link the arm stands "
            "on, the flange the one the gripper is mounted on"
        )
    return base_frame, flange_frame


def _joints_off_the_arm(full: Any, urdf: Path, base_frame: str, flange_frame: str) -> list[int]:
    """The joints to hold at 0: all but those between the base and the flange, which move
    the flange. Any other (a gripper's fingers, a torso or a mobile base above the base
    frame) is held: poses are in the base frame, which must not move with the arm's
    joints. One line when the flange does not hang from the base or nothing moves it."""
    import pinocchio as pin

    base_joint = full.frames[full.getFrameId(base_frame, pin.FrameType.BODY)].parentJoint
    chain = set()
    j = full.frames[full.getFrameId(flange_frame, pin.FrameType.BODY)].parentJoint
    while j > 0 and j != base_joint:
        chain.add(j)
        j = full.parents[j]
    if j != base_joint:
        raise SettingsError(
            f"{urdf}: flange_frame {flange_frame!r} does not hang from base_frame {base_frame!r}; give a base "
            "the flange is reached from through the arm's joints"
        )
    if not chain:
        raise SettingsError(
            f"{urdf}: no movable joint between base_frame {base_frame!r} and flange_frame {flange_frame!r} "
            "(fixed to each other); give the arm's base and its flange"
        )
    return [k for k in range(1, full.njoints) if k not in chain]


def _add_tcp(model: Any, flange_frame: str, tcp_xyz_m: Sequence[float], tcp_yaw_deg: float) -> str:
    """The closing point as a frame ("clear_tcp") at an offset from the flange: ``tcp_xyz_m``
    in the flange frame, turned ``tcp_yaw_deg`` about its z. Returns its name."""
    import pinocchio as pin

    yaw = math.radians(tcp_yaw_deg)
    R = np.array([[math.cos(yaw), -math.sin(yaw), 0.0], [math.sin(yaw), math.cos(yaw), 0.0], [0.0, 0.0, 1.0]])
    fl = model.frames[model.getFrameId(flange_frame)]
    offset = pin.SE3(R, np.asarray(tcp_xyz_m if len(tcp_xyz_m) else (0.0, 0.0, 0.0), dtype=float))
    name = "clear_tcp"
    model.addFrame(
        pin.Frame(name, fl.parentJoint, model.getFrameId(flange_frame), fl.placement * offset, pin.FrameType.OP_FRAME)
    )
    return name


def _check_revolute(model: Any, urdf: Path) -> None:
    """The arm is a serial chain of six or more revolute joints and nothing else movable."""
    revolute = [
        j
        for j in model.joints[1:]
        if j.shortname() in ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned")
    ]
    if len(revolute) < 6 or model.nq != len(revolute):
        raise SettingsError(
            f"{urdf}: a chain of {len(revolute)} revolute joints (nq {model.nq}); the generic IK needs a "
            "serial chain of 6 or more revolute joints and nothing else movable"
        )


class UrdfKinematics(SolverAccess):
    """A serial arm of six or more revolute joints read from a URDF.

    Built in named steps (`__init__`): the description read and checked, the arm's
    frames and the joints off it held, the closing point added, the frames placed, the
    reach measured, the IK search set up, the collision capsules read, a closed form
    attached when the arm has one."""

    def __init__(
        self,
        urdf: Path,
        base_frame: str,
        tcp_frame: str,
        *,
        flange_frame: str,
        tcp_xyz_m: Sequence[float] = (),
        tcp_yaw_deg: float = 0.0,
        closed_form: tuple[Any, str, str] | None = None,
        rest: Sequence[float] | None = None,
        arm_from_joint: int = 2,
        gripper_frames: Sequence[str] = (),
        damping: float = 0.05,
        max_iterations: int = 150,
        tolerance_m: float = 0.001,
        tolerance_rad: float = 0.01,
        n_seeds: int = 8,
    ) -> None:
        import pinocchio as pin

        self.pin = pin
        self.urdf = Path(urdf)
        full = _read_model(self.urdf)
        base_frame, flange_frame = _arm_frames(full, urdf, base_frame, flange_frame, tcp_frame)
        locked = _joints_off_the_arm(full, urdf, base_frame, flange_frame)
        self.model = pin.buildReducedModel(full, locked, pin.neutral(full)) if locked else full
        self._locked = locked
        if not tcp_frame:  # the closing point as an offset from the flange
            tcp_frame = _add_tcp(self.model, flange_frame, tcp_xyz_m, tcp_yaw_deg)
        _check_revolute(self.model, urdf)
        self._place_frames(base_frame, flange_frame, tcp_frame)
        self._measure_reach(int(arm_from_joint), tolerance_m, tolerance_rad)
        self.rest = np.clip(
            np.asarray(rest if rest is not None else np.zeros(self.model.nq), dtype=float), self.lower, self.upper
        )
        self.damping = float(damping)
        self.max_iterations = int(max_iterations)
        self.tolerance_m = float(tolerance_m)
        self.tolerance_rad = float(tolerance_rad)
        self.n_seeds = max(_MIN_STARTS, int(n_seeds))
        self._new_search()
        self._set_capsules(arm_from_joint, gripper_frames)
        self._closed = self._closed_form_of(closed_form)

    # -- the steps of __init__ --------------------------------------------------------
    def _place_frames(self, base_frame: str, flange_frame: str, tcp_frame: str) -> None:
        """The frames' ids, the joint limits, and the base, the flange and the TCP placed
        at the zero configuration: poses are in the base frame, Pinocchio's in the root."""
        pin, model = self.pin, self.model
        self.data = model.createData()
        self.joint_names = tuple(model.names[1:])
        self.tcp_id = model.getFrameId(tcp_frame)
        self.flange_id = model.getFrameId(flange_frame)
        self.lower = np.array(model.lowerPositionLimit, dtype=float)
        self.upper = np.array(model.upperPositionLimit, dtype=float)
        pin.framesForwardKinematics(model, self.data, np.zeros(model.nq))
        self.M_root_base = self.data.oMf[model.getFrameId(base_frame)].copy()
        self.M_base_root = self.M_root_base.inverse()
        self.M_flange_tcp = self.data.oMf[self.flange_id].actInv(self.data.oMf[self.tcp_id])
        self.base_frame = base_frame
        self.flange_frame = flange_frame

    def _measure_reach(self, j0: int, tolerance_m: float, tolerance_rad: float) -> None:
        """What `reachable` tests: an upper bound on the flange's distance from the
        shoulder joint's origin (joint ``j0``); at first the sum of the chain's link
        lengths from there (the triangle inequality), then, where measured, tighter. The
        makers' reach figures are not bounds: a UR5e's flange reaches 0.97 m from its
        shoulder against the quoted 0.85 m."""
        pin, model = self.pin, self.model
        self._arm_from_joint = j0
        pin.forwardKinematics(model, self.data, np.zeros(model.nq))
        self.shoulder_bound = np.asarray((self.M_base_root * self.data.oMi[j0]).translation, dtype=float)
        links = [float(np.linalg.norm(model.jointPlacements[k].translation)) for k in range(j0 + 1, model.njoints)]
        flange = model.frames[self.flange_id]
        self.stretch_m = sum(links) + float(np.linalg.norm(flange.placement.translation))
        self.links_stretch_m = self.stretch_m  # (benchmarks/ik.py draws "in reach" within it)
        # Tighter, measured over the joint limits (`_reach_bounds`): the flange's and the
        # last joint's neighbour's greatest distance from the shoulder. A Panda's flange
        # comes 0.858 m from it at most, against 0.986 m summed; the tool-down poses
        # between the two are most of its refusals, each paid with every IK start.
        self._wrist = _reach_bounds(model, j0, self.flange_id, self.lower, self.upper)
        if self._wrist is not None:
            self.stretch_m = min(self.stretch_m, self._wrist.flange_m)
            self._tcp_to_last = np.linalg.inv(np.asarray(self.M_flange_tcp.homogeneous)) @ self._wrist.flange_to_last
            # a solution is accepted within the IK's tolerances: its wrist may stand this
            # much beyond where the exact pose puts it (the tilt times the lever from the
            # TCP, plus the position)
            lever_m = float(np.linalg.norm(self._tcp_to_last[:3, 3])) + self._wrist.radius_m + abs(self._wrist.along_m)
            self._wrist_slack_m = float(tolerance_m) + float(tolerance_rad) * lever_m

    def _new_search(self) -> None:
        """An IK search's own state, empty: statistics, the cache, the random seeds (drawn
        when first needed), the ring of recent solved poses (position, a tenth of the
        rotation's entries) and their solutions."""
        nq = self.model.nq
        self.stats = IKStats()
        self._cache: dict[bytes, np.ndarray | None] = {}
        self._random_seeds: list[np.ndarray] | None = None
        self._near_pose = np.zeros((_NEAR_KEEP, 12))
        self._near_q = np.zeros((_NEAR_KEEP, nq))
        self._n_solved = 0

    def _set_capsules(self, arm_from_joint: int, gripper_frames: Sequence[str]) -> None:
        """The arm's collision capsules (`_read_capsules`), and the same as arrays:
        `capsules` places them all in one stacked product."""
        self._capsule_parts = self._read_capsules(arm_from_joint, set(gripper_frames))
        parts = self._capsule_parts
        self._capsule_joints = [j for j, *_ in parts]
        self._capsule_a = np.array([pa for _, pa, _, _ in parts], dtype=float).reshape(-1, 3)
        self._capsule_b = np.array([pb for _, _, pb, _ in parts], dtype=float).reshape(-1, 3)
        self._capsule_r = np.array([r for *_, r in parts], dtype=float)

    def _closed_form_of(self, closed_form: tuple[Any, str, str] | None) -> tuple[Any, Any, Any] | None:
        """(solver, its base frame, its end frame): a closed form for this arm (the UR
        family's, ur_ik.py); its end frame's pose is the TCP's less a fixed offset. Kept
        as (solver, M_dh_root, M_tcp_end)."""
        if closed_form is None:
            return None
        pin, model = self.pin, self.model
        solver, dh_base, dh_end = closed_form
        pin.framesForwardKinematics(model, self.data, np.zeros(model.nq))
        M_root_dh = self.data.oMf[model.getFrameId(dh_base)]
        M_end_tcp = self.data.oMf[model.getFrameId(dh_end)].actInv(self.data.oMf[self.tcp_id])
        return (solver, M_root_dh.inverse(), M_end_tcp.inverse())

    def fresh(self) -> UrdfKinematics:
        """A new IK search on this model: the same arm and settings, its own Pinocchio
        data and an empty search state (as if built again, without reading the URDF)."""
        out = copy.copy(self)
        out.data = self.model.createData()
        out._new_search()
        return out

    # -- collision model ------------------------------------------------------------
    def _read_capsules(
        self, arm_from_joint: int, gripper_frames: set[str]
    ) -> list[tuple[int, np.ndarray, np.ndarray, float]]:
        """(joint, a, b, radius) in the joint's frame for every collision shape of the arm
        moved by joint ``arm_from_joint`` or later, the gripper's left out: what hangs
        from the flange and ``gripper_frames`` (what the gripper touches is what
        block_grasp/block_dir say; the base and the shoulder column stand still). A mesh
        whose file is missing is left out, the rest kept, with one warning."""
        pin = self.pin
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                with _quiet_stderr():
                    geom = pin.buildGeomFromUrdf(
                        self.model, str(self.urdf), pin.GeometryType.COLLISION, package_dirs=[str(self.urdf.parent)]
                    )
            except Exception as exc:  # missing package:// meshes: the rest without them
                kept, dropped = _without_missing_meshes(self.urdf)
                geom = None
                if kept is not None:
                    try:
                        with _quiet_stderr():
                            geom = pin.buildGeomFromUrdfString(self.model, kept, pin.GeometryType.COLLISION)
                    except Exception:
                        geom = None
                if self.urdf not in _WARNED:  # once per file and process
                    _WARNED.add(self.urdf)
                    logging.getLogger(__name__).warning(
                        "%s: %s (%s); %s",
                        self.urdf,
                        f"{dropped} collision mesh(es) not found, left out"
                        if geom is not None
                        else "collision geometry not loaded",
                        str(exc).splitlines()[0],
                        f"the arm's collision check uses the {len(geom.geometryObjects)} shape(s) left"
                        if geom is not None
                        else "the arm's collision check is off",
                    )
                if geom is None:
                    return []
        out = []
        for go in geom.geometryObjects:
            if go.parentJoint < arm_from_joint:
                continue
            if self._beyond_flange(go.parentFrame) or self.model.frames[go.parentFrame].name in gripper_frames:
                continue
            cap = _capsule_of(go.geometry)
            if cap is None:
                continue
            a, b, r = cap
            M = go.placement
            R, t = np.asarray(M.rotation), np.asarray(M.translation)
            out.append((int(go.parentJoint), R @ a + t, R @ b + t, r))
        return _without_covered(out)

    def _beyond_flange(self, frame_id: int) -> bool:
        """The frame is the flange or hangs from it (the gripper's bodies)."""
        frames = self.model.frames
        while True:
            if frame_id == self.flange_id:
                return True
            parent = int(frames[frame_id].parentFrame)
            if parent == frame_id or frames[frame_id].parentJoint == 0 and parent == 0:
                return False
            frame_id = parent

    def capsules(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Arm capsules at q: (C,3) start points, (C,3) end points, (C,) radii (base frame)."""
        pin = self.pin
        pin.forwardKinematics(self.model, self.data, np.asarray(q, dtype=float))
        if not self._capsule_parts:
            return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
        # one stacked product for all parts (the IK check asks this for every pose)
        oMi = self.data.oMi
        joints, pa, pb = self._capsule_joints, self._capsule_a, self._capsule_b
        R = np.array([oMi[j].rotation for j in joints])  # (C,3,3) joint frames in the root
        t = np.array([oMi[j].translation for j in joints])
        M = self.M_base_root
        Rb, tb = np.asarray(M.rotation), np.asarray(M.translation)
        a = (np.einsum("cij,cj->ci", R, pa) + t) @ Rb.T + tb
        b = (np.einsum("cij,cj->ci", R, pb) + t) @ Rb.T + tb
        return a, b, self._capsule_r.copy()

    # -- forward kinematics ---------------------------------------------------------
    def fk(self, q: np.ndarray, frame: str | None = None) -> np.ndarray:
        """T_base_<frame> (4x4) at joint angles q; the TCP by default."""
        pin = self.pin
        pin.framesForwardKinematics(self.model, self.data, np.asarray(q, dtype=float))
        fid = self.tcp_id if frame is None else self.model.getFrameId(frame)
        return np.array((self.M_base_root * self.data.oMf[fid]).homogeneous)

    # -- inverse kinematics ---------------------------------------------------------
    def reachable(self, T_base_tcp: np.ndarray, slack_m: float = 0.005) -> bool:
        """Cheap necessary condition (no pose it rejects has a solution): the flange
        within its greatest distance from the shoulder joint (``stretch_m``: measured
        over the joint limits, else the links' summed lengths; plus ``slack_m``), and
        the joint before the last within its own (`_reach_bounds`)."""
        T = np.asarray(T_base_tcp, dtype=float)
        M = np.asarray(self.M_flange_tcp.homogeneous)
        flange = T[:3, 3] - T[:3, :3] @ (M[:3, :3].T @ M[:3, 3])
        if float(np.linalg.norm(flange - self.shoulder_bound)) > self.stretch_m + slack_m:
            return False
        w = self._wrist
        if w is None:
            return True
        # The last joint's frame is fixed by the pose; the joint before it turns about
        # the last one's axis on a circle around it: its nearest point to the shoulder
        # must lie within that joint's greatest distance from it.
        T_last = T @ self._tcp_to_last  # the last joint's frame in the base frame
        R, t = T_last[:3, :3], T_last[:3, 3]
        u = R @ w.axis
        centre = t + R @ (w.along_m * w.axis)
        v = self.shoulder_bound - centre
        along = float(v @ u)
        across = float(np.linalg.norm(v - along * u))
        return math.hypot(along, across - w.radius_m) <= w.previous_m + self._wrist_slack_m

    def seeds(self, T_target: np.ndarray) -> list[np.ndarray]:
        """The rest shape turned towards the target, then fixed pseudo-random ones (drawn
        once: the same for every pose)."""
        q = self.rest.copy()
        q[0] = float(np.clip(math.atan2(T_target[1, 3], T_target[0, 3]) + q[0], self.lower[0], self.upper[0]))
        if self._random_seeds is None:
            rng = np.random.default_rng(12345)
            self._random_seeds = list(rng.uniform(self.lower, self.upper, size=(self.n_seeds - 1, self.lower.size)))
        return [q, *self._random_seeds]

    def _solve_from(self, target: Any, q0: np.ndarray, iterations: int | None = None) -> np.ndarray | None:
        """Damped least squares from q0 (clipped to the limits at every step); a start
        that stops improving is given up."""
        pin = self.pin
        model, data, fid, local = self.model, self.data, self.tcp_id, pin.LOCAL
        lo, hi = self.lower, self.upper
        tol_m2, tol_rad2 = self.tolerance_m**2, self.tolerance_rad**2
        q = np.clip(np.asarray(q0, dtype=float), lo, hi)
        damp = self.damping**2 * np.eye(6)
        self.stats.starts += 1
        n_it = self.max_iterations if iterations is None else int(iterations)
        best, since = math.inf, 0
        for it in range(n_it):
            pin.computeJointJacobians(model, data, q)
            pin.updateFramePlacement(model, data, fid)
            err = pin.log6(data.oMf[fid].actInv(target)).vector
            vx, vy, vz, wx, wy, wz = err.tolist()
            e_m2, e_rad2 = vx * vx + vy * vy + vz * vz, wx * wx + wy * wy + wz * wz
            if e_m2 < tol_m2 and e_rad2 < tol_rad2:
                self.stats.iterations += it
                return q
            # stuck (a joint against its limit, a local minimum): another start does
            # better than more steps here
            size = e_m2 + _RAD_AS_M2 * e_rad2
            if size < _PROGRESS * best:
                best, since = size, 0
            else:
                since += 1
                if since >= _STALL_ITERATIONS:
                    self.stats.iterations += it
                    return None
            J = pin.getFrameJacobian(model, data, fid, local)
            dq = J.T @ np.linalg.solve(J @ J.T + damp, err)
            step = float(np.abs(dq).max())
            if step > _MAX_STEP_RAD:
                dq *= _MAX_STEP_RAD / step
            q = np.minimum(np.maximum(q + dq, lo), hi)
        self.stats.iterations += n_it
        return None

    def ik(self, T_base_tcp: np.ndarray, warm: np.ndarray | None = None) -> np.ndarray | None:
        """Joint angles putting the TCP at ``T_base_tcp`` within the tolerances and the
        joint limits, or None: beyond the stretch at once; else damped least squares
        from ``warm`` (the previous pose's solution), then from the seeds."""
        T_base_tcp = np.asarray(T_base_tcp, dtype=float)
        key, found, hit = cache_lookup(self, T_base_tcp)
        if found:
            return hit
        q: np.ndarray | None = None
        if self._closed is not None:
            q = self._closed_form(T_base_tcp, warm) if self.reachable(T_base_tcp) else None
        elif self.reachable(T_base_tcp):
            target = self.M_root_base * se3(T_base_tcp)
            near = self._nearest_solved(T_base_tcp) if warm is None else None
            starts = [np.asarray(x, dtype=float) for x in (warm, near) if x is not None] + self.seeds(T_base_tcp)
            for q0 in starts:
                q = self._solve_from(target, q0)
                if q is not None:
                    break
        self._cache[key] = None if q is None else q.copy()
        if q is not None:  # into the ring of recent solutions (a long replay does not grow it)
            k = self._n_solved % _NEAR_KEEP
            self._near_pose[k, :3] = T_base_tcp[:3, 3]
            self._near_pose[k, 3:] = 0.1 * T_base_tcp[:3, :3].ravel()
            self._near_q[k] = q
            self._n_solved += 1
        return q

    def _closed_form(self, T_base_tcp: np.ndarray, warm: np.ndarray | None) -> np.ndarray | None:
        """The exact solution within the joint limits nearest the warm start (else the
        nearest solved pose's solution, else the rest shape), each joint taken at the turn
        (plus or minus 2 pi) nearest that start; None when no exact solution is within the
        limits. Every one is confirmed by Pinocchio's forward kinematics."""
        assert self._closed is not None
        solver, M_dh_root, M_tcp_end = self._closed
        target = self.M_root_base * se3(T_base_tcp)
        T_dh_end = np.asarray((M_dh_root * target * M_tcp_end).homogeneous)
        ref = warm if warm is not None else self._nearest_solved(T_base_tcp)
        ref = self.rest if ref is None else np.asarray(ref, dtype=float)
        cands = solver(T_dh_end)
        if not cands:
            return None
        Q = np.array(cands)
        Q = Q + 2.0 * math.pi * np.round((ref - Q) / (2.0 * math.pi))  # the turn nearest ref
        for _ in range(2):  # then into the limits, when a turn away fits
            Q = np.where(Q > self.upper, Q - 2.0 * math.pi, Q)
            Q = np.where(Q < self.lower, Q + 2.0 * math.pi, Q)
        inside = np.all((Q >= self.lower) & (Q <= self.upper), axis=1)
        order = np.argsort(np.sum((Q - ref) ** 2, axis=1))
        for k in order:  # nearest first; the first confirmed is the answer
            if inside[k] and within_tolerance(self, target, Q[k]):
                return Q[k].copy()
        return None

    def _nearest_solved(self, T: np.ndarray) -> np.ndarray | None:
        """The solution of the solved pose nearest ``T`` (position, plus a tenth of a metre
        per unit of rotation difference, Frobenius), when within _NEAR_M: the poses of one
        plan cluster round its objects, and a neighbour's solution is a few iterations
        away. The last _NEAR_KEEP solved poses are searched."""
        n = min(self._n_solved, _NEAR_KEEP)
        if n == 0:
            return None
        key = np.concatenate([T[:3, 3], 0.1 * T[:3, :3].ravel()])
        diff = self._near_pose[:n] - key
        d = np.sqrt(np.einsum("ij,ij->i", diff[:, :3], diff[:, :3])) + np.sqrt(
            np.einsum("ij,ij->i", diff[:, 3:], diff[:, 3:])
        )
        k = int(np.argmin(d))
        return self._near_q[k].copy() if d[k] <= _NEAR_M else None
