"""The same camera image as other conventions and mountings write it (issue 37: frames of
labs no one here has seen), for the tests and `benchmarks/conventions.py`.

Each variant of an organized image in the optical frame (x right, y down, z forward) is
made by reordering and negating coordinates and moving pixels whole, so its points are
the image's exactly; with it comes, per pixel of the variant, the pixel of the image it
shows. Written here from the conventions themselves, not from
`clearcli.perception.orientation`, which the variants test.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from clearcli.io.frames import Frame


def _made(frame: Frame, grid: np.ndarray, pixels: np.ndarray) -> tuple[Frame, np.ndarray]:
    """The variant whose (h, w, 3) points are ``grid`` and whose pixels show ``pixels`` of
    ``frame`` (colours and per-pixel fields moved with them)."""
    at = np.ascontiguousarray(pixels).reshape(-1)
    n = frame.n_points
    return (
        dataclasses.replace(
            frame,
            points=np.ascontiguousarray(grid.reshape(-1, 3)),
            colors=None if frame.colors is None else np.ascontiguousarray(frame.colors[at]),
            shape=(pixels.shape[0], pixels.shape[1]),
            fields={k: np.asarray(v)[at] if np.shape(v)[:1] == (n,) else v for k, v in frame.fields.items()},
        ),
        at,
    )


def _camera_link(g: np.ndarray) -> np.ndarray:
    """ROS's camera_link axes (x forward, y left, z up) of optical-frame points (..., 3)."""
    return np.stack([g[..., 2], -g[..., 0], -g[..., 1]], axis=-1)


def _upside_down(g: np.ndarray) -> np.ndarray:
    """The image of the camera rolled a half turn about its axis: rows and columns
    reversed, x and y negated."""
    return g[::-1, ::-1] * np.array([-1, -1, 1], dtype=g.dtype)


def _on_its_side(g: np.ndarray) -> np.ndarray:
    """The image of the camera rolled a quarter turn: np.rot90's, whose right is the
    former down (+y) and whose down the former left (-x)."""
    q = np.rot90(g, 1)
    return np.stack([q[..., 1], -q[..., 0], q[..., 2]], axis=-1)


def variants(frame: Frame) -> dict[str, tuple[Frame, np.ndarray]]:
    """``frame`` (an organized optical image) as other cameras and conventions write the
    same view: name -> (the variant, (N,) the frame's pixel each of its pixels shows)."""
    assert frame.shape is not None and frame.shape[0] * frame.shape[1] == frame.n_points
    h, w = frame.shape
    g = frame.points.reshape(h, w, 3)
    at = np.arange(h * w).reshape(h, w)
    makers: dict[str, tuple[Callable[[np.ndarray], np.ndarray], np.ndarray]] = {
        # OpenGL's (y up, looking along -z): Open3D's tutorials turn clouds so
        "opengl": (lambda p: p * np.array([1, -1, -1], dtype=p.dtype), at),
        "camera_link": (_camera_link, at),
        "upside_down": (_upside_down, at[::-1, ::-1]),
        "on_its_side": (_on_its_side, np.rot90(at, 1)),
        "camera_link_upside_down": (lambda p: _camera_link(_upside_down(p)), at[::-1, ::-1]),
    }
    return {name: _made(frame, make(g), pixels) for name, (make, pixels) in makers.items()}


def beneath_the_table(frame: Frame, normal: np.ndarray, offset: float, below_m: float = 0.75) -> Frame:
    """``frame`` moved into a z-up frame whose origin lies ``below_m`` under the table's
    top (a mobile robot's base on the floor): the table's plane ``normal . p + offset = 0``
    (normal towards the camera) becomes z = ``below_m``. Organized as ``frame`` is."""
    z = np.asarray(normal, dtype=np.float64) / np.linalg.norm(normal)
    x = np.cross([0.0, 1.0, 0.0], z) if abs(z[1]) < 0.9 else np.cross([1.0, 0.0, 0.0], z)
    x /= np.linalg.norm(x)
    rotation = np.stack([x, np.cross(z, x), z])  # rows: the new axes in the frame's
    p = frame.points.astype(np.float64) @ rotation.T
    p[:, 2] += offset + below_m  # the plane at z = -offset before
    return dataclasses.replace(frame, points=p.astype(np.float32))
