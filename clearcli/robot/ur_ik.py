"""The UR family's inverse kinematics in closed form (after Hawkins, "Analytic inverse
kinematics for the Universal Robots UR-5/UR-10 arms", 2013): up to eight exact solutions
for the flange pose in the arm's DH base frame. Shoulder, elbow and wrist offsets make a
closed form possible: the wrist-2 centre fixes the base angle (two values), the flange's
axis then the wrist-2 angle (two), the flange's orientation the wrist-3 angle, and a
planar two-link problem the shoulder and elbow (two).

The UR5e's DH table (the maker's): d1 0.1625, a2 -0.425, a3 -0.3922, d4 0.1333,
d5 0.0997, d6 0.0996; alpha pi/2, 0, 0, pi/2, -pi/2, 0. The description's
``base_link_inertia`` is the DH base frame and ``wrist_3_link`` (= ``tool0``) its frame 6
(checked in tests/robot/test_profiles.py against Pinocchio's forward kinematics).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

_ALPHA = (math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0)


@dataclass(frozen=True)
class URDH:
    d1: float
    a2: float
    a3: float
    d4: float
    d5: float
    d6: float

    @property
    def a(self) -> tuple[float, ...]:
        return (0.0, self.a2, self.a3, 0.0, 0.0, 0.0)

    @property
    def d(self) -> tuple[float, ...]:
        return (self.d1, 0.0, 0.0, self.d4, self.d5, self.d6)


UR5E = URDH(d1=0.1625, a2=-0.425, a3=-0.3922, d4=0.1333, d5=0.0997, d6=0.0996)


def _dh(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array(
        [[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0.0, sa, ca, d], [0.0, 0.0, 0.0, 1.0]]
    )


def fk(dh: URDH, q: np.ndarray) -> np.ndarray:
    """T_base_6 (4x4) in the DH base frame."""
    T = np.eye(4)
    for i in range(6):
        T = T @ _dh(float(q[i]), dh.d[i], dh.a[i], _ALPHA[i])
    return T


def _inv(T: np.ndarray) -> np.ndarray:
    """Inverse of a rigid 4x4 transform."""
    out = np.eye(4)
    Rt = T[:3, :3].T
    out[:3, :3] = Rt
    out[:3, 3] = -Rt @ T[:3, 3]
    return out


def solutions(dh: URDH, T: np.ndarray) -> list[np.ndarray]:
    """Every exact solution (up to 8, angles in (-pi, pi] give or take 2 pi) putting
    frame 6 at ``T`` (4x4, DH base frame); none when the pose is out of reach."""
    out: list[np.ndarray] = []
    p, R = T[:3, 3], T[:3, :3]
    p05 = p - dh.d6 * R[:, 2]  # wrist 2's centre
    r = math.hypot(p05[0], p05[1])
    if r < abs(dh.d4):
        return out
    for s1 in (1.0, -1.0):
        q1 = math.atan2(p05[1], p05[0]) + s1 * math.acos(dh.d4 / r) + math.pi / 2
        c1, sn1 = math.cos(q1), math.sin(q1)
        c5 = (p[0] * sn1 - p[1] * c1 - dh.d4) / dh.d6
        if abs(c5) > 1.0 + 1e-12:
            continue
        T1 = _inv(_dh(q1, dh.d1, 0.0, _ALPHA[0])) @ T
        for s5 in (1.0, -1.0):
            q5 = s5 * math.acos(max(-1.0, min(1.0, c5)))
            sq5 = math.sin(q5)
            # a wrist singularity (q5 = 0): q6 is free; 0 is as good as any
            q6 = (
                0.0
                if abs(sq5) < 1e-9
                else math.atan2((-R[0, 1] * sn1 + R[1, 1] * c1) / sq5, (R[0, 0] * sn1 - R[1, 0] * c1) / sq5)
            )
            T14 = T1 @ _inv(_dh(q5, dh.d5, 0.0, _ALPHA[4]) @ _dh(q6, dh.d6, 0.0, _ALPHA[5]))
            x, y = T14[0, 3], T14[1, 3]
            c3 = (x * x + y * y - dh.a2 * dh.a2 - dh.a3 * dh.a3) / (2.0 * dh.a2 * dh.a3)
            if abs(c3) > 1.0 + 1e-12:
                continue
            # q4: the angle of frame 4's x axis in the plane, less q2 + q3 (the planar
            # chain's three joints are parallel)
            phi = math.atan2(T14[1, 0], T14[0, 0])
            for s3 in (1.0, -1.0):
                q3 = s3 * math.acos(max(-1.0, min(1.0, c3)))
                q2 = math.atan2(y, x) - math.atan2(dh.a3 * math.sin(q3), dh.a2 + dh.a3 * math.cos(q3))
                out.append(np.array([q1, q2, q3, math.atan2(math.sin(phi - q2 - q3), math.cos(phi - q2 - q3)), q5, q6]))
    return out
