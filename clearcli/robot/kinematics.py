"""What every arm's kinematics offers, and the pieces its solvers share.

`Kinematics` is the interface the planner (`ik`, `reachable`, `capsules`, `fk`) and the
simulated world (`target`, `solve_from`, `within_tolerance`, `pose_error`: the world runs
a solver of its own on the arm's model; every arm has them from `SolverAccess`) use;
`fresh` gives a new IK search (its cache, warm starts and statistics empty) on the same
model, read once per command. The WAM's analytic solver is `wam_kinematics.py` (its
model in NumPy: a plan on the WAM does not import Pinocchio), every other arm's
`generic.py` (Pinocchio's model; `SolverAccess` below).

Frames: poses are ``T_base_tcp`` in the arm's base frame; the TCP is the gripper's
closing point (z = approach, x = closing direction). Pinocchio is imported inside
functions: the CLI must start fast.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np


class Kinematics(Protocol):
    """What the planner and the simulated world use of an arm."""

    lower: np.ndarray
    upper: np.ndarray
    joint_names: tuple[str, ...]
    tolerance_m: float
    tolerance_rad: float

    def fk(self, q: np.ndarray, frame: str | None = None) -> np.ndarray: ...

    def ik(self, T_base_tcp: np.ndarray, warm: np.ndarray | None = None) -> np.ndarray | None: ...

    def reachable(self, T_base_tcp: np.ndarray, slack_m: float = 0.005) -> bool: ...

    def capsules(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...

    def fresh(self) -> Kinematics: ...

    def target(self, T_base_tcp: np.ndarray) -> Any: ...

    def solve_from(self, target: Any, q0: np.ndarray, iterations: int | None = None) -> np.ndarray | None: ...

    def within_tolerance(self, target: Any, q: np.ndarray) -> bool: ...

    def pose_error(self, target: Any, q: np.ndarray) -> np.ndarray: ...


@dataclass
class IKStats:
    solves: int = 0
    iterations: int = 0  # damped least squares iterations
    cache_hits: int = 0
    starts: int = 0  # damped least squares runs (a warm start or a seed each)
    sweeps: int = 0  # analytic swivel sweeps (the ring, and the dense ring when needed)


def se3(T: np.ndarray) -> Any:
    """A 4x4 pose as Pinocchio's SE3."""
    import pinocchio as pin

    return pin.SE3(np.ascontiguousarray(T[:3, :3]), np.ascontiguousarray(T[:3, 3]))


def half_turn(T: np.ndarray) -> np.ndarray:
    """The same gripper pose turned by pi about its approach axis (the gripper is
    symmetric, so both are equally good grasps/pushes)."""
    out = T.copy()
    out[:3, 0] = -T[:3, 0]
    out[:3, 1] = -T[:3, 1]
    return out


def cache_lookup(kin: Any, T_base_tcp: np.ndarray) -> tuple[bytes, bool, np.ndarray | None]:
    """(key, found, answer) of a pose in ``kin``'s IK cache, counted in its stats (a hit,
    or a solve to come). Keyed by the pose alone, to a micrometre."""
    key = np.round(T_base_tcp[:3], 6).tobytes()
    if key in kin._cache:
        kin.stats.cache_hits += 1
        hit = kin._cache[key]
        return key, True, None if hit is None else hit.copy()
    kin.stats.solves += 1
    return key, False, None


def within_tolerance(kin: Any, target: Any, q: np.ndarray) -> bool:
    """Pinocchio's FK of q (within ``kin``'s limits) meets the target within its tolerances."""
    pin = kin.pin
    if np.any(q < kin.lower) or np.any(q > kin.upper):
        return False
    pin.forwardKinematics(kin.model, kin.data, q)
    pin.updateFramePlacement(kin.model, kin.data, kin.tcp_id)
    vx, vy, vz, wx, wy, wz = pin.log6(kin.data.oMf[kin.tcp_id].actInv(target)).vector.tolist()
    return (
        math.sqrt(vx * vx + vy * vy + vz * vz) < kin.tolerance_m
        and math.sqrt(wx * wx + wy * wy + wz * wz) < kin.tolerance_rad
    )


def pose_error(kin: Any, target: Any, q: np.ndarray) -> np.ndarray:
    """The TCP's pose error at q against the target (Pinocchio's log6, 6 values, in the
    TCP frame): what a least-squares solver drives to zero."""
    pin = kin.pin
    pin.framesForwardKinematics(kin.model, kin.data, q)
    return np.asarray(pin.log6(kin.data.oMf[kin.tcp_id].actInv(target)).vector)


class SolverAccess:
    """The part of `Kinematics` a solver of its own uses (the simulated world's), the
    same on every arm's Pinocchio model: the pose as the solvers' target, the arm's
    damped least squares from a start, the tolerance check and the pose error. An arm's
    class provides the model (``pin``, ``model``, ``data``, ``tcp_id``, ``M_root_base``,
    its limits and tolerances) and its damped least squares (``_solve_from``)."""

    M_root_base: Any

    def _solve_from(self, target: Any, q0: np.ndarray, iterations: int | None = None) -> np.ndarray | None:
        raise NotImplementedError

    def target(self, T_base_tcp: np.ndarray) -> Any:
        """``T_base_tcp`` as the solvers' target: Pinocchio's SE3 in the model's root."""
        return self.M_root_base * se3(T_base_tcp)

    def solve_from(self, target: Any, q0: np.ndarray, iterations: int | None = None) -> np.ndarray | None:
        """Damped least squares from q0 towards ``target`` (`target`), within the joint
        limits, for ``iterations`` (default ``max_iterations``); None if it does not
        converge within the tolerances."""
        return self._solve_from(target, q0, iterations)

    def within_tolerance(self, target: Any, q: np.ndarray) -> bool:
        """q within the joint limits puts the TCP on ``target`` within the tolerances."""
        return within_tolerance(self, target, q)

    def pose_error(self, target: Any, q: np.ndarray) -> np.ndarray:
        """The TCP's pose error at q (log6, in the TCP frame)."""
        return pose_error(self, target, q)
