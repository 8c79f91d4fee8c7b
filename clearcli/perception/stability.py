"""Segmentation under rounding-sized changes (issue 37): the perturbations and the
comparison the stability benchmark (benchmarks/stability.py) and its test
(tests/perception/test_stability.py) share.

A frame moved by a micrometre (far below any sensor's noise; float32 rounding of a
millimetre depth is about 0.1 micrometre) must give the same objects: the same count,
each matched at IoU >= `MATCH_IOU`. Under sensor-level noise (`sensor_noise`) objects
may change; the benchmark reports the share kept at IoU >= `KEPT_IOU`.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from clearcli.io.frames import Frame
from clearcli.perception.types import Segmentation

MATCH_IOU = 0.95  # "the same object" under a rounding-sized change
KEPT_IOU = 0.9  # "the object is kept" under sensor noise


def perturbed(frame: Frame, amplitude_m: float = 1e-6, seed: int = 0) -> Frame:
    """``frame`` with every coordinate moved by uniform noise in [-amplitude_m,
    +amplitude_m] (drawn from ``seed``), stored in the frame's own dtype."""
    rng = np.random.default_rng(seed)
    pts = frame.points.astype(np.float64)
    pts = pts + rng.uniform(-amplitude_m, amplitude_m, size=pts.shape)
    return dataclasses.replace(frame, points=pts.astype(frame.points.dtype))


def sensor_noise(frame: Frame, sigma_at_1m: float = 1e-3, seed: int = 0) -> Frame:
    """``frame`` with Gaussian noise along each point's ray (the camera at the origin),
    sigma = ``sigma_at_1m`` (z / 1 m)^2 with z the depth along the optical axis: a
    structured-light or stereo camera's depth error grows with the square of the depth."""
    rng = np.random.default_rng(seed)
    pts = frame.points.astype(np.float64)
    z = np.abs(pts[:, 2])
    error = rng.standard_normal(pts.shape[0]) * sigma_at_1m * z * z  # along the ray, m
    r = np.linalg.norm(pts, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(r > 0, 1.0 + error / r, 1.0)
    return dataclasses.replace(frame, points=(pts * scale[:, None]).astype(frame.points.dtype))


def object_matches(a: Segmentation, b: Segmentation) -> np.ndarray:
    """(len(a.objects),) each object of ``a``: its best IoU (over the frame's points)
    with an object of ``b``, 0 when it meets none."""
    owner = np.full(b.n_points, -1, dtype=np.int64)
    for k, o in enumerate(b.objects):
        owner[o.indices] = k
    sizes_b = np.array([o.indices.size for o in b.objects], dtype=np.float64)
    best = np.zeros(len(a.objects))
    for i, o in enumerate(a.objects):
        hit = owner[o.indices]
        hit = hit[hit >= 0]
        if hit.size:
            inter = np.bincount(hit, minlength=len(b.objects))
            best[i] = float((inter / (o.indices.size + sizes_b - inter)).max())
    return best


def same_objects(a: Segmentation, b: Segmentation, iou: float = MATCH_IOU) -> bool:
    """The same objects: as many, and every object of each matched in the other at
    ``iou`` or more (above 0.5 a match is one to one)."""
    return (
        len(a.objects) == len(b.objects)
        and bool((object_matches(a, b) >= iou).all())
        and bool((object_matches(b, a) >= iou).all())
    )
