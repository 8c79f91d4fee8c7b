"""The simulated world and its camera: sections [world], [world_reach], [camera] and
[depth_noise] (`clear simulate`, the clearing benchmark)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from clearcli.settings.fields import Section, param


@dataclass(frozen=True)
class WorldParams(Section):
    """How the simulated world departs from the planner's model."""

    NAME = "world"

    # Push: the object advances in steps of this length.
    push_step_m: float = param(0.005, ge=0.0005, le=0.1)
    # Heading noise per step (degrees) and yaw turn per step (always the same way within
    # one push): a pushed box turns a degree or two per centimetre when the contact is
    # off its centre.
    heading_noise_deg: float = param(1.0, ge=0, le=45)
    yaw_noise_deg: float = param(0.8, ge=0, le=45)
    # A grasp across a width within this margin of the gripper's opening slips with
    # this probability.
    tight_grasp_margin_m: float = param(0.01, ge=0, le=0.1)
    tight_grasp_fail_probability: float = param(0.5, ge=0, le=1)
    # Seconds between frames (the thesis's actions take a few seconds each).
    frame_interval_s: float = param(1.0, gt=0, le=3600)


@dataclass(frozen=True)
class WorldReachParams(Section):
    """How the world judges reach with its own IK (not the planner's code path)."""

    NAME = "world_reach"

    n_seeds: int = param(24, ge=1, le=500)  # the planner's fallback solver uses 8
    n_yaws: int = param(8, ge=1, le=72)  # cylinders: closing directions tried over a half-turn
    max_iterations: int = param(200, ge=1, le=10000)
    # the arm's links (capsules) must stay this far above the table top where over it
    table_margin_m: float = param(0.0, ge=0, le=0.2)


@dataclass(frozen=True)
class PinholeCamera(Section):
    """Intrinsics of the simulated depth camera: the Kinect's (registered) depth camera."""

    NAME = "camera"

    width: int = param(640, ge=16, le=4096)
    height: int = param(480, ge=16, le=4096)
    fx: float = param(525.0, gt=1, le=100000)
    fy: float = param(525.0, gt=1, le=100000)
    cx: float = param(319.5, ge=0, le=4096)
    cy: float = param(239.5, ge=0, le=4096)

    def cross_checks(self) -> None:
        if self.cx > self.width:
            self.fail("cx", f"must lie within the image (width {self.width})")
        if self.cy > self.height:
            self.fail("cy", f"must lie within the image (height {self.height})")

    def ray_directions(self) -> Any:
        """(H*W, 3) per-pixel ray directions scaled to z = 1, row-major (v, then u):
        a point at depth z on pixel (u, v) is z * ray."""
        import numpy as np  # noqa: PLC0415  (NumPy ~90 ms: `clear settings` loads this module, not NumPy)

        u = np.arange(self.width, dtype=np.float64)
        v = np.arange(self.height, dtype=np.float64)
        uu, vv = np.meshgrid(u, v)
        rays = np.empty((self.height * self.width, 3))
        rays[:, 0] = ((uu - self.cx) / self.fx).ravel()
        rays[:, 1] = ((vv - self.cy) / self.fy).ravel()
        rays[:, 2] = 1.0
        return rays

    def project(self, points_camera: Any) -> Any:
        """(N, 3) camera-frame points -> (N, 2) pixel coordinates (u, v), not rounded."""
        import numpy as np  # noqa: PLC0415  (NumPy ~90 ms: `clear settings` loads this module, not NumPy)

        p = np.asarray(points_camera, dtype=np.float64)
        return np.stack([self.fx * p[:, 0] / p[:, 2] + self.cx, self.fy * p[:, 1] / p[:, 2] + self.cy], axis=1)


@dataclass(frozen=True)
class DepthNoise(Section):
    """Kinect depth errors. ``enabled=False`` renders exact depth."""

    NAME = "depth_noise"

    enabled: bool = param(True)
    # Nguyen et al. 2012, axial noise of the Kinect v1, fitted for 0.4-3 m.
    sigma_base_m: float = param(0.0012, ge=0, le=0.1)
    sigma_quadratic_per_m: float = param(0.0019, ge=0, le=0.1)
    sigma_reference_z_m: float = param(0.4, ge=0, le=10)
    # Disparity: the Kinect reports disparity in 1/8 px over a ~7.5 cm baseline.
    baseline_m: float = param(0.075, gt=0, le=1)
    disparity_step_px: float = param(0.125, ge=0, le=10)
    # Pixels behind a depth edge of more than this lose their depth with this probability.
    dropout_edge_m: float = param(0.01, ge=0, le=1)
    dropout_probability: float = param(0.35, ge=0, le=1)

    def sigma_m(self, z_m: Any) -> Any:
        return self.sigma_base_m + self.sigma_quadratic_per_m * (z_m - self.sigma_reference_z_m) ** 2
