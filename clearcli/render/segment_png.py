"""A picture of a segmentation: the scene coloured by object, seen from the camera and
from above the table, with the table outline. matplotlib (Agg) is imported inside."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from clearcli.io.frames import LABEL_TABLE, Frame, object_ids
from clearcli.perception.types import Segmentation
from clearcli.render.camera import draw_camera_view, has_camera_picture

_TABLE_RGB = (0.78, 0.78, 0.78)
_NONE_RGB = (0.93, 0.93, 0.93)


def _object_colors(n: int) -> np.ndarray:
    import matplotlib

    cmap = matplotlib.colormaps["tab20"]
    return np.array([cmap(i % 20)[:3] for i in range(max(n, 1))])


def label_colors(labels: np.ndarray, n_objects: int) -> np.ndarray:
    """(N, 3) float RGB: objects from a qualitative map, table grey, the rest pale."""
    cols = np.tile(np.array(_NONE_RGB), (labels.shape[0], 1))
    cols[labels == LABEL_TABLE] = _TABLE_RGB
    ids = object_ids(labels)
    obj = ids > 0
    palette = _object_colors(n_objects)
    cols[obj] = palette[(ids[obj] - 1) % palette.shape[0]]
    return cols


def render_segmentation(path: Path, frame: Frame, seg: Segmentation, title: str = "") -> None:
    """Write a PNG at ``path``: left the camera view (the pixel grid when the frame is
    organized, else a pinhole projection), right a top view onto the table plane."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    labels = seg.labels()
    n_obj = len(seg.objects)
    cols = label_colors(labels, n_obj)
    finite = np.isfinite(frame.points).all(axis=1)
    fig, (ax_cam, ax_top) = plt.subplots(1, 2, figsize=(13, 5.2), dpi=100)

    # camera view: the colour image with the segments outlined, when the frame has one
    palette = _object_colors(n_obj)
    if has_camera_picture(frame):
        draw_camera_view(
            ax_cam,
            frame,
            [o.indices for o in seg.objects],
            [palette[k % palette.shape[0]] for k in range(n_obj)],
            [str(k) for k in range(n_obj)],
        )
        ax_cam.set_title("camera view (colour, segments outlined)")
    elif frame.shape is not None and frame.shape[0] > 1:
        h, w = frame.shape
        img = cols.reshape(h, w, 3).copy()
        img[~finite.reshape(h, w)] = 1.0
        ax_cam.imshow(img, interpolation="nearest")
    else:
        p = frame.points[finite].astype(np.float64)
        front = p[:, 2] > 1e-6
        # a camera frame (the sensor above the table, at the origin): pinhole
        if abs(seg.table.offset) >= 0.05 and front.sum() > p.shape[0] // 2:
            uv = p[front, :2] / p[front, 2:3]
            ax_cam.scatter(uv[:, 0], uv[:, 1], c=cols[finite][front], s=1, linewidths=0)
            ax_cam.invert_yaxis()
        else:  # not a camera frame (e.g. z-up in the table's frame): plain x-y
            ax_cam.scatter(p[:, 0], p[:, 1], c=cols[finite], s=1, linewidths=0)
            ax_cam.set_title("x-y view")
        ax_cam.set_aspect("equal")
    for k, obj in enumerate(seg.objects):
        if frame.shape is not None and frame.shape[0] > 1 and not has_camera_picture(frame):
            rows, cols_ = np.divmod(obj.indices, frame.shape[1])
            ax_cam.text(cols_.mean(), rows.mean(), str(k), ha="center", va="center", fontsize=9, weight="bold")
    if not ax_cam.get_title():
        ax_cam.set_title("camera view")
    ax_cam.set_xticks([])
    ax_cam.set_yticks([])

    # top view: coordinates in the table plane
    n = seg.table.normal
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(helper, n)
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    keep = finite & (labels > 0)
    p = frame.points[keep].astype(np.float64)
    order = np.argsort(seg.table.height_of(p))  # higher points drawn last
    ax_top.scatter((p @ u)[order], (p @ v)[order], c=cols[keep][order], s=0.5, linewidths=0)
    poly = seg.table_polygon
    if poly.shape[0] >= 3:
        closed = np.vstack([poly, poly[:1]])
        ax_top.plot(closed @ u, closed @ v, "-", color="black", lw=1.2, label="table hull")
    for k, obj in enumerate(seg.objects):
        corners = []
        for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1), (-1, -1)):
            c = obj.obb_center + 0.5 * (
                sx * obj.obb_extents[0] * obj.obb_axes[0] + sy * obj.obb_extents[1] * obj.obb_axes[1]
            )
            corners.append((c @ u, c @ v))
        cc = np.array(corners)
        ax_top.plot(cc[:, 0], cc[:, 1], "-", color="black", lw=0.6)
        ax_top.text(obj.centroid @ u, obj.centroid @ v, str(k), ha="center", va="center", fontsize=9, weight="bold")
    ax_top.set_aspect("equal")
    ax_top.set_title("from above the table (m)")
    fig.suptitle(title or f"{seg.source}: {n_obj} object(s)")
    fig.tight_layout()
    fig.savefig(str(path), format="png")
    plt.close(fig)
