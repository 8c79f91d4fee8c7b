"""The Barrett WAM's kinematics: forward and inverse kinematics on our URDF (read with
the standard library, computed with NumPy: no Pinocchio, see "the URDF's chain in NumPy"
below), the IK in closed form over the arm's swivel angle, and its collision capsules at
a joint configuration. What the capsules may hit is `clearcli.robot.collision`; what
every arm's kinematics offers, `clearcli.robot.kinematics`.

Frames: ``base`` is the WAM's DH frame 0 at the shoulder (z up, x towards the table by
default placement), ``tcp`` the gripper closing point (z = approach, x = closing
direction), 0.115 m past the tool plate.
"""

from __future__ import annotations

import copy
import functools
import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from clearcli.robot.kinematics import IKStats, SolverAccess, cache_lookup
from clearcli.settings.robot import RobotSettings

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


# -- analytic IK (the DH table of wam_kinematics.md) ------------------------------------
# Joints 1-3 intersect at the shoulder (the base origin) and 5-7 at the wrist centre, and
# each DH pair Rx(-pi/2) Rz(q) Rx(+pi/2) is Ry(q), so
#   R_base_link7 = Rz(q1) Ry(q2) Rz(q3) Ry(q4) Rz(q5) Ry(q6) Rz(q7).
# In the frame A = Rz(q1) Ry(q2) Rz(q3) the elbow (joint 4) is at _UPPER_ARM and the wrist
# centre at v(q4) = _UPPER_ARM + Ry(q4) _FOREARM; the TCP is _WRIST_TO_TCP_M along link 7's
# z (no rotation). Hence |wrist centre| alone fixes q4 (two values, closed form), and what
# is left is the swivel: a turn of the whole arm about the shoulder-to-wrist-centre line.
# At each swivel angle the shoulder (q1..q3) and the wrist (q5..q7) are ZYZ Euler angles,
# two branches each. The solver sweeps the swivel angle and keeps the solutions within
# the joint limits.
_UPPER_ARM = np.array([0.045, 0.0, 0.55])
_FOREARM = np.array([-0.045, 0.0, 0.30])
_WRIST_TO_TCP_M = 0.06 + TCP_PAST_TOOL_PLATE_M
# |v(q4)|^2 = _K0 + 2 (_P cos q4 + _Q sin q4) = _K0 + 2 _RHO cos(q4 - _PHI)
_K0 = float(_UPPER_ARM @ _UPPER_ARM + _FOREARM @ _FOREARM)
_P = float(_UPPER_ARM[0] * _FOREARM[0] + _UPPER_ARM[2] * _FOREARM[2])
_Q = float(_UPPER_ARM[0] * _FOREARM[2] - _UPPER_ARM[2] * _FOREARM[0])
_RHO = math.hypot(_P, _Q)
_PHI = math.atan2(_Q, _P)
_TWO_PI = 2.0 * math.pi
# Swivel sweep: a ring of angles plus, per elbow angle, the one that puts the elbow
# nearest the reference's (the warm start's, else the rest shape's); a dense ring only
# when that finds no solution within the limits. Top-down poses over the table have a wide
# swivel range (12 angles found a solution for all of 2000 FK-generated ones).
_SWIVEL_COARSE = 36
_SWIVEL_DENSE = 720
_COARSE_PSI = np.linspace(-math.pi, math.pi, _SWIVEL_COARSE, endpoint=False)
_DENSE_PSI = np.linspace(-math.pi, math.pi, _SWIVEL_DENSE, endpoint=False)
_COARSE_BASIS = np.column_stack([np.ones(_SWIVEL_COARSE), np.sin(_COARSE_PSI), 1.0 - np.cos(_COARSE_PSI)])
_DENSE_BASIS = np.column_stack([np.ones(_SWIVEL_DENSE), np.sin(_DENSE_PSI), 1.0 - np.cos(_DENSE_PSI)])
# A pose whose exact solutions all miss the limits by less than this (summed over the
# joints, radians) gets damped least squares from the nearest one: the tolerances may
# still let it in. Near misses are rare (a thin band at the edge of the workspace).
_NEAR_MISS_RAD = 0.05
# ...for at most this many iterations (the successes on the benchmark's poses took 0-7).
_NEAR_MISS_ITERATIONS = 30
# Where a solution exists, damped least squares first tracks it from the warm start (else
# from the rest shape) for at most this many iterations: that is the solution the seeded
# solver found before, which the planner's collision checks were tuned on (taking the
# exact solution nearest the start instead found 72 instead of 81 of 90 actions clear of
# collisions in three clutter scenes). From these starts it converged within 12
# iterations on every planner pose seen; the swivel sweep answers where it does not.
_TRACK_ITERATIONS = 20
# The reference posture when there is no warm start: the first of the DLS seeds, the
# arm turned towards the target, leaning forward, elbow bent up, wrist in line.
_REST_SHAPE = (0.9, 0.0, 1.6, 0.0, 0.6, 0.0)


def _rot_y(t: float) -> np.ndarray:
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rot_z(t: float) -> np.ndarray:
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _elbow_position(q: np.ndarray) -> np.ndarray:
    """Joint 4's origin (base frame) at joint angles q: Rz(q1) Ry(q2) Rz(q3) _UPPER_ARM."""
    c1, s1, c2, s2, c3, s3 = (f(q[i]) for i in (0, 1, 2) for f in (math.cos, math.sin))
    x, y, z = _UPPER_ARM[0] * c3, _UPPER_ARM[0] * s3, _UPPER_ARM[2]
    x, z = x * c2 + z * s2, -x * s2 + z * c2
    return np.array([x * c1 - y * s1, x * s1 + y * c1, z])


def dh_fk(q: np.ndarray) -> np.ndarray:
    """T_base_tcp from the DH table (what the analytic IK inverts); equals ``fk`` on our
    URDF (checked when a WamKinematics is built)."""
    R = _rot_z(q[0]) @ _rot_y(q[1]) @ _rot_z(q[2])
    W = R @ _UPPER_ARM
    R = R @ _rot_y(q[3])
    W = W + R @ _FOREARM
    R = R @ _rot_z(q[4]) @ _rot_y(q[5]) @ _rot_z(q[6])
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = W + _WRIST_TO_TCP_M * R[:, 2]
    return T


# -- the URDF's chain in NumPy ----------------------------------------------------------
# Forward kinematics, the TCP's Jacobian and the pose error are computed here, not by
# Pinocchio: importing Pinocchio (its C++ bindings, and coal's) was 0.1-0.45 s of every
# cold `clear plan` on this project's machines (issue 39), for a chain of seven revolute
# joints whose solver needs a few dozen of these products per plan. The formulas are
# Pinocchio's (rpy = Rz(y) Ry(p) Rx(r) as in URDF, joint placements, the LOCAL frame
# Jacobian, log6 with its Taylor branches), so the results agree with it to rounding
# (tests/robot/test_kinematics.py checks them against Pinocchio on random configurations).
_EPS = float(np.finfo(float).eps)
_PREC2 = _EPS ** (1.0 / 3.0)  # Pinocchio's TaylorSeriesExpansion<double>::precision<2>()


def _rpy(r: float, p: float, y: float) -> np.ndarray:
    """URDF's rpy as a rotation: Rz(y) Ry(p) Rx(r)."""
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    Rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    Ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    Rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    return Rz @ Ry @ Rx


def _origin(joint: ET.Element) -> np.ndarray:
    """A joint's <origin> as a 4x4 pose of its frame in its parent link's."""
    T = np.eye(4)
    origin = joint.find("origin")
    if origin is not None:
        T[:3, :3] = _rpy(*(float(v) for v in origin.get("rpy", "0 0 0").split()))
        T[:3, 3] = [float(v) for v in origin.get("xyz", "0 0 0").split()]
    return T


class _UrdfChain:
    """The serial chain of a URDF whose movable joints are revolute about their z axis
    (the WAM's): per joint its placement in the previous joint's frame, its limits; per
    link (and joint) name the joint it hangs from and its placement in that joint's frame."""

    def __init__(self, urdf: Path) -> None:
        root = ET.parse(urdf).getroot()
        by_parent = {j.find("parent").get("link"): j for j in root.iter("joint")}  # type: ignore[union-attr]  # URDF joints have a <parent>
        children = {j.find("child").get("link") for j in root.iter("joint")}  # type: ignore[union-attr]
        link = next(str(k.get("name")) for k in root.iter("link") if k.get("name") not in children)
        self.root_link = link
        self.placements: list[np.ndarray] = []  # joint i in joint i-1's frame (the root's for 0)
        self.names: list[str] = []
        lower, upper = [], []
        # frame name -> (index of the joint it hangs from, -1 for the root; its placement there)
        self.frames: dict[str, tuple[int, np.ndarray]] = {link: (-1, np.eye(4))}
        since = np.eye(4)  # the fixed transforms since the last revolute joint
        while link in by_parent:
            joint = by_parent[link]
            T = since @ _origin(joint)
            kind, name = joint.get("type"), str(joint.get("name"))
            link = str(joint.find("child").get("link"))  # type: ignore[union-attr]
            if kind == "fixed":
                since = T
                self.frames[name] = self.frames[link] = (len(self.names) - 1, T)
                continue
            axis = joint.find("axis")
            xyz = [float(v) for v in (axis.get("xyz", "1 0 0") if axis is not None else "1 0 0").split()]
            if kind != "revolute" or xyz != [0.0, 0.0, 1.0]:
                raise ValueError(f"{urdf}: joint {name!r}: only revolute joints about z are modelled here")
            limit = joint.find("limit")
            assert limit is not None  # a revolute joint has limits (urdf_joints checks)
            lower.append(float(limit.get("lower", "0")))
            upper.append(float(limit.get("upper", "0")))
            self.placements.append(T)
            self.names.append(name)
            since = np.eye(4)
            self.frames[name] = self.frames[link] = (len(self.names) - 1, np.eye(4))
        self.lower = np.array(lower)
        self.upper = np.array(upper)
        self._placements = np.array(self.placements)

    def joint_poses(self, q: np.ndarray) -> np.ndarray:
        """Each joint's frame in the root's at q, (n, 4, 4): Pinocchio's oMi[1:]. (The
        placements turned by their angles at once: this runs in every solver iteration.)"""
        q = np.asarray(q, dtype=float)
        c, s = np.cos(q)[:, None], np.sin(q)[:, None]
        P = self._placements
        local = P.copy()
        local[:, :, 0] = P[:, :, 0] * c + P[:, :, 1] * s  # placement @ Rz(q)
        local[:, :, 1] = P[:, :, 1] * c - P[:, :, 0] * s
        out = np.empty_like(local)
        out[0] = local[0]
        for i in range(1, len(local)):
            np.matmul(out[i - 1], local[i], out=out[i])
        return out

    def frame_pose(self, poses: np.ndarray, frame: str) -> np.ndarray:
        """A frame's pose in the root's, given `joint_poses`."""
        joint, placement = self.frames[frame]
        return placement if joint < 0 else poses[joint] @ placement


def _log3(R: list[list[float]]) -> tuple[float, float, float, float]:
    """Pinocchio's log3 (its renormalisation, its branches): the rotation vector of R
    (rows, plain floats: 3x3 NumPy products cost more than they compute here) and its
    angle."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R
    n0 = math.sqrt(r00 * r00 + r10 * r10 + r20 * r20)
    n1 = math.sqrt(r01 * r01 + r11 * r11 + r21 * r21)
    a0, a1, a2 = r00 / n0, r10 / n0, r20 / n0
    b0, b1, b2 = r01 / n1, r11 / n1, r21 / n1
    c0, c1, c2 = a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0  # col 2 = col 0 x col 1
    a0, a1, a2 = b1 * c2 - b2 * c1, b2 * c0 - b0 * c2, b0 * c1 - b1 * c0  # col 0 = col 1 x col 2
    Rn = ((a0, b0, c0), (a1, b1, c1), (a2, b2, c2))
    tr = a0 + b1 + c2
    cos_value = (tr - 1.0) / 2.0
    if cos_value < -1.0 + _PREC2:
        return _log3_near_pi(Rn, tr)
    acos_expansion = math.sqrt(2.0 * (1.0 - cos_value) + _EPS * _EPS)
    theta = math.acos(cos_value) if tr <= 3.0 - _PREC2 else acos_expansion
    u0, u1, u2 = 0.5 * (b2 - c1), 0.5 * (c0 - a2), 0.5 * (a1 - b0)  # unSkew(Rn)
    if theta >= _PREC2:
        t = theta / math.sin(theta)
    else:
        n2 = u0 * u0 + u1 * u1 + u2 * u2
        t = 1.0 + n2 / 6.0 + n2 * n2 * 3.0 / 40.0
    return t * u0, t * u1, t * u2, theta


def _log3_near_pi(Rn: tuple[tuple[float, ...], ...], tr: float) -> tuple[float, float, float, float]:
    """Pinocchio's log3 near a half turn (compute_theta_axis on the largest diagonal term)."""
    val = [2.0 * Rn[k][k] - tr + 1.0 for k in range(3)]
    if val[0] >= val[1]:
        i0 = 0 if val[0] >= val[2] else 2
    else:
        i0 = 1 if val[1] >= val[2] else 2
    i1, i2 = (i0 + 1) % 3, (i0 + 2) % 3
    s = math.sqrt(val[i0] + _EPS + _EPS * _EPS) * (1.0 if Rn[i2][i1] >= Rn[i1][i2] else -1.0)
    axis = [0.0, 0.0, 0.0]
    axis[i0] = s / 2.0
    axis[i1] = 1.0 / (2.0 * s) * (Rn[i1][i0] + Rn[i0][i1])
    axis[i2] = 1.0 / (2.0 * s) * (Rn[i2][i0] + Rn[i0][i2])
    w = 1.0 / (2.0 * s) * (Rn[i2][i1] - Rn[i1][i2])
    norm = math.sqrt(axis[0] ** 2 + axis[1] ** 2 + axis[2] ** 2)
    angle = 2.0 * math.atan2(norm, w)
    return angle * axis[0] / norm, angle * axis[1] / norm, angle * axis[2] / norm, angle


def _log6_rows(R: list[list[float]], p: list[float]) -> list[float]:
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R
    u0, u1, u2 = 0.5 * (r21 - r12), 0.5 * (r02 - r20), 0.5 * (r10 - r01)
    t2 = u0 * u0 + u1 * u1 + u2 * u2
    tr = r00 + r11 + r22
    w0, w1, w2, theta = _log3(R)
    if tr >= 3.0 - _PREC2:
        alpha = 1.0 - t2 / 12.0 - t2 * t2 / 720.0
        beta = 1.0 / 12.0 + t2 / 720.0
    else:
        st, ct = math.sin(theta), math.cos(theta)
        alpha = theta * st / (2.0 * (1.0 - ct))
        beta = 1.0 / (theta * theta) - st / (2.0 * theta * (1.0 - ct))
    p0, p1, p2 = p
    bwp = beta * (w0 * p0 + w1 * p1 + w2 * p2)
    return [
        alpha * p0 - 0.5 * (w1 * p2 - w2 * p1) + bwp * w0,
        alpha * p1 - 0.5 * (w2 * p0 - w0 * p2) + bwp * w1,
        alpha * p2 - 0.5 * (w0 * p1 - w1 * p0) + bwp * w2,
        w0,
        w1,
        w2,
    ]


def _error(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """log6(A^-1 B) for rigid poses (Pinocchio's log6(A.actInv(B))): B seen from A."""
    a, b = A.tolist(), B.tolist()
    R = [[sum(a[k][i] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    d = [b[k][3] - a[k][3] for k in range(3)]
    p = [a[0][i] * d[0] + a[1][i] * d[1] + a[2][i] * d[2] for i in range(3)]
    return np.array(_log6_rows(R, p))


def _dh_error_and_jacobian(q: np.ndarray, target: list[list[float]]) -> tuple[list[float], list[list[float]]]:
    """The damped least squares' step inputs on the DH arm, in plain floats: the pose
    error log6(T_base_tcp(q)^-1 target) and the TCP's Jacobian in its own frame (rows v
    then w, 6 x 7), for ``target`` a T_base_tcp's rows. The same values as the URDF
    chain's (`_error`, `_tcp_jacobian`) to rounding, about five times faster: this is
    the solver's inner loop (a plan runs it a few hundred times)."""
    q1, q2, q3, q4, q5, q6, q7 = q.tolist()

    def turn_z(x: tuple[float, ...], y: tuple[float, ...], t: float) -> tuple[tuple[float, ...], ...]:
        c, s = math.cos(t), math.sin(t)
        return (
            (c * x[0] + s * y[0], c * x[1] + s * y[1], c * x[2] + s * y[2]),
            (c * y[0] - s * x[0], c * y[1] - s * x[1], c * y[2] - s * x[2]),
        )

    def turn_y(x: tuple[float, ...], z: tuple[float, ...], t: float) -> tuple[tuple[float, ...], ...]:
        c, s = math.cos(t), math.sin(t)
        return (
            (c * x[0] - s * z[0], c * x[1] - s * z[1], c * x[2] - s * z[2]),
            (s * x[0] + c * z[0], s * x[1] + c * z[1], s * x[2] + c * z[2]),
        )

    # R = Rz(q1) Ry(q2) Rz(q3) Ry(q4) Rz(q5) Ry(q6) Rz(q7) by its columns x, y, z; joint
    # i turns about the column its factor leaves fixed, through the shoulder (joints
    # 1-3), the elbow (4) or the wrist centre (5-7)
    x: tuple[float, ...] = (1.0, 0.0, 0.0)
    y: tuple[float, ...] = (0.0, 1.0, 0.0)
    z: tuple[float, ...] = (0.0, 0.0, 1.0)
    axes = [z]
    x, y = turn_z(x, y, q1)
    axes.append(y)
    x, z = turn_y(x, z, q2)
    axes.append(z)
    x, y = turn_z(x, y, q3)
    ux, uz = float(_UPPER_ARM[0]), float(_UPPER_ARM[2])
    elbow = (ux * x[0] + uz * z[0], ux * x[1] + uz * z[1], ux * x[2] + uz * z[2])
    axes.append(y)
    x, z = turn_y(x, z, q4)
    fx, fz = float(_FOREARM[0]), float(_FOREARM[2])
    wrist = tuple(elbow[k] + fx * x[k] + fz * z[k] for k in range(3))
    axes.append(z)
    x, y = turn_z(x, y, q5)
    axes.append(y)
    x, z = turn_y(x, z, q6)
    axes.append(z)
    x, y = turn_z(x, y, q7)
    tcp = [wrist[k] + _WRIST_TO_TCP_M * z[k] for k in range(3)]
    origin = (0.0, 0.0, 0.0)
    J: list[list[float]] = [[], [], [], [], [], []]
    for a, at in zip(axes, (origin, origin, origin, elbow, wrist, wrist, wrist)):
        d0, d1, d2 = tcp[0] - at[0], tcp[1] - at[1], tcp[2] - at[2]
        v = (a[1] * d2 - a[2] * d1, a[2] * d0 - a[0] * d2, a[0] * d1 - a[1] * d0)
        for row, col in enumerate((x, y, z)):
            J[row].append(col[0] * v[0] + col[1] * v[1] + col[2] * v[2])
            J[row + 3].append(col[0] * a[0] + col[1] * a[1] + col[2] * a[2])
    cols = (x, y, z)
    R = [
        [cols[i][0] * target[0][j] + cols[i][1] * target[1][j] + cols[i][2] * target[2][j] for j in range(3)]
        for i in range(3)
    ]
    d = [target[k][3] - tcp[k] for k in range(3)]
    p = [cols[i][0] * d[0] + cols[i][1] * d[1] + cols[i][2] * d[2] for i in range(3)]
    return _log6_rows(R, p), J


def _act_inv(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """A^-1 B for rigid poses (Pinocchio's A.actInv(B))."""
    out = np.eye(4)
    out[:3, :3] = A[:3, :3].T @ B[:3, :3]
    out[:3, 3] = A[:3, :3].T @ (B[:3, 3] - A[:3, 3])
    return out


class WamKinematics(SolverAccess):
    """The WAM model loaded from ``wam.urdf`` with joint limits from the manual."""

    def __init__(
        self,
        damping: float | None = None,
        max_iterations: int | None = None,
        tolerance_m: float | None = None,
        tolerance_rad: float | None = None,
        n_seeds: int | None = None,
    ) -> None:
        """The IK search's bounds; None: [robot]'s (clearcli/settings/robot.py, their one
        home; a profile passes a user's: `kinematics_of_wam`)."""
        robot = RobotSettings()
        damping = robot.ik_damping if damping is None else damping
        max_iterations = robot.ik_max_iterations if max_iterations is None else max_iterations
        tolerance_m = robot.ik_tolerance_m if tolerance_m is None else tolerance_m
        tolerance_rad = robot.ik_tolerance_rad if tolerance_rad is None else tolerance_rad
        n_seeds = robot.ik_seeds if n_seeds is None else n_seeds

        self.chain = _chain(URDF_PATH)
        self.joint_names = tuple(self.chain.names)
        self.lower = self.chain.lower.copy()
        self.upper = self.chain.upper.copy()
        self.damping = float(damping)
        self.max_iterations = int(max_iterations)
        self.tolerance_m = float(tolerance_m)
        self.tolerance_rad = float(tolerance_rad)
        self.n_seeds = max(1, int(n_seeds))
        self.stats = IKStats()
        self._cache: dict[bytes, np.ndarray | None] = {}
        # The chain's root is the URDF's (the footprint); our poses are in the base
        # (shoulder) frame, 0.346 m above it. (4x4 poses: T_root_base and its inverse.)
        n = len(self.joint_names)
        self.M_root_base = self.chain.frame_pose(self.chain.joint_poses(np.zeros(n)), BASE_FRAME)
        self.M_base_root = _act_inv(self.M_root_base, np.eye(4))
        # The analytic IK inverts the DH table: use it only if the URDF is that arm (it
        # is; a changed wam.urdf falls back to damped least squares from seeds alone).
        rng = np.random.default_rng(0)
        self.analytic = all(
            np.allclose(dh_fk(q), self.fk(q), atol=1e-9) for q in rng.uniform(self.lower, self.upper, size=(8, n))
        )
        # the limits of the shoulder's and the wrist's ZYZ angles (see swivel_sweep)
        lo = np.stack([self.lower[0:3], self.lower[4:7]], axis=-1).reshape(3, 1, 1, 1, 2)
        hi = np.stack([self.upper[0:3], self.upper[4:7]], axis=-1).reshape(3, 1, 1, 1, 2)
        self._euler_mid = 0.5 * (lo + hi)
        self._euler_half = 0.5 * (hi - lo)
        self._euler_mid_less_pi = self._euler_mid - math.pi
        # The wrist centre's distance from the shoulder over the elbow's range: longest
        # at q4 = _PHI (the offsets in line), shortest at the limit farthest from it.
        lo4, hi4 = float(self.lower[3]), float(self.upper[3])

        def wrist_distance(q4: float) -> float:
            return math.sqrt(_K0 + 2.0 * _RHO * math.cos(q4 - _PHI))

        self._q4_stretched = min(max(_PHI, lo4), hi4)
        self._q4_folded = min((lo4, hi4), key=wrist_distance)
        self._w_max = wrist_distance(self._q4_stretched)
        self._w_min = wrist_distance(self._q4_folded)
        # damped least squares iterations from the warm start / rest shape before the
        # swivel sweep (0: the sweep alone, the exact solution nearest the start)
        self.track_iterations = _TRACK_ITERATIONS

    # -- forward kinematics ---------------------------------------------------------
    def fk(self, q: np.ndarray, frame: str | None = None) -> np.ndarray:
        """T_base_<frame> (4x4) at joint angles q (7,); the TCP by default (a frame: a
        link's or a joint's name)."""
        poses = self.chain.joint_poses(q)
        return self.M_base_root @ self.chain.frame_pose(poses, TCP_FRAME if frame is None else frame)

    def capsules(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Arm capsules at q: (C,3) start points, (C,3) end points, (C,) radii (base frame)."""
        poses = self.chain.joint_poses(q)
        # joint indices from 1 (Pinocchio's, as in _CAPSULES); -1 the tool plate
        plate = self.chain.frame_pose(poses, TOOL_PLATE_FRAME)[:3, 3]
        a = np.array([poses[i - 1][:3, 3] for i, _, _ in _CAPSULES])
        b = np.array([plate if j < 0 else poses[j - 1][:3, 3] for _, j, _ in _CAPSULES])
        R, t = self.M_base_root[:3, :3], self.M_base_root[:3, 3]
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

    def _solve_from(self, target: Any, q0: np.ndarray, iterations: int | None = None) -> np.ndarray | None:
        """Damped least squares from q0 (clipped to the limits at every step), for
        ``iterations`` (default ``max_iterations``)."""
        lo, hi = self.lower, self.upper
        tol_m2, tol_rad2 = self.tolerance_m**2, self.tolerance_rad**2
        q = q0.copy()
        damp = self.damping**2 * np.eye(6)
        self.stats.starts += 1
        n_it = self.max_iterations if iterations is None else int(iterations)
        target_base = (self.M_base_root @ target).tolist() if self.analytic else None
        for it in range(n_it):
            if target_base is not None:  # the DH arm: its formulas in plain floats
                err_list, J_list = _dh_error_and_jacobian(q, target_base)
                vx, vy, vz, wx, wy, wz = err_list
            else:
                poses = self.chain.joint_poses(q)
                T_root_tcp = self.chain.frame_pose(poses, TCP_FRAME)
                vx, vy, vz, wx, wy, wz = err_list = _error(T_root_tcp, target).tolist()  # log6, in the TCP frame
            if vx * vx + vy * vy + vz * vz < tol_m2 and wx * wx + wy * wy + wz * wz < tol_rad2:
                self.stats.iterations += it
                return q
            J = np.array(J_list) if target_base is not None else self._tcp_jacobian(poses, T_root_tcp)
            err = np.array(err_list)
            dq = J.T @ np.linalg.solve(J @ J.T + damp, err)
            step = float(np.abs(dq).max())
            if step > 0.4:  # keep the linearisation honest far from the target
                dq *= 0.4 / step
            q = np.minimum(np.maximum(q + dq, lo), hi)
        self.stats.iterations += n_it
        return None

    @staticmethod
    def _tcp_jacobian(poses: np.ndarray, T_root_tcp: np.ndarray) -> np.ndarray:
        """The TCP's Jacobian (6, 7) in its own frame (Pinocchio's LOCAL frame Jacobian:
        rows v then w), from the joints' poses: joint i turns about its z axis a_i at p_i,
        moving the TCP by a_i x (p_tcp - p_i)."""
        A = poses[:, :3, 2].T  # (3, n)
        D = T_root_tcp[:3, 3:4] - poses[:, :3, 3].T
        cross = np.array([A[1] * D[2] - A[2] * D[1], A[2] * D[0] - A[0] * D[2], A[0] * D[1] - A[1] * D[0]])
        Rt = T_root_tcp[:3, :3].T
        J = np.empty((6, poses.shape[0]))
        J[:3] = Rt @ cross
        J[3:] = Rt @ A
        return J

    def target(self, T_base_tcp: np.ndarray) -> np.ndarray:
        """``T_base_tcp`` as the solvers' target: T_root_tcp (4x4), in the chain's root."""
        return self.M_root_base @ np.asarray(T_base_tcp, dtype=float)

    def within_tolerance(self, target: Any, q: np.ndarray) -> bool:
        """q within the joint limits puts the TCP on ``target`` within the tolerances."""
        if np.any(q < self.lower) or np.any(q > self.upper):
            return False
        vx, vy, vz, wx, wy, wz = self.pose_error(target, q).tolist()
        return (
            math.sqrt(vx * vx + vy * vy + vz * vz) < self.tolerance_m
            and math.sqrt(wx * wx + wy * wy + wz * wz) < self.tolerance_rad
        )

    def pose_error(self, target: Any, q: np.ndarray) -> np.ndarray:
        """The TCP's pose error at q against the target (log6, 6 values, in the TCP frame)."""
        if self.analytic:  # the DH arm's floats, as in the solver (the simulated world's least squares)
            return np.array(_dh_error_and_jacobian(np.asarray(q, dtype=float), (self.M_base_root @ target).tolist())[0])
        T_root_tcp = self.chain.frame_pose(self.chain.joint_poses(q), TCP_FRAME)
        return _error(T_root_tcp, target)

    def fresh(self) -> WamKinematics:
        """A new IK search on this model: the same arm and settings, an empty cache and
        statistics (as if built again, without reading the URDF)."""
        out = copy.copy(self)
        out.stats = IKStats()
        out._cache = {}
        return out

    def elbow_angles(self, T_base_tcp: np.ndarray) -> list[float]:
        """The elbow angles q4 (0, 1 or 2) within the limits that put the wrist centre of
        ``T_base_tcp`` at its distance from the shoulder: none means no exact solution."""
        R, p = T_base_tcp[:3, :3], T_base_tcp[:3, 3]
        W = p - _WRIST_TO_TCP_M * R[:, 2]
        x = 0.5 * (float(W @ W) - _K0) / _RHO  # cos(q4 - _PHI)
        if not -1.0 <= x <= 1.0:
            return []
        acs = math.acos(x)
        both = (_PHI + acs, _PHI - acs) if acs > 0.0 else (_PHI,)
        return [q4 for q4 in both if self.lower[3] <= q4 <= self.upper[3]]

    def _into_reach(self, T_base_tcp: np.ndarray) -> np.ndarray | None:
        """A pose within the tolerances of ``T_base_tcp`` whose wrist centre is at a
        distance from the shoulder that the elbow's limits allow, when the wrist centre
        of ``T_base_tcp`` is just outside: the TCP moved along the shoulder-to-wrist line
        and the tool tilted about the TCP, each by up to 0.9 of its tolerance, the gap
        shared in proportion. None when that is not enough."""
        R, p = T_base_tcp[:3, :3], T_base_tcp[:3, 3]
        z = R[:, 2]
        d = _WRIST_TO_TCP_M
        W = p - d * z
        w = math.sqrt(float(W @ W))
        margin = 0.9 * (self.tolerance_m + d * self.tolerance_rad)  # what the tolerances make up
        if not (self._w_max < w <= self._w_max + margin or self._w_min - margin <= w < self._w_min):
            return None
        eps = 1e-6
        goal = min(max(w, self._w_min + eps), self._w_max - eps)
        # share the gap between the two tolerances in proportion
        shift = (goal - w) / margin * 0.9 * self.tolerance_m
        p = p + shift * (W / w)
        # Tilt z about u = z x W / |z x W| (the fastest way to change |W|): z(t) =
        # cos t z + sin t (u x z), and |p - d z(t)|^2 = |p|^2 + d^2 - 2 d p.z(t).
        u = np.cross(z, W)
        un = float(np.linalg.norm(u))
        if un < 1e-9:
            return None
        u = u / un
        uz = np.cross(u, z)
        a, b = float(p @ z), float(p @ uz)
        need = (float(p @ p) + d * d - goal * goal) / (2.0 * d)  # = a cos t + b sin t
        amp = math.hypot(a, b)
        if amp < 1e-12 or abs(need) > amp:
            return None
        base, off = math.atan2(b, a), math.acos(need / amp)
        t = min((base + off, base - off), key=lambda x: abs(math.remainder(x, _TWO_PI)))
        t = math.remainder(t, _TWO_PI)
        if abs(t) > 0.9 * self.tolerance_rad:
            return None
        # rotate the whole tool frame by t about u (Rodrigues)
        Ku = np.array([[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]])
        Ru = np.eye(3) + math.sin(t) * Ku + (1.0 - math.cos(t)) * (Ku @ Ku)
        out = np.eye(4)
        out[:3, :3] = Ru @ R
        out[:3, 3] = p
        return out

    def swivel_sweep(
        self,
        T_base_tcp: np.ndarray,
        q4s: Sequence[float],
        psi: np.ndarray,
        basis: np.ndarray | None = None,
        toward: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray, int]:
        """The exact solutions with elbow angle in ``q4s`` at swivel angles ``psi``, as
        ZYZ Euler angles of the shoulder and of the wrist.

        Returns Z (3, 2, N, K, 2): Z[e, branch, psi, q4, part] is Euler angle e (a, b, g)
        of the shoulder (part 0: q1, q2, q3) or of the wrist (part 1: q5, q6, q7) in one of
        its two branches, as the turn nearest the middle of its joint's limits; and V (2,
        N, K, 2), how far those three angles are outside their limits (radians, summed; 0
        = within). Any shoulder branch goes with any wrist branch at the same (psi, q4).
        Swivel 0 puts the arm's plane (shoulder, elbow, wrist centre) vertical, through the
        shoulder's axis. ``basis``: the rows (1, sin psi, 1 - cos psi), if known.
        ``toward``: an elbow position (base frame); for each q4 the swivel angle that
        brings the elbow nearest it is added after ``psi``. The third value returned is
        N, the number of swivel angles used."""
        self.stats.sweeps += 1
        R = T_base_tcp[:3, :3]
        wx, wy, wz = (T_base_tcp[:3, 3] - _WRIST_TO_TCP_M * R[:, 2]).tolist()
        w = math.sqrt(wx * wx + wy * wy + wz * wz)
        wx, wy, wz = wx / w, wy / w, wz / w
        nn = math.hypot(wx, wy)
        n1x, n1y = (-wy / nn, wx / nn) if nn > 1e-9 else (0.0, 1.0)
        # the arm's frame at swivel 0: (wc, n1, wc x n1) as columns
        F0 = np.array([[wx, n1x, -wz * n1y], [wy, n1y, wz * n1x], [wz, 0.0, wx * n1y - wy * n1x]])
        Kw = np.array([[0.0, -wz, wy], [wz, 0.0, -wx], [-wy, wx, 0.0]])
        # The shoulder's A(psi) = Rz(q1) Ry(q2) Rz(q3) = Rot(wc, psi) A0 = A0 +
        # sin(psi) Kw A0 + (1 - cos(psi)) Kw^2 A0 (Rodrigues), and the wrist's
        # Rz(q5) Ry(q6) Rz(q7) = Ry(q4)^T A(psi)^T R: both linear in (1, sin, 1 - cos).
        k, n0 = len(q4s), len(psi)
        n = n0 + (k if toward is not None else 0)
        coef = np.empty((3, k, 2, 3, 3))
        rows = np.empty((n, 3))
        rows[:n0] = np.column_stack([np.ones(n0), np.sin(psi), 1.0 - np.cos(psi)]) if basis is None else basis
        for i, q4 in enumerate(q4s):
            c4, s4 = math.cos(q4), math.sin(q4)
            vx = _UPPER_ARM[0] + c4 * _FOREARM[0] + s4 * _FOREARM[2]
            vz = _UPPER_ARM[2] + c4 * _FOREARM[2] - s4 * _FOREARM[0]
            vn = math.hypot(vx, vz)
            vx, vz = vx / vn, vz / vn
            # A0 maps the arm's frame in A's coordinates, rows (v, y, v x y), onto F0
            A0 = F0 @ np.array([[vx, 0.0, vz], [0.0, 1.0, 0.0], [-vz, 0.0, vx]])
            X = Kw @ A0
            coef[0, i, 0] = A0
            coef[1, i, 0] = X
            coef[2, i, 0] = Kw @ X
            coef[:, i, 1] = _rot_y(-q4) @ np.swapaxes(coef[:, i, 0], 1, 2) @ R
            if toward is not None:
                # elbow(psi) = (A0 + sin X + (1 - cos) Kw X) _UPPER_ARM is nearest
                # ``toward`` where sin(psi) s1 - cos(psi) s2 is largest
                s1, s2 = (coef[1:, i, 0] @ _UPPER_ARM @ toward).tolist()
                e = math.atan2(s1, -s2)
                rows[n0 + i] = (1.0, math.sin(e), 1.0 - math.cos(e))
        M = (rows @ coef.reshape(3, -1)).reshape(n, k, 2, 3, 3)  # rotations, all psi
        # ZYZ: M = Rz(a) Ry(b) Rz(g); branch 2 is (a + pi, -b, g + pi). With b = 0 only
        # a + g is fixed (a = 0 then); b = pi is outside both q2's and q6's limits.
        sb = np.hypot(M[..., 0, 2], M[..., 1, 2])
        Z = np.empty((3, 2, n, k, 2))
        Z[0, 0] = np.arctan2(M[..., 1, 2], M[..., 0, 2])
        Z[1, 0] = np.arctan2(sb, M[..., 2, 2])
        Z[2, 0] = np.arctan2(M[..., 2, 1], -M[..., 2, 0])
        flat = sb < 1e-9
        if flat.any():
            Z[0, 0][flat] = 0.0
            Z[2, 0][flat] = np.arctan2(M[..., 1, 0], M[..., 0, 0])[flat]
        Z[0::2, 1] = Z[0::2, 0] + math.pi
        Z[1, 1] = -Z[1, 0]
        # Each angle as the turn nearest the middle of its limits, r in [-pi, pi) from it
        # (the same angle for a and g; b is in [-pi, pi] already): outside the limits by
        # |r| - half their width.
        r = np.mod(Z - self._euler_mid_less_pi, _TWO_PI) - math.pi
        V = np.maximum(np.abs(r) - self._euler_half, 0.0).sum(axis=0)
        Z = r + self._euler_mid
        return Z, V, n

    @staticmethod
    def _joints(Z: np.ndarray, q4s: Sequence[float], idx: tuple[int, ...]) -> np.ndarray:
        """The joint angles of candidate (shoulder branch, wrist branch, psi, q4)."""
        i, j, m, kk = idx
        return np.array([*Z[:, i, m, kk, 0], q4s[kk], *Z[:, j, m, kk, 1]])

    def _ik_analytic(self, T: np.ndarray, warm: np.ndarray | None) -> np.ndarray | None:
        q4s = self.elbow_angles(T)
        target = None
        if not q4s:
            # The wrist centre too far from (or too near) the shoulder for the elbow; a
            # pose within the tolerances may still do.
            T_in = self._into_reach(T)
            if T_in is None:
                return None
            target = self.target(T)
            T, q4s = T_in, self.elbow_angles(T_in)
            if not q4s:
                return None
        if target is None:
            target = self.target(T)
        if warm is not None:
            ref = np.clip(warm, self.lower, self.upper)
        else:
            az = math.atan2(T[1, 3], T[0, 3])
            ref = np.clip(np.array([az, *_REST_SHAPE]), self.lower, self.upper)
        if self.track_iterations > 0:
            q = self._solve_from(target, ref, min(self.max_iterations, self.track_iterations))
            if q is not None:
                return q
        elbow = _elbow_position(ref)
        for psi, basis in ((_COARSE_PSI, _COARSE_BASIS), (_DENSE_PSI, _DENSE_BASIS)):
            Z, V, n_psi = self.swivel_sweep(T, q4s, psi, basis, toward=elbow)
            ok = V == 0.0
            if (ok[..., 0].any(axis=0) & ok[..., 1].any(axis=0)).any():
                # (within the limits but for rounding)
                q = np.clip(self._joints(Z, q4s, self._best(Z, ok, q4s, ref)), self.lower, self.upper)
                if self.within_tolerance(target, q):
                    return q
                return self._solve_from(target, q)  # numerically off (not seen): polish it
        # No exact solution within the limits: damped least squares from the nearest
        # misses (at most two), which the tolerances may still let in.
        miss = (V[:, None, ..., 0] + V[None, :, ..., 1]).ravel()
        for flat in np.argsort(miss, kind="stable")[:2]:
            if miss[flat] >= _NEAR_MISS_RAD:
                break
            idx = tuple(int(x) for x in np.unravel_index(flat, (2, 2, n_psi, len(q4s))))
            q0 = np.clip(self._joints(Z, q4s, idx), self.lower, self.upper)
            q = self._solve_from(target, q0, min(self.max_iterations, _NEAR_MISS_ITERATIONS))
            if q is not None:
                return q
        return None

    def _best(self, Z: np.ndarray, ok: np.ndarray, q4s: Sequence[float], ref: np.ndarray) -> tuple[int, ...]:
        """The candidate (shoulder branch, wrist branch, psi, q4) within the limits
        nearest ``ref`` (squared joint distance)."""
        r = np.empty((3, 1, 1, 1, 2))
        r[:, 0, 0, 0, 0] = ref[0:3]
        r[:, 0, 0, 0, 1] = ref[4:7]
        d = np.where(ok, ((Z - r) ** 2).sum(axis=0), np.inf)  # (2, N, K, 2)
        total = d[:, None, ..., 0] + d[None, :, ..., 1] + (np.asarray(q4s) - ref[3]) ** 2
        return tuple(int(x) for x in np.unravel_index(int(np.argmin(total)), total.shape))

    def ik(self, T_base_tcp: np.ndarray, warm: np.ndarray | None = None) -> np.ndarray | None:
        """Joint angles putting the TCP at ``T_base_tcp`` within the tolerances and the
        joint limits, or None.

        1. The elbow angle in closed form from the shoulder-to-wrist-centre distance: none
           within its limits means no solution, at once (a wrist centre just out of the
           elbow's range is first brought in by moving the pose within the tolerances).
        2. Damped least squares (``damping``) from ``warm``, else from the rest shape
           turned towards the target (the first of the old seeds), for at most
           ``track_iterations`` iterations: the solution the seeded solver gave before.
        3. Else a sweep of the swivel angle for the exact solution within the limits
           nearest that start; none means no solution (except that when the exact ones
           all miss the limits by a little, damped least squares from the nearest two
           decides). If the URDF is not the DH arm: damped least squares from ``warm``
           and the ``n_seeds`` seeds, ``max_iterations`` each, as before."""
        # Keyed by the pose alone: a pose met again (the lift pose is the pre-grasp pose;
        # backtracking re-checks candidates) gets the same answer, whatever the warm start.
        T_base_tcp = np.asarray(T_base_tcp, dtype=float)
        key, found, hit = cache_lookup(self, T_base_tcp)
        if found:
            return hit
        q: np.ndarray | None = None
        if self.analytic:
            q = self._ik_analytic(T_base_tcp, warm)
        else:
            target = self.target(T_base_tcp)
            starts = ([np.clip(warm, self.lower, self.upper)] if warm is not None else []) + self.seeds(T_base_tcp)
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


@functools.cache
def _chain(urdf: Path) -> _UrdfChain:
    return _UrdfChain(urdf)


def kinematics_of_wam(robot: RobotSettings) -> WamKinematics:
    """The WAM model with the IK search of ``[robot]`` (`RobotSettings`)."""
    return WamKinematics(
        damping=robot.ik_damping,
        max_iterations=robot.ik_max_iterations,
        tolerance_m=robot.ik_tolerance_m,
        tolerance_rad=robot.ik_tolerance_rad,
        n_seeds=robot.ik_seeds,
    )
