"""The camera's own picture with segments outlined on it: what a person checks a
segmentation against. Used by the segmentation and plan pictures when a frame is
organized and has colour (a Kinect or RealSense frame, an RGB-D pair)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np


def mask_edge(mask: np.ndarray) -> np.ndarray:
    """Pixels of ``mask`` (H, W) with a 4-neighbour outside it (the image border counts as
    outside): the outline drawn here, and the boundary the Boundary metric scores
    (clearcli/evaluate/osd.py)."""
    padded = np.pad(mask, 1, constant_values=False)
    inner = padded[:-2, 1:-1] & padded[2:, 1:-1] & padded[1:-1, :-2] & padded[1:-1, 2:]
    return mask & ~inner


def _thicken(edge: np.ndarray, mask: np.ndarray, px: int) -> np.ndarray:
    """The edge grown ``px - 1`` pixels into the mask (outlines stay inside their segment,
    so the image outside every segment is never painted)."""
    out = edge.copy()
    for _ in range(px - 1):
        grown = out.copy()
        grown[1:, :] |= out[:-1, :]
        grown[:-1, :] |= out[1:, :]
        grown[:, 1:] |= out[:, :-1]
        grown[:, :-1] |= out[:, 1:]
        out = grown & mask
    return out


def outlined(
    rgb: np.ndarray,
    shape: tuple[int, int],
    segments: Sequence[np.ndarray],
    colors: Sequence[Sequence[float]],
    width_px: int = 2,
) -> np.ndarray:
    """(H, W, 3) uint8: the colour image ``rgb`` ((H*W, 3) or (H, W, 3) uint8) with the
    outline of each segment (flat pixel indices) drawn in its colour (RGB in 0..1),
    ``width_px`` wide inside the segment. Every pixel off the outlines is the image's."""
    h, w = shape
    image = np.array(np.asarray(rgb, dtype=np.uint8).reshape(h, w, 3), copy=True)
    for indices, color in zip(segments, colors):
        flat = np.zeros(h * w, dtype=bool)
        flat[np.asarray(indices, dtype=np.int64)] = True
        mask = flat.reshape(h, w)
        line = _thicken(mask_edge(mask), mask, width_px)
        image[line] = np.round(np.clip(np.asarray(color[:3], dtype=float), 0, 1) * 255).astype(np.uint8)
    return image


def has_camera_picture(frame: Any) -> bool:
    """Whether the frame can be shown as the camera saw it: organized, with colour."""
    return frame.colors is not None and frame.shape is not None and frame.shape[0] > 1


def draw_camera_view(
    ax: Any, frame: Any, segments: Sequence[np.ndarray], colors: Sequence[Sequence[float]], names: Sequence[str]
) -> None:
    """The colour image with each segment outlined and named at its centre, on ``ax``."""
    h, w = frame.shape
    ax.imshow(outlined(frame.colors, frame.shape, segments, colors), interpolation="nearest")
    for indices, color, name in zip(segments, colors, names):
        if len(indices) == 0:
            continue
        rows, cols = np.divmod(np.asarray(indices, dtype=np.int64), w)
        ax.text(
            cols.mean(),
            rows.mean(),
            name,
            ha="center",
            va="center",
            fontsize=8,
            weight="bold",
            color="white",
            bbox=dict(boxstyle="round,pad=0.15", fc=tuple(color[:3]), ec="none", alpha=0.85),
        )
    ax.set_xticks([])
    ax.set_yticks([])
    ax.set_xlim(-0.5, w - 0.5)
    ax.set_ylim(h - 0.5, -0.5)
