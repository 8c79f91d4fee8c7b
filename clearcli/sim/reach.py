"""The simulated world's own judgment of what the robot can take, on true poses.

The planner decides what it calls unreachable from a noisy model of the scene, with its
own (analytic, swivel-sweep) IK. A benchmark that excused whatever the planner gave up
on would reward a planner for giving up. So the world judges by itself, from the
object's true pose and size (`clearcli.sim.scene`), with a different IK:

* **Can the gripper hold it?** Its narrowest width is within the gripper's opening
  and above its closing width (`physics.truly_ungraspable`).
* **Does an arm motion reach it?** A top-down grasp of the object standing alone (the
  other objects can be moved out of the way; the table cannot): the closing point half
  the closing region below its top, the fingertips at least ``fingertips_above_table_m``
  above the table, the gripper closing across either side that fits the opening (for a
  cylinder, at ``n_yaws`` yaws), each at both half-turns; for each, the pre-grasp pose
  ``approach_m`` above and the grasp pose must have joint angles within the limits that
  Pinocchio's forward kinematics confirms, with no arm capsule under the table top.
  Joint angles come from ``n_seeds`` seeds (random within the joint limits, from a fixed
  generator) by a solver the planner does not use, as the arm's profile says
  (``world_solver``): damped least squares for the WAM (whose planner solves in closed
  form), SciPy's bounded least squares for another arm (whose planner runs damped least
  squares). An error in the planner's solver cannot excuse itself. The world uses the
  arm's kinematics through their public interface (clearcli/robot/kinematics.py).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from clearcli.robot.arm import resolve_arm
from clearcli.robot.collision import capsule_spheres
from clearcli.settings import Settings
from clearcli.settings.sim import WorldReachParams  # [world_reach]
from clearcli.sim.physics import truly_ungraspable
from clearcli.sim.scene import Box, Cylinder, Table

if TYPE_CHECKING:
    from clearcli.robot.arm import Arm
    from clearcli.settings.geometry import GripperSettings, PushSettings
    from clearcli.sim.scene import Scene, SceneObject


def grasp_poses_T_table_tcp(
    obj: SceneObject, gripper: GripperSettings, push: PushSettings, n_yaws: int = 8, any_yaw: bool = False
) -> list[tuple[np.ndarray, np.ndarray]]:
    """(pre-grasp, grasp) pose pairs of a top-down grasp of ``obj``, in the table frame.
    ``any_yaw``: at ``n_yaws`` yaws whatever the object's widths (the pose over an object
    another kind takes: a cup on its top, the fingers on its edge)."""
    half = gripper.closing_region_height_m / 2.0
    z = max(obj.top_z_m - half, push.fingertips_above_table_m + half)
    if isinstance(obj, Cylinder) or any_yaw:
        yaws = [math.pi * k / n_yaws for k in range(n_yaws)]
    else:
        assert isinstance(obj, Box)
        # closing across local y (width size_y) or across local x (width size_x)
        yaws = [
            obj.yaw_rad + (math.pi / 2 if across_y else 0.0)
            for across_y, width in ((True, obj.size_y_m), (False, obj.size_x_m))
            if width <= gripper.opening_width_m
        ]
    out = []
    for yaw in yaws:
        for turn in (0.0, math.pi):
            a = yaw + turn
            x = np.array([math.cos(a), math.sin(a), 0.0])
            zc = np.array([0.0, 0.0, -1.0])  # approach: down
            y = np.cross(zc, x)
            T = np.eye(4)
            T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = x, y, zc, (obj.x_m, obj.y_m, z)
            pre = T.copy()
            pre[2, 3] += push.approach_m
            out.append((pre, T))
    return out


class WorldReach:
    """``reachable(scene, k)``: whether the world's arm can grasp object ``k`` where it
    truly stands. ``T_base_table`` places the robot (the world's, fixed for a session);
    ``table`` is the table top the arm must stay above."""

    def __init__(
        self,
        T_base_table: np.ndarray,
        gripper: GripperSettings,
        push: PushSettings,
        params: WorldReachParams = WorldReachParams(),
        table: Table = Table(),
        robot: Arm | None = None,
    ) -> None:
        """``robot``: the arm the world has (the command's resolved arm; the default
        settings' when None). Its model gives FK, limits and capsules; the solving is the
        world's own (``world_solver``)."""
        if robot is None:
            robot = resolve_arm(Settings())
        self.T_base_table = np.asarray(T_base_table, dtype=float)
        self.T_table_base = np.linalg.inv(self.T_base_table)
        self.gripper, self.push, self.params, self.table = gripper, push, params, table
        self.solver = robot.profile.world_solver
        self.kin = robot.kinematics()
        rng = np.random.default_rng(20261122)
        self.seeds = rng.uniform(self.kin.lower, self.kin.upper, size=(params.n_seeds, self.kin.lower.size))

    def _solve(self, T_base_tcp: np.ndarray, warm: np.ndarray | None) -> np.ndarray | None:
        target = self.kin.target(T_base_tcp)
        starts = ([warm] if warm is not None else []) + list(self.seeds)
        for q0 in starts:
            q0 = np.asarray(q0, dtype=float)
            # damped least squares (for an arm planned in closed form: the WAM), else
            # SciPy's bounded least squares (its planner runs damped least squares)
            if self.solver == "damped_least_squares":
                q = self.kin.solve_from(target, q0, self.params.max_iterations)
            else:
                q = self._least_squares(target, q0)
            if q is not None and self.kin.within_tolerance(target, q) and self._clear_of_table(q):
                return q
        return None

    def _least_squares(self, target: Any, q0: np.ndarray) -> np.ndarray | None:
        """SciPy's trust-region reflective least squares on the pose error (Pinocchio's
        log6), within the joint limits: a solver the planner does not use."""
        from scipy.optimize import least_squares

        kin = self.kin

        def error(q: np.ndarray) -> np.ndarray:
            return kin.pose_error(target, q)

        lo, hi = kin.lower, kin.upper
        eps = 1e-9
        start = np.clip(q0, lo + eps, hi - eps)
        res = least_squares(error, start, bounds=(lo, hi), max_nfev=self.params.max_iterations, xtol=1e-10, ftol=1e-12)
        return np.asarray(res.x, dtype=float)

    def _clear_of_table(self, q: np.ndarray) -> bool:
        a, b, r = self.kin.capsules(q)
        centres, radii = capsule_spheres(a, b, r)
        c_table = centres @ self.T_table_base[:3, :3].T + self.T_table_base[:3, 3]
        # only where over the table top (the arm's base stands beside the table, lower)
        half_x, half_y = self.table.size_x_m / 2, self.table.size_y_m / 2
        over = (np.abs(c_table[:, 0]) <= half_x + radii) & (np.abs(c_table[:, 1]) <= half_y + radii)
        return not bool(np.any(over & (c_table[:, 2] < radii + self.params.table_margin_m)))

    def grasp_motion(self, obj: SceneObject, any_yaw: bool = False) -> tuple[np.ndarray, np.ndarray] | None:
        """(T_base_tcp, joint angles) of the first top-down grasp of ``obj`` whose
        pre-grasp and grasp poses both have arm configurations; None when none has.
        ``any_yaw``: `grasp_poses_T_table_tcp`'s."""
        pairs = grasp_poses_T_table_tcp(obj, self.gripper, self.push, self.params.n_yaws, any_yaw)
        for pre, T in pairs:
            q_pre = self._solve(self.T_base_table @ pre, None)
            if q_pre is None:
                continue
            T_base_tcp = self.T_base_table @ T
            q = self._solve(T_base_tcp, q_pre)
            if q is not None:
                return T_base_tcp, q
        return None

    def why_not(self, obj: SceneObject, other_kind: bool = False) -> str:
        """Empty when the gripper can hold ``obj`` and some top-down grasp of it has an
        arm motion; else why not. ``other_kind``: another grasp kind the robot has takes
        it by the world's rules (`physics.truly_ungraspable_by`: a cup on its top, a
        slide, a rim grasp), so that the fingers cannot close across it excuses nothing;
        then only an arm that reaches no top-down pose over it at any yaw does (the
        pose's height is the pinch's: a cup's lip or a slide's fingers come within a few
        cm of it)."""
        wide = truly_ungraspable(obj, self.gripper.opening_width_m, self.gripper.closing_width_m)
        if wide and not other_kind:
            return "the gripper cannot hold it (narrowest width beyond the opening or under the closing width)"
        if wide:
            if self.grasp_motion(obj, any_yaw=True) is None:
                return "no arm motion reaches a top-down pose over it"
            return ""
        if self.grasp_motion(obj) is None:
            return "no arm motion reaches a top-down grasp of it"
        return ""

    def reachable(self, scene: Scene, k: int) -> bool:
        return not self.why_not(scene.objects[k])


def T_base_table_of(T_base_camera: Any, scene: Scene) -> np.ndarray:
    return np.asarray(T_base_camera, dtype=float) @ scene.T_camera_table
