"""Colour registered to depth: each depth pixel's point, seen by the colour camera.

`color_for_depth(points_depth_m, T_color_depth, color_model, rgb)` gives every point of
a depth frame (back-projected with the depth intrinsics, clearcli/io/intrinsics.py) the
colour of the colour image pixel it projects to: the point is moved into the colour
camera's optical frame by ``T_color_depth`` (4 x 4, metres: p_color = R p_depth + t),
projected with the colour intrinsics (and their plumb_bob / rational_polynomial lens
distortion), and the *nearest* colour pixel is sampled (no interpolation: a depth edge
never gets a blend of the two sides).

A point with no depth, behind the colour camera, outside the colour image or outside
its calibrated field gets no colour: (0, 0, 0), what librealsense's own `rs2::align`
leaves in pixels it cannot map (src/proc/align.cpp zeroes its output first). A frame
holds one colour array or none (clearcli/io/frames.py), so no-colour is black.

This is what the RealSense SDK does at run time (`rs2::align` to depth: deproject,
`rs2_transform_point_to_point`, `rs2_project_point_to_pixel`); a recording keeps the
streams unaligned (clearcli/io/mcap_images.py reads the extrinsics it records).
"""

from __future__ import annotations

import numpy as np

from clearcli.io.intrinsics import _N_COEFFS, CameraModel, _distort, _undistorted_rays

# Points whose undistorted radius passes the image's own largest (its border pixels,
# undistorted) by more than this share are outside the calibrated field, where the
# distortion polynomial folds back and would put them inside the image again.
_FIELD_MARGIN = 1.02


class CannotRegister(Exception):
    """The colour cannot be registered (a distortion model clear cannot project); the
    message names what, for the note that says colour is left out."""


def project_to_pixels(points_m: np.ndarray, model: CameraModel) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(col, row, ok): integer nearest pixel of each (N, 3) point (camera optical frame,
    metres) in the image ``model`` describes (after its ROI and binning), and whether it
    lies in front of the camera, in the image and in its calibrated field.

    Raises CannotRegister for a distortion model with non-zero coefficients other than
    plumb_bob / rational_polynomial (the models clearcli.io.intrinsics inverts)."""
    size = model._image_size()
    if size is None:
        raise CannotRegister(f"the colour intrinsics ({model.source or 'camera info'}) give no image size")
    width, height = size
    p = np.asarray(points_m, dtype=np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        z = p[:, 2]
        front = np.isfinite(p).all(axis=1) & (z > 0)
        x = np.where(front, p[:, 0] / np.where(front, z, 1.0), np.nan)
        y = np.where(front, p[:, 1] / np.where(front, z, 1.0), np.nan)
        if model.distorted:
            name = model.distortion_model.lower()
            n = _N_COEFFS.get(name)
            if n is None or any(model.distortion[n:]):
                raise CannotRegister(
                    f"the colour intrinsics ({model.source or 'camera info'}) use the distortion model "
                    f"{model.distortion_model!r} with coefficients {list(model.distortion)}, which clear cannot "
                    "project (plumb_bob, rational_polynomial, or no distortion)"
                )
            rays_x, rays_y = _undistorted_rays(model, height, width)
            border = np.concatenate(
                [
                    rays_x[[0, -1], :].ravel() ** 2 + rays_y[[0, -1], :].ravel() ** 2,
                    rays_x[:, [0, -1]].ravel() ** 2 + rays_y[:, [0, -1]].ravel() ** 2,
                ]
            )
            r2_max = float(np.nanmax(border, initial=0.0)) * _FIELD_MARGIN**2
            front &= (x * x + y * y) <= r2_max
            coeffs = (list(model.distortion[:n]) + [0.0] * 8)[:8]
            x, y, _ = _distort(x, y, coeffs)
        # full-resolution pixel (centres at integers), then the ROI / binned image's pixel
        # (the inverse of clearcli.io.intrinsics._pixel_grid)
        ox, oy = (model.roi[0], model.roi[1]) if model.roi else (0, 0)
        u = (model.fx * x + model.cx - ox + 0.5) / model.binning_x - 0.5
        v = (model.fy * y + model.cy - oy + 0.5) / model.binning_y - 0.5
        col = np.floor(u + 0.5)
        row = np.floor(v + 0.5)
        ok = front & (col >= 0) & (col < width) & (row >= 0) & (row < height)
    col = np.where(ok, col, 0).astype(np.intp)
    row = np.where(ok, row, 0).astype(np.intp)
    return col, row, ok


def color_for_depth(
    points_depth_m: np.ndarray, T_color_depth: np.ndarray, color_model: CameraModel, rgb: np.ndarray
) -> np.ndarray:
    """(N, 3) uint8 RGB for the (N, 3) depth points (NaN rows: no depth): the nearest pixel
    of the colour image ``rgb`` (H, W, 3) each projects to; (0, 0, 0) where none (module doc)."""
    T = np.asarray(T_color_depth, dtype=np.float64)
    p = np.asarray(points_depth_m, dtype=np.float64)
    points_color_m = p @ T[:3, :3].T + T[:3, 3]
    col, row, ok = project_to_pixels(points_color_m, color_model)
    colors = np.zeros((p.shape[0], 3), dtype=np.uint8)
    colors[ok] = rgb[row[ok], col[ok]]
    return colors
