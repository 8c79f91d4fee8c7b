"""Pinhole camera intrinsics of RGB-D recordings, and depth image -> organized point cloud.

`read_intrinsics(spec)` reads a ROS camera calibration YAML, a sensor_msgs/CameraInfo
dumped as YAML/JSON, an Open3D PinholeCameraIntrinsic JSON or the UOIS camera_params.json
(told apart by their keys, not their names), or a string "fx fy cx cy".
`from_camera_info(...)` builds the model from the fields of a CameraInfo message.
`back_project(depth_m, model)` turns a depth image in metres into an (H*W, 3) float32
cloud in the optical frame, with binning, ROI and plumb_bob / rational_polynomial lens
distortion accounted for. Bad input raises InputError (exit 3), never a traceback.
"""

from __future__ import annotations

import functools
import json
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from clearcli.errors import InputError
from clearcli.files import exists, require_regular

# Distortion models whose inverse back_project computes -> their coefficient count (ROS order).
_N_COEFFS = {"plumb_bob": 5, "rational_polynomial": 8}
_LAYOUTS = (
    "ROS camera calibration YAML (image_width, image_height, camera_matrix, distortion_coefficients), "
    "sensor_msgs/CameraInfo (width, height, k, d, distortion_model), "
    "Open3D PinholeCameraIntrinsic JSON (width, height, intrinsic_matrix), "
    "UOIS camera_params.json (fx, fy, x_offset, y_offset, img_width, img_height)"
)
# Fixed-point inversion of the distortion (as OpenCV's undistortPoints): it contracts by
# roughly 2|k1|r^2 per step, so realistic lenses converge to 1e-9 in well under 20 steps.
_MAX_ITERATIONS = 50
_STEP_TOLERANCE = 1e-9
# A pixel whose ray, distorted again, misses its normalized coordinates by more than this
# (outside the calibrated field, where the polynomial folds back) gets no point rather than a wrong one.
_RESIDUAL_TOLERANCE = 1e-6


@dataclass(frozen=True)
class CameraModel:
    """Pinhole intrinsics of a camera; K is for the full-resolution sensor image.

    fx, fy, cx, cy:    focal lengths and principal point, pixels (pixel centres at integers).
    width, height:     full-resolution image size, pixels; None when not known.
    distortion_model:  ROS name ("", "none", "plumb_bob", "rational_polynomial", "equidistant"...).
    distortion:        coefficients in ROS order (plumb_bob k1 k2 p1 p2 k3;
                       rational_polynomial k1 k2 p1 p2 k3 k4 k5 k6).
    binning_x/_y:      pixels of the full image summed into one (1 = none).
    roi:               (x_offset, y_offset, width, height) in full-resolution pixels, or None.
    source:            what it was read from, for messages.
    """

    fx: float
    fy: float
    cx: float
    cy: float
    width: int | None = None
    height: int | None = None
    distortion_model: str = ""
    distortion: tuple[float, ...] = ()
    binning_x: int = 1
    binning_y: int = 1
    roi: tuple[int, int, int, int] | None = None
    source: str = ""

    @property
    def distorted(self) -> bool:
        """True when any distortion coefficient is non-zero (whatever the model's name)."""
        return any(c != 0.0 for c in self.distortion)

    def _image_size(self) -> tuple[int, int] | None:
        """(width, height) of the image these intrinsics describe, after ROI and binning."""
        if self.width is None or self.height is None:
            return None
        w, h = (self.roi[2], self.roi[3]) if self.roi else (self.width, self.height)
        return w // self.binning_x, h // self.binning_y

    def check_size(self, width: int, height: int, what: str) -> None:
        """InputError when the size is known and the `what` image is not that size."""
        expected = self._image_size()
        if expected is None or expected == (width, height):
            return
        whose = f"the intrinsics ({self.source})" if self.source else "the intrinsics"
        raise InputError(
            f"{what} is {width} x {height} but {whose} are for {expected[0]} x {expected[1]}; "
            "give the intrinsics of that image"
        )


def read_intrinsics(spec: str | Path) -> CameraModel:
    """The intrinsics in the file at `spec`, or in a string "fx fy cx cy" (commas or spaces)."""
    path = Path(spec)
    text = str(spec).strip()
    if isinstance(spec, str) and not (text and exists(path)):
        numbers = _four_numbers(text)
        if numbers is not None:
            where, fix = f'"{text}"', 'fix the string "fx fy cx cy"'
            return _build(*numbers, None, None, "", (), 1, 1, None, source=text, where=where, fix=fix)
        raise InputError(
            f'{text or "(empty)"}: no such file, and not four numbers "fx fy cx cy"; give an intrinsics '
            'file (ROS camera YAML, CameraInfo, Open3D or UOIS JSON) or "fx fy cx cy"'
        )
    where = str(path)
    if not path.is_file():
        what = "is a folder" if path.is_dir() else "no such file"
        if exists(path) and not path.is_dir():
            require_regular(path, 'an intrinsics file or "fx fy cx cy"')
        raise InputError(f'{where}: {what}; give an intrinsics file or "fx fy cx cy"')
    try:
        st = path.stat()
        return _read_file(str(path.resolve()), st.st_mtime_ns, st.st_size, where)
    except OSError:
        return _read_file(str(path), 0, 0, where)


@functools.lru_cache(maxsize=16)
def _read_file(path_text: str, mtime_ns: int, size: int, where: str) -> CameraModel:
    """One intrinsics file read, kept while unchanged (mtime and size in the key): a
    folder of image pairs reads its camera file once, not once per frame."""
    path = Path(path_text)
    try:
        raw = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"{where}: cannot be read as text ({e}); give a YAML or JSON intrinsics file") from None
    if not raw.strip():
        raise InputError(f"{where}: is empty; give a YAML or JSON intrinsics file")
    data = _parse(raw, where)
    if not isinstance(data, dict):
        raise InputError(f"{where}: holds no mapping of keys; accepted layouts: {_LAYOUTS}")
    return _from_mapping(data, where)


def from_camera_info(
    width: Any,
    height: Any,
    k: Sequence[float],
    d: Sequence[float],
    distortion_model: str,
    binning_x: Any = 0,
    binning_y: Any = 0,
    roi: Any = None,
    source: str = "",
) -> CameraModel:
    """The model of a sensor_msgs/CameraInfo message (k row-major; roi as in the message:
    (x_offset, y_offset, height, width, do_rectify), a mapping or an object with those names)."""
    where = f"camera info on {source}" if source else "camera info"
    try:
        return _camera_info(width, height, k, d, distortion_model, binning_x, binning_y, roi, source, where)
    except (KeyError, TypeError, ValueError, AttributeError) as e:
        raise InputError(f"{where}: malformed message ({e}); give a sensor_msgs/CameraInfo") from None


def back_project(depth_m: np.ndarray, model: CameraModel) -> np.ndarray:
    """(H*W, 3) float32 points in the optical frame (x right, y down, z forward, metres),
    row-major (pixel (v, u) at row v*W + u); NaN rows where the depth is 0, negative or not finite.

    depth_m: (H, W) float32/float64 depth along the optical axis, metres. Float64 depth is
    rounded to float32 first: the arithmetic is float32 (see below).
    """
    depth = np.asarray(depth_m)
    if depth.ndim != 2:
        raise InputError(
            f"depth image of shape {depth.shape} is not one (height, width) image; give a single-channel depth image"
        )
    if depth.dtype.kind != "f":
        # A caller's bug, not the user's: raw sensor units must be scaled to metres first.
        raise TypeError(f"back_project takes depth in metres as float32/float64, not {depth.dtype}")
    h, w = depth.shape
    model.check_size(w, h, "the depth image")
    z = depth.astype(np.float32)
    with np.errstate(invalid="ignore"):
        z[~(np.isfinite(z) & (z > 0))] = np.nan
    # A depth near float32's top (a corrupt pixel) overflows x or y to inf: such a pixel is
    # no point either, marked NaN below rather than warned about.
    with np.errstate(over="ignore", invalid="ignore"):
        if model.distorted:
            ray_x, ray_y = _undistorted_rays(model, h, w)
            x, y = ray_x * z, ray_y * z
        else:
            # Float32, in the order (u - cx) * z / fx: this reproduces the UOIS PCDs bit for bit;
            # float64 then cast (or dividing before multiplying) is 1 ulp off in most points.
            u, v = _pixel_grid(model, h, w)
            x = (u[None, :].astype(np.float32) - np.float32(model.cx)) * z / np.float32(model.fx)
            y = (v[:, None].astype(np.float32) - np.float32(model.cy)) * z / np.float32(model.fy)
    points = np.stack([x, y, z], axis=-1).reshape(-1, 3)
    points[~np.isfinite(points).all(axis=1)] = np.nan
    return points


# --- reading -------------------------------------------------------------------------------


def _parse(raw: str, where: str) -> Any:
    """JSON when it looks like JSON, else YAML (the ROS files; a YAML flow mapping also starts with "{")."""
    if raw.lstrip().startswith("{"):
        try:
            return json.loads(raw)
        except ValueError as e:
            if where.lower().endswith(".json"):
                raise InputError(f"{where}: not valid JSON ({e}); fix the file") from None
    import yaml

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml's, 10x faster where built
    try:
        return yaml.load(raw, Loader=loader)  # noqa: S506 (a safe loader)
    except yaml.YAMLError as e:
        first = str(e).strip().splitlines()[0] if str(e).strip() else e.__class__.__name__
        raise InputError(f"{where}: not valid YAML ({first}); fix the file") from None


def _from_mapping(data: dict[str, Any], where: str) -> CameraModel:
    """Decide the layout by its keys, then read it."""
    layout = "intrinsics"
    try:
        if "camera_matrix" in data:
            layout = "ROS camera calibration YAML"
            fx, fy, cx, cy = _k_entries(data["camera_matrix"]["data"], "camera_matrix", where, row_major=True)
            dist = data.get("distortion_coefficients") or {}
            return _build(
                fx,
                fy,
                cx,
                cy,
                data["image_width"],
                data["image_height"],
                data.get("distortion_model"),
                dist.get("data") or (),
                1,
                1,
                None,
                source=where,
                where=where,
                fix="fix the camera matrix",
            )
        if "k" in data or "K" in data:
            layout = "sensor_msgs/CameraInfo"
            k = data["k"] if "k" in data else data["K"]
            d = data.get("d", data.get("D")) or ()
            return _camera_info(
                data["width"],
                data["height"],
                k,
                d,
                data.get("distortion_model"),
                data.get("binning_x", 0),
                data.get("binning_y", 0),
                data.get("roi"),
                where,
                where,
            )
        if "intrinsic_matrix" in data:
            layout = "Open3D PinholeCameraIntrinsic JSON"
            fx, fy, cx, cy = _k_entries(data["intrinsic_matrix"], "intrinsic_matrix", where, row_major=False)
            return _build(
                fx,
                fy,
                cx,
                cy,
                data["width"],
                data["height"],
                "",
                (),
                1,
                1,
                None,
                source=where,
                where=where,
                fix="fix intrinsic_matrix (column-major)",
            )
        if {"fx", "fy", "x_offset", "y_offset"} & set(data):
            layout = "UOIS camera_params.json"
            return _build(
                data["fx"],
                data["fy"],
                data["x_offset"],
                data["y_offset"],
                data["img_width"],
                data["img_height"],
                "",
                (),
                1,
                1,
                None,
                source=where,
                where=where,
                fix="fix the file",
            )
    except KeyError as e:
        raise InputError(f"{where}: missing key {e.args[0]!r} of a {layout}; add it") from None
    except (TypeError, ValueError, AttributeError) as e:
        raise InputError(f"{where}: malformed {layout} ({e}); fix the file") from None
    keys = ", ".join(sorted(map(str, data))[:8])
    raise InputError(f"{where}: unknown intrinsics layout (keys: {keys}); accepted layouts: {_LAYOUTS}")


def _four_numbers(text: str) -> tuple[float, float, float, float] | None:
    parts = [p for p in re.split(r"[,\s]+", text) if p]
    if len(parts) != 4:
        return None
    try:
        fx, fy, cx, cy = (float(p) for p in parts)
    except ValueError:
        return None
    return fx, fy, cx, cy


def _k_entries(k: Any, name: str, where: str, row_major: bool) -> tuple[Any, Any, Any, Any]:
    """fx, fy, cx, cy of a 3x3 camera matrix given as 9 numbers, checking its last row
    (which catches a matrix given in the other order)."""
    values = [_number(x, f"an entry of {name}", where, "fix the camera matrix") for x in k]
    if len(values) != 9:
        raise InputError(f"{where}: {name} has {len(values)} numbers, not 9 (a 3 x 3 matrix); fix the camera matrix")
    last_row = values[6:9] if row_major else values[2::3]
    if any(values) and last_row != [0.0, 0.0, 1.0]:
        order = "row" if row_major else "column"
        raise InputError(
            f"{where}: {name} is not a {order}-major camera matrix (its last row is {last_row}, not [0, 0, 1]); "
            "fix the camera matrix"
        )
    return (values[0], values[4], values[2], values[5]) if row_major else (values[0], values[4], values[6], values[7])


def _camera_info(
    width: Any, height: Any, k: Any, d: Any, model: Any, bx: Any, by: Any, roi: Any, source: str, where: str
) -> CameraModel:
    fx, fy, cx, cy = _k_entries(k, "K", where, row_major=True)
    if fx == fy == cx == cy == 0.0:
        raise InputError(f"{where} has no intrinsics (K is all zero); the camera is not calibrated: give intrinsics")
    if roi is not None and not isinstance(roi, (list, tuple)):
        names = ("x_offset", "y_offset", "height", "width")
        roi = [roi.get(n, 0) for n in names] if isinstance(roi, dict) else [getattr(roi, n) for n in names]
    d = () if d is None else d
    return _build(fx, fy, cx, cy, width, height, model, d, bx, by, roi, source=source, where=where, fix="fix K")


def _build(
    fx: Any,
    fy: Any,
    cx: Any,
    cy: Any,
    width: Any,
    height: Any,
    model: Any,
    coeffs: Any,
    bx: Any,
    by: Any,
    roi: Any,
    *,
    source: str,
    where: str,
    fix: str,
) -> CameraModel:
    """A validated CameraModel; roi here in message order (x_offset, y_offset, height, width)."""
    values = {}
    for name, value in (("fx", fx), ("fy", fy), ("cx", cx), ("cy", cy)):
        number = _number(value, name, where, fix)
        # The back-projection works in float32: a value beyond its range (about 3.4e38), or
        # a focal length that rounds to 0 there, would make every point inf or NaN.
        with np.errstate(over="ignore", under="ignore"):
            as_f32 = float(np.float32(number)) if math.isfinite(number) else number
        if not math.isfinite(as_f32) or (name in ("fx", "fy") and as_f32 <= 0):
            must = "a positive finite number" if name in ("fx", "fy") else "a finite number"
            if math.isfinite(number) and not (name in ("fx", "fy") and number <= 0):
                must += " within float32's range, as the back-projection computes in float32"
            raise InputError(f"{where}: {name} = {value} (must be {must}); {fix}")
        values[name] = number
    w = None if width is None else _count(width, "width", where, 1)
    h = None if height is None else _count(height, "height", where, 1)
    distortion = tuple(_number(c, "a distortion coefficient", where, fix) for c in coeffs)
    if not all(map(math.isfinite, distortion)):
        raise InputError(f"{where}: distortion coefficients {list(distortion)} are not all finite; fix them")
    roi_wh = None
    if roi is not None:
        x0, y0, rh, rw = (_count(r, "roi", where, 0) for r in list(roi)[:4])
        if rw and rh:  # ROS: a zero width or height means the full image
            if w is not None and h is not None and (x0 + rw > w or y0 + rh > h):
                raise InputError(f"{where}: roi {rw} x {rh} at ({x0}, {y0}) leaves the {w} x {h} image; fix roi")
            roi_wh = (x0, y0, rw, rh)
    return CameraModel(
        values["fx"],
        values["fy"],
        values["cx"],
        values["cy"],
        w,
        h,
        str(model or ""),
        distortion,
        _count(bx, "binning_x", where, 0) or 1,
        _count(by, "binning_y", where, 0) or 1,
        roi_wh,
        source,
    )


def _number(value: Any, name: str, where: str, fix: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, str, np.number)):
        raise InputError(f"{where}: {name} = {value!r} is not a number; {fix}")
    try:
        return float(value)
    except (ValueError, OverflowError):
        shown = repr(value) if len(repr(value)) <= 40 else repr(value)[:37] + "..."
        raise InputError(f"{where}: {name} = {shown} is not a number a camera has; {fix}") from None


def _count(value: Any, name: str, where: str, minimum: int) -> int:
    number = _number(value, name, where, f"fix {name}")
    if not (math.isfinite(number) and number == int(number) and number >= minimum):
        kind = "a positive whole number" if minimum else "a whole number >= 0"
        raise InputError(f"{where}: {name} = {value} (must be {kind}); fix {name}")
    return int(number)


# --- back-projection ----------------------------------------------------------------------


def _pixel_grid(model: CameraModel, h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    """Full-resolution coordinates (float64) of the columns (W,) and rows (H,) of the image:
    pixel u of a binned/ROI image is the centre of its block, roi_x + (u + 0.5) * binning - 0.5
    (exactly u without binning or ROI)."""
    ox, oy = (model.roi[0], model.roi[1]) if model.roi else (0, 0)
    u = ox + (np.arange(w, dtype=np.float64) + 0.5) * model.binning_x - 0.5
    v = oy + (np.arange(h, dtype=np.float64) + 0.5) * model.binning_y - 0.5
    return u, v


def _distort(x: np.ndarray, y: np.ndarray, c: Sequence[float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Forward ROS/OpenCV model on normalized coordinates: (x_d, y_d, radial factor)."""
    k1, k2, p1, p2, k3, k4, k5, k6 = c
    r2 = x * x + y * y
    radial = (1 + ((k3 * r2 + k2) * r2 + k1) * r2) / (1 + ((k6 * r2 + k5) * r2 + k4) * r2)
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return xd, yd, radial


@functools.lru_cache(maxsize=4)  # every frame of a log shares one model: invert once (2 x 4 bytes a pixel)
def _undistorted_rays(model: CameraModel, h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    """(H, W) float32 x', y' of the undistorted normalized ray of each pixel (NaN where the
    inversion does not converge); read-only, as they are shared through the cache."""
    name = model.distortion_model.lower()
    n = _N_COEFFS.get(name)
    if n is None:
        raise InputError(
            f"distortion model {model.distortion_model!r} of {model.source or 'the intrinsics'} is not supported; "
            "give rectified images or plumb_bob / rational_polynomial intrinsics"
        )
    if any(model.distortion[n:]):
        raise InputError(
            f"{model.source or 'the intrinsics'}: {name} takes {n} distortion coefficients, "
            f"got {len(model.distortion)} with non-zero extras; fix the distortion coefficients"
        )
    coeffs = (list(model.distortion[:n]) + [0.0] * 8)[:8]
    u, v = _pixel_grid(model, h, w)
    x0 = np.broadcast_to((u[None, :] - model.cx) / model.fx, (h, w))
    y0 = np.broadcast_to((v[:, None] - model.cy) / model.fy, (h, w))
    x, y = x0.copy(), y0.copy()
    with np.errstate(all="ignore"):  # diverging pixels become inf/NaN and are dropped below
        for _ in range(_MAX_ITERATIONS):
            xd, yd, radial = _distort(x, y, coeffs)
            # x = (x0 - tangential(x)) / radial(x), written as a correction of the current estimate
            x_new, y_new = x + (x0 - xd) / radial, y + (y0 - yd) / radial
            step = np.nanmax(np.maximum(np.abs(x_new - x), np.abs(y_new - y)), initial=0.0)
            x, y = x_new, y_new
            if step < _STEP_TOLERANCE:
                break
        xd, yd, radial = _distort(x, y, coeffs)
        bad = ~((np.abs(xd - x0) <= _RESIDUAL_TOLERANCE) & (np.abs(yd - y0) <= _RESIDUAL_TOLERANCE) & (radial > 0))
    x[bad] = np.nan
    y[bad] = np.nan
    ray_x, ray_y = x.astype(np.float32), y.astype(np.float32)
    ray_x.flags.writeable = False
    ray_y.flags.writeable = False
    return ray_x, ray_y
