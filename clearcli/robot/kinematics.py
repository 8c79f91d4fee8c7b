"""Forward/inverse kinematics of the WAM (our URDF, Pinocchio) and the arm's collision
capsules; the feasibility check of one planner action (thesis 4.3).

Frames: ``base`` is the WAM's DH frame 0 at the shoulder (z up, x towards the table by
default placement), ``tcp`` the gripper closing point (z = approach, x = closing
direction), 0.115 m past the tool plate. Pinocchio is imported inside functions: the CLI
must start fast.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

URDF_PATH = Path(__file__).with_name("wam.urdf")
TCP_FRAME = "wam_gripper_tcp"
TOOL_PLATE_FRAME = "wam_tool_plate"
BASE_FRAME = "wam_link_base"
SHOULDER_ABOVE_FOOTPRINT_M = 0.346
TCP_PAST_TOOL_PLATE_M = 0.115
# Shoulder centre to tool plate at full stretch: |(0.045, 0.55)| + |(0.045, 0.30)| + 0.06.
REACH_TOOL_PLATE_M = math.hypot(0.045, 0.55) + math.hypot(0.045, 0.30) + 0.06

# Arm collision capsules (the URDF's cylinders/spheres as capsules between joint
# origins): (joint index a, joint index b or -1 for the tool plate, radius). The gripper
# is left out: whether it touches other objects is what block_grasp/block_dir say, and
# its fingers are meant to reach the table (push) and the target object.
_CAPSULES: tuple[tuple[int, int, float], ...] = (
    (3, 4, 0.06),  # upper arm: shoulder to elbow
    (4, 5, 0.06),  # elbow
    (5, 6, 0.045),  # forearm: elbow to wrist centre
    (7, -1, 0.045),  # wrist to tool plate
)


def _se3(T: np.ndarray) -> Any:
    import pinocchio as pin

    return pin.SE3(np.ascontiguousarray(T[:3, :3]), np.ascontiguousarray(T[:3, 3]))


def half_turn(T: np.ndarray) -> np.ndarray:
    """The same gripper pose turned by pi about its approach axis (the gripper is
    symmetric, so both are equally good grasps/pushes)."""
    out = T.copy()
    out[:3, 0] = -T[:3, 0]
    out[:3, 1] = -T[:3, 1]
    return out


@dataclass
class IKStats:
    solves: int = 0
    iterations: int = 0
    cache_hits: int = 0


class WamKinematics:
    """The WAM model loaded from ``wam.urdf`` with joint limits from the manual."""

    def __init__(
        self,
        damping: float = 0.05,
        max_iterations: int = 150,
        tolerance_m: float = 0.001,
        tolerance_rad: float = 0.01,
        n_seeds: int = 8,
    ) -> None:
        import pinocchio as pin

        self.pin = pin
        self.model = pin.buildModelFromUrdf(str(URDF_PATH))
        self.data = self.model.createData()
        self.tcp_id = self.model.getFrameId(TCP_FRAME)
        self.plate_id = self.model.getFrameId(TOOL_PLATE_FRAME)
        self.lower = np.array(self.model.lowerPositionLimit, dtype=float)
        self.upper = np.array(self.model.upperPositionLimit, dtype=float)
        self.damping = float(damping)
        self.max_iterations = int(max_iterations)
        self.tolerance_m = float(tolerance_m)
        self.tolerance_rad = float(tolerance_rad)
        self.n_seeds = max(1, int(n_seeds))
        self.stats = IKStats()
        self._cache: dict[bytes, np.ndarray | None] = {}
        # Pinocchio's world is the URDF root (the footprint); our poses are in the base
        # (shoulder) frame, 0.346 m above it.
        pin.framesForwardKinematics(self.model, self.data, np.zeros(self.model.nq))
        self.M_root_base = self.data.oMf[self.model.getFrameId(BASE_FRAME)].copy()
        self.M_base_root = self.M_root_base.inverse()

    # -- forward kinematics ---------------------------------------------------------
    def fk(self, q: np.ndarray, frame: str = TCP_FRAME) -> np.ndarray:
        """T_base_<frame> (4x4) at joint angles q (7,)."""
        pin = self.pin
        pin.framesForwardKinematics(self.model, self.data, np.asarray(q, dtype=float))
        fid = self.model.getFrameId(frame)
        return np.array((self.M_base_root * self.data.oMf[fid]).homogeneous)

    def capsules(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Arm capsules at q: (C,3) start points, (C,3) end points, (C,) radii (base frame)."""
        pin = self.pin
        pin.framesForwardKinematics(self.model, self.data, np.asarray(q, dtype=float))
        return self._capsules_now()

    def _capsules_now(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        oMi = self.data.oMi
        plate = self.data.oMf[self.plate_id].translation
        a = np.array([oMi[i].translation for i, _, _ in _CAPSULES])
        b = np.array([plate if j < 0 else oMi[j].translation for _, j, _ in _CAPSULES])
        R, t = self.M_base_root.rotation, self.M_base_root.translation
        a = a @ R.T + t
        b = b @ R.T + t
        r = np.array([rad for _, _, rad in _CAPSULES])
        return a, b, r

    # -- inverse kinematics ---------------------------------------------------------
    def seeds(self, T_target: np.ndarray) -> list[np.ndarray]:
        """Deterministic start configurations: arm turned towards the target with a few
        elbow/wrist shapes, then fixed pseudo-random ones."""
        azimuth = math.atan2(T_target[1, 3], T_target[0, 3])
        az = float(np.clip(azimuth, self.lower[0], self.upper[0]))
        shapes = [
            (0.9, 0.0, 1.6, 0.0, 0.6, 0.0),
            (0.5, 0.0, 2.0, 0.0, 0.6, 0.0),
            (1.3, 0.0, 1.0, 0.0, 0.8, 0.0),
            (0.9, 0.0, 1.6, 0.0, -0.6, 0.0),
            (0.6, 1.5, 1.6, -1.5, 0.6, 0.0),
            (0.6, -1.5, 1.6, 1.5, 0.6, 0.0),
        ]
        out = [np.array([az, *s]) for s in shapes]
        rng = np.random.default_rng(12345)
        while len(out) < self.n_seeds:
            q = rng.uniform(self.lower, self.upper)
            q[0] = az
            out.append(q)
        return [np.clip(q, self.lower, self.upper) for q in out[: max(self.n_seeds, 1)]]

    def _solve_from(self, target: Any, q0: np.ndarray) -> np.ndarray | None:
        pin = self.pin
        model, data, fid = self.model, self.data, self.tcp_id
        q = q0.copy()
        lam2 = self.damping**2
        eye = np.eye(6)
        for it in range(self.max_iterations):
            pin.computeJointJacobians(model, data, q)
            pin.updateFramePlacement(model, data, fid)
            err = pin.log6(data.oMf[fid].actInv(target)).vector  # in the TCP frame
            if np.linalg.norm(err[:3]) < self.tolerance_m and np.linalg.norm(err[3:]) < self.tolerance_rad:
                self.stats.iterations += it
                return q
            J = pin.getFrameJacobian(model, data, fid, pin.LOCAL)
            dq = J.T @ np.linalg.solve(J @ J.T + lam2 * eye, err)
            step = float(np.max(np.abs(dq)))
            if step > 0.4:  # keep the linearisation honest far from the target
                dq *= 0.4 / step
            q = np.clip(q + dq, self.lower, self.upper)
        self.stats.iterations += self.max_iterations
        return None

    def ik(self, T_base_tcp: np.ndarray, warm: np.ndarray | None = None) -> np.ndarray | None:
        """Joint angles putting the TCP at ``T_base_tcp`` within the tolerances and the
        joint limits, or None. Tries ``warm`` first, then the deterministic seeds."""
        # Keyed by the pose alone: a pose met again (the lift pose is the pre-grasp pose;
        # backtracking re-checks candidates) gets the same answer, whatever the warm start.
        key = np.round(np.asarray(T_base_tcp, dtype=float)[:3], 6).tobytes()
        if key in self._cache:
            self.stats.cache_hits += 1
            hit = self._cache[key]
            return None if hit is None else hit.copy()
        self.stats.solves += 1
        target = self.M_root_base * _se3(T_base_tcp)
        starts = ([np.clip(warm, self.lower, self.upper)] if warm is not None else []) + self.seeds(T_base_tcp)
        q = None
        for q0 in starts:
            q = self._solve_from(target, q0)
            if q is not None:
                break
        self._cache[key] = None if q is None else q.copy()
        return q

    def reachable(self, T_base_tcp: np.ndarray, slack_m: float = 0.005) -> bool:
        """Cheap necessary condition: the tool plate within the arm's stretch from the
        shoulder (the base origin)."""
        plate = T_base_tcp[:3, 3] - TCP_PAST_TOOL_PLATE_M * T_base_tcp[:3, 2]
        return float(np.linalg.norm(plate)) <= REACH_TOOL_PLATE_M + slack_m


# -- collision helpers -----------------------------------------------------------------


def hull_planes(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(F,4) outward face planes (n, d) with n.x + d <= 0 inside the convex hull."""
    v = np.asarray(vertices, dtype=float)
    f = np.asarray(faces, dtype=int)
    if len(v) == 0 or len(f) == 0:
        return np.zeros((0, 4))
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    n = np.cross(b - a, c - a)
    norm = np.linalg.norm(n, axis=1)
    keep = norm > 1e-12
    n = n[keep] / norm[keep, None]
    a = a[keep]
    d = -np.einsum("ij,ij->i", n, a)
    inside = v.mean(axis=0)
    flip = n @ inside + d > 0
    n[flip] *= -1
    d[flip] *= -1
    return np.column_stack([n, d])


def capsule_spheres(a: np.ndarray, b: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Spheres covering capsules, spaced at half a radius: (S,3) centres, (S,) radii."""
    centres, radii = [], []
    for p, q, rad in zip(a, b, r):
        n = max(2, int(math.ceil(np.linalg.norm(q - p) / (0.5 * rad))) + 1)
        t = np.linspace(0.0, 1.0, n)[:, None]
        centres.append(p + t * (q - p))
        radii.append(np.full(n, rad))
    return np.concatenate(centres), np.concatenate(radii)


@dataclass
class Obstacles:
    """Table plane and object hulls in the robot base frame."""

    table_normal: np.ndarray  # (3,) up
    table_offset: float  # n.x + d = height above the table
    names: tuple[str, ...] = ()
    planes: tuple[np.ndarray, ...] = ()  # (F,4) per object
    boxes: tuple[tuple[np.ndarray, np.ndarray], ...] = ()  # AABB per object
    margin_m: float = 0.01

    def collisions(self, centres: np.ndarray, radii: np.ndarray, ignore: Sequence[str] = ()) -> list[str]:
        """What the spheres touch: "table" and/or object names."""
        hit: list[str] = []
        heights = centres @ self.table_normal + self.table_offset
        if np.any(heights < radii + self.margin_m):
            hit.append("table")
        reach = radii + self.margin_m
        for name, planes, (lo, hi) in zip(self.names, self.planes, self.boxes):
            if name in ignore or len(planes) == 0:
                continue
            near = np.all((centres + reach[:, None] > lo) & (centres - reach[:, None] < hi), axis=1)
            if not np.any(near):
                continue
            # Largest face-plane distance: a lower bound of the true distance, so this
            # errs towards "collides" near the hull's edges and corners.
            dist = np.max(centres[near] @ planes[:, :3].T + planes[:, 3], axis=1)
            if np.any(dist < reach[near]):
                hit.append(name)
        return hit


@dataclass
class PoseCheck:
    ok: bool
    joints: tuple[np.ndarray, ...] = ()
    reason: str = ""


@dataclass
class SequenceChecker:
    """IK + collision check of a gripper pose sequence (pre-pose ... retreat)."""

    kin: WamKinematics
    obstacles: Obstacles
    timings: dict[str, float] = field(default_factory=dict)

    def check(self, poses_base: Sequence[np.ndarray], target: str) -> PoseCheck:
        for i, T in enumerate(poses_base):
            if not self.kin.reachable(T):
                return PoseCheck(False, reason=f"pose {i + 1}/{len(poses_base)} beyond the arm's reach")
        joints: list[np.ndarray] = []
        warm: np.ndarray | None = None
        for i, T in enumerate(poses_base):
            q = self.kin.ik(T, warm)  # the warm start first, then the seeds
            if q is None:
                return PoseCheck(False, reason=f"no IK solution for pose {i + 1}/{len(poses_base)}")
            a, b, r = self.kin.capsules(q)
            centres, radii = capsule_spheres(a, b, r)
            hit = self.obstacles.collisions(centres, radii, ignore=(target,))
            if hit:
                return PoseCheck(False, reason=f"arm collides with {', '.join(hit)} at pose {i + 1}/{len(poses_base)}")
            joints.append(q)
            warm = q
        return PoseCheck(True, tuple(joints))


def make_obstacles(state: Any, T_base_camera: np.ndarray, margin_m: float = 0.01) -> Obstacles:
    """Table and object hulls of a SymbolicState, moved into the base frame."""
    R, t = T_base_camera[:3, :3], T_base_camera[:3, 3]
    n_cam = np.asarray(state.table.normal, dtype=float)
    n = R @ n_cam
    # A point on the table in the camera frame: -d n; moved to the base frame.
    p = R @ (-float(state.table.offset) * n_cam) + t
    names, planes, boxes = [], [], []
    for obj in state.objects:
        v = np.asarray(obj.hull_vertices, dtype=float)
        if len(v) == 0:
            continue
        vb = v @ R.T + t
        names.append(obj.name)
        planes.append(hull_planes(vb, obj.hull_faces))
        boxes.append((vb.min(axis=0), vb.max(axis=0)))
    return Obstacles(n, float(-n @ p), tuple(names), tuple(planes), tuple(boxes), margin_m)
