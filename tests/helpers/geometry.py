"""Helpers that several test modules share (from the tests of geometry)."""

from __future__ import annotations

import numpy as np

from clearcli.predicates.state_builder import compute_state
from clearcli.predicates.synthetic import Box, camera_pose, make_scene
from clearcli.settings import Settings

BOX = (0.10, 0.05, 0.05)


def one_box(box: Box, settings: Settings | None = None):
    frame, seg = make_scene([box])
    state = compute_state(frame, seg, settings or Settings())
    return state, state.objects[0]


def world_to_camera(v: np.ndarray) -> np.ndarray:
    """A world-frame direction in the synthetic camera's frame."""
    return camera_pose()[:3, :3].T @ np.asarray(v, float)


def world_point_to_camera(p: np.ndarray) -> np.ndarray:
    T = camera_pose()
    return T[:3, :3].T @ (np.asarray(p, float) - T[:3, 3])
