"""Tests of clearcli/settings/sim.py: sections [world], [world_reach], [camera],
[depth_noise]; the camera's rays and projection and the noise model worked out by hand
from the figures fixtures/README.md states (fx = fy = 525, cx = 319.5, cy = 239.5;
sigma = 0.0012 + 0.0019 (z - 0.4)^2 m)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.sections import range_tests, refused

from clearcli.settings.sim import DepthNoise, PinholeCamera, WorldParams, WorldReachParams

test_defaults_lie_within_their_ranges, test_every_number_is_refused_past_its_bounds_naming_its_key = range_tests(
    WorldParams, WorldReachParams, PinholeCamera, DepthNoise
)


def test_the_camera_is_the_kinects() -> None:
    c = PinholeCamera()
    assert (c.width, c.height, c.fx, c.fy, c.cx, c.cy) == (640, 480, 525.0, 525.0, 319.5, 239.5)


def test_the_principal_point_lies_within_the_image() -> None:
    assert PinholeCamera(width=100, cx=100).cx == 100.0
    error = refused(PinholeCamera, "cx", 100.5, width=100)
    assert "within the image (width 100)" in str(error)
    error = refused(PinholeCamera, "cy", 50.5, height=50)
    assert "within the image (height 50)" in str(error)


def test_rays_and_projection_by_hand() -> None:
    c = PinholeCamera(width=16, height=20, fx=2.0, fy=4.0, cx=1.5, cy=1.0)
    rays = c.ray_directions()
    assert rays.shape == (20 * 16, 3)
    # row-major, v then u: pixel (u, v) is row v * width + u, its ray ((u - cx)/fx, (v - cy)/fy, 1)
    assert rays[0] == pytest.approx([-0.75, -0.25, 1.0])
    assert rays[2 * 16 + 3] == pytest.approx([0.75, 0.25, 1.0])
    assert rays[19 * 16 + 15] == pytest.approx([6.75, 4.5, 1.0])
    assert np.all(rays[:, 2] == 1.0)
    # a point at depth z on a pixel's ray projects back to that pixel
    z = np.linspace(0.5, 3.0, 20 * 16)[:, None]
    uv = c.project(rays * z)
    u, v = np.meshgrid(np.arange(16.0), np.arange(20.0))
    assert uv == pytest.approx(np.column_stack([u.ravel(), v.ravel()]))
    # the Kinect's: (0.1, -0.05, 1.0) m -> u = 525 * 0.1 + 319.5, v = 525 * -0.05 + 239.5
    assert PinholeCamera().project(np.array([[0.1, -0.05, 1.0]]))[0] == pytest.approx([372.0, 213.25])


def test_the_axial_noise_grows_with_the_square_of_the_distance() -> None:
    n = DepthNoise()
    assert n.sigma_m(0.4) == pytest.approx(0.0012)
    assert n.sigma_m(1.4) == pytest.approx(0.0012 + 0.0019)
    assert n.sigma_m(np.array([2.4])) == pytest.approx([0.0012 + 0.0019 * 4])
    assert DepthNoise(enabled=False).enabled is False


def test_world_steps_and_probabilities() -> None:
    refused(WorldParams, "push_step_m", 0.0004)
    refused(WorldParams, "tight_grasp_fail_probability", 1.01)
    refused(WorldParams, "frame_interval_s", 0)
    refused(WorldReachParams, "n_seeds", 0)
    assert WorldReachParams(n_yaws=72).n_yaws == 72
