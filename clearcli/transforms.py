"""Rotations and rigid transforms, one home for the whole package.

Quaternions are (x, y, z, w), as ROS and Foxglove write them; 4 x 4 transforms are
named ``T_<to>_<from>``. NumPy only: every layer may use this.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np


def quat_to_matrix(q: Sequence[float]) -> np.ndarray:
    """(x, y, z, w) -> 3 x 3 rotation; the quaternion need not be unit. ValueError for a
    zero or non-finite one (callers say what it was in their own words)."""
    x, y, z, w = (float(v) for v in q)
    norm = x * x + y * y + z * z + w * w
    if not math.isfinite(norm) or norm < 1e-18:
        raise ValueError(f"not a rotation: quaternion {[x, y, z, w]}")
    s = 2.0 / norm
    return np.array(
        [
            [1 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w)],
            [s * (x * y + z * w), 1 - s * (x * x + z * z), s * (y * z - x * w)],
            [s * (x * z - y * w), s * (y * z + x * w), 1 - s * (x * x + y * y)],
        ]
    )


def matrix_to_quat(R: np.ndarray) -> tuple[float, float, float, float]:
    """Rotation matrix -> unit (x, y, z, w) with w >= 0 (Shepperd's method, numerically
    safe). A matrix a hair off a rotation (PCA axes, composed poses) is projected onto
    the nearest rotation first."""
    m = nearest_rotation(R)
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 0:
        s = 2.0 * np.sqrt(trace + 1.0)
        w, x, y, z = 0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        w, x, y, z = (m[2, 1] - m[1, 2]) / s, 0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        w, x, y, z = (m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s
    else:
        s = 2.0 * np.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        w, x, y, z = (m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s
    q = np.array([x, y, z, w])
    q /= np.linalg.norm(q)
    if q[3] < 0:
        q = -q
    return float(q[0]), float(q[1]), float(q[2]), float(q[3])


def nearest_rotation(R: np.ndarray) -> np.ndarray:
    """The rotation nearest ``R`` (SVD), R itself when it already is one."""
    m = np.asarray(R, dtype=float)
    if np.allclose(m @ m.T, np.eye(3), atol=1e-12) and np.linalg.det(m) > 0:
        return m
    u, _, vt = np.linalg.svd(m)
    if np.linalg.det(u @ vt) < 0:
        u[:, -1] *= -1
    return u @ vt


def pose_to_matrix(translation: Sequence[float], quaternion: Sequence[float]) -> np.ndarray:
    """4 x 4 transform from a translation and an (x, y, z, w) quaternion."""
    T = np.eye(4)
    T[:3, :3] = quat_to_matrix(quaternion)
    T[:3, 3] = [float(v) for v in translation]
    return T


def rot2(angle_rad: float) -> np.ndarray:
    """2 x 2 rotation by ``angle_rad`` (counter-clockwise) in the plane."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, -s], [s, c]])


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross`` of 3-vectors along the last axis (one vector or rows of them), written
    out: its products and differences in its order, so the same floats, without its ~20 us
    of set-up per call (paid per pose, per object and per plane hypothesis)."""
    x = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    y = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    z = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return np.stack([x, y, z], axis=-1)
