"""Tests of clearcli/io/tf.py."""

from __future__ import annotations

from typing import Any

import numpy as np
from helpers.replay_session import sim_log  # noqa: F401  (fixtures)

from clearcli.io.tf import base_camera_from_log, lookup_transform


def test_transforms_from_the_log(sim_log: dict[str, Any]) -> None:
    T, base = base_camera_from_log(sim_log["path"], "camera_rgb_optical_frame")
    assert base == "wam_base"
    np.testing.assert_allclose(T, sim_log["T_base_camera"], atol=1e-9)
    assert base_camera_from_log(sim_log["path"], "another_frame") == (None, "")


def test_lookup_transform_chains_and_inverts() -> None:
    def tf(x: float, yaw_deg: float) -> np.ndarray:
        a = np.radians(yaw_deg)
        T = np.eye(4)
        T[:2, :2] = [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]
        T[0, 3] = x
        return T

    transforms = {("base", "link"): tf(1.0, 90), ("link", "camera"): tf(0.5, 0), ("camera", "optical"): tf(0.0, -90)}
    T = lookup_transform(transforms, "base", "optical")
    np.testing.assert_allclose(T, tf(1.0, 90) @ tf(0.5, 0) @ tf(0.0, -90), atol=1e-12)
    np.testing.assert_allclose(lookup_transform(transforms, "optical", "base"), np.linalg.inv(T), atol=1e-12)
    assert lookup_transform(transforms, "base", "nowhere") is None
    np.testing.assert_allclose(lookup_transform(transforms, "/base", "base"), np.eye(4))
