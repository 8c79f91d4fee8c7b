"""Depth images from files -> an organized `Frame`, as a camera's point cloud would be.

A depth frame is a 16-bit PNG (integer units, `[images] depth_scale_m` metres each:
millimetres by default), a 32-bit float TIFF (metres) or an NPY array (float: metres;
integer: units as a PNG). Its intrinsics come from `[images] intrinsics` (`--intrinsics`:
a file or "fx fy cx cy") or else from the one intrinsics file beside it. Its colour
comes from `--color`, or else from the image the naming rule pairs with it
(`<stem>_depth.png` -> `<stem>_color.png`, both suffixes in [images]).

The frame is what the PCD path gives for the same data: (height x width) points in the
optical frame, NaN where the depth is 0, colour per pixel (clearcli/io/intrinsics.py
holds the back-projection, and why its arithmetic is float32).

Every bad input is one InputError naming the file and what to do: a colour image given
as depth, a truncated or non-image file, sizes that differ, intrinsics for another
resolution, an all-zero depth image.
"""

from __future__ import annotations

import logging
import warnings
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from clearcli.errors import InputError
from clearcli.files import require_regular
from clearcli.io.frames import Frame
from clearcli.io.intrinsics import CameraModel, back_project, read_intrinsics
from clearcli.io.sniff import NPY_MAGIC
from clearcli.settings.images import ImageSettings

if TYPE_CHECKING:
    import PIL.Image

# File names an intrinsics file beside the images may have, in the order they are tried.
INTRINSICS_NAMES = (
    "camera_info.yaml",
    "camera_info.yml",
    "camera_params.json",
    "intrinsics.json",
    "intrinsic.json",
    "camera_intrinsic.json",
    "camera.yaml",
    "camera.json",
)


def or_defaults(images: ImageSettings | None) -> ImageSettings:
    """``images``, or the [images] defaults when a caller has none (a library call)."""
    if images is None:
        return ImageSettings()
    return images


# The largest image `clear` decodes, checked on the header before a byte is decoded (a
# PNG may claim 100000 x 100000 in 60 bytes; decoded, that is 20 GB). The largest frames
# depth and structured-light cameras write are 4096 x 3072 (Azure Kinect colour, 12.6 MP),
# 2448 x 2048 (Zivid 2+), 2208 x 1242 (ZED 2) and 1920 x 1080 (RealSense colour): 2^25
# pixels (33.5 MP, 2.7 times the largest) and 16384 a side leave room for any of them
# and for stitched or upsampled frames, and bound one frame's points to 400 MB.
MAX_IMAGE_PIXELS = 1 << 25
MAX_IMAGE_SIDE_PX = 16384


def check_image_size(width: int, height: int, where: str) -> None:
    """Refuse an image larger than any camera writes before decoding it (see above)."""
    if width > MAX_IMAGE_SIDE_PX or height > MAX_IMAGE_SIDE_PX or width * height > MAX_IMAGE_PIXELS:
        raise InputError(
            f"{where}: a {width} x {height} image, larger than any camera frame clear reads (at most "
            f"{MAX_IMAGE_PIXELS:,} pixels and {MAX_IMAGE_SIDE_PX} a side); is its header damaged? Scale it down if real"
        )


def _open_image(path: Path, what: str) -> PIL.Image.Image:
    from PIL import Image, UnidentifiedImageError

    # PIL's own bomb check (warn past 89 MP, raise past twice that) is replaced by ours,
    # which runs first and refuses with the reason: ours is the stricter of the two.
    Image.MAX_IMAGE_PIXELS = None
    require_regular(path, what)
    try:
        # PIL warns of what it can mend (a corrupt EXIF block of a truncated TIFF): what it
        # cannot mend raises and is reported below as one line; the warning would be a second
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            image = Image.open(path)  # reads the header only
            check_image_size(image.width, image.height, str(path))
            image.load()  # decode now: a truncated file fails here, not half-way into a stage
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except UnidentifiedImageError:
        raise InputError(f"{path}: not an image file (PNG or TIFF) although it was given as {what}") from None
    except (OSError, SyntaxError, ValueError, Image.DecompressionBombError) as exc:
        raise InputError(f"{path}: a damaged or truncated image ({exc}); record or copy it again") from None
    except MemoryError:
        raise InputError(f"{path}: too large to decode in this machine's memory") from None
    return image


def _units_to_m(raw: np.ndarray, scale_m: float) -> np.ndarray:
    """Integer depth units -> float32 metres. Dividing by the units per metre when that is
    a whole number (1000 for millimetres) gives the same floats as a PCD written from the
    same data; multiplying by 0.001 is 1 ulp off on most points."""
    per_m = 1.0 / scale_m
    if abs(per_m - round(per_m)) < 1e-9 * per_m:
        return raw.astype(np.float32) / np.float32(round(per_m))
    return raw.astype(np.float32) * np.float32(scale_m)


def read_depth_m(path: Path, scale_m: float) -> np.ndarray:
    """(H, W) float32 depth in metres of a depth image file; 0 or NaN = no reading."""
    path = Path(path)
    try:
        with open(path, "rb") as fp:
            is_npy = fp.read(len(NPY_MAGIC)) == NPY_MAGIC
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror})") from None
    if is_npy:
        try:
            with open(path, "rb") as fp:
                # the header's shape is checked before the array is read, as an image's is
                fmt = np.lib.format
                version = fmt.read_magic(fp)
                header = fmt.read_array_header_1_0 if version == (1, 0) else fmt.read_array_header_2_0
                shape = header(fp, max_header_size=10000)[0] if version[0] <= 2 else ()
            if len(shape) in (2, 3):
                check_image_size(int(shape[1]), int(shape[0]), str(path))
            raw = np.load(path, allow_pickle=False)
        except InputError:
            raise
        except MemoryError:
            raise InputError(f"{path}: too large to read in this machine's memory") from None
        except Exception as exc:  # a damaged header fails in numpy's parser as anything (TokenError, SyntaxError, ...)
            raise InputError(f"{path}: not a readable NPY array ({type(exc).__name__}: {exc})") from None
    else:
        image = _open_image(path, "a depth image")
        mode = image.mode
        if mode in ("RGB", "RGBA", "P", "L", "LA", "CMYK", "YCbCr", "1"):
            raise InputError(
                f"{path}: an 8-bit {mode} image, not a depth image (16-bit PNG in millimetres, float TIFF or NPY in "
                "metres); if it is the colour image, give its depth image and this one with --color"
            )
        raw = np.asarray(image)
    if raw.ndim == 3 and raw.shape[2] == 1:
        raw = raw[:, :, 0]
    if raw.ndim != 2:
        raise InputError(f"{path}: an array of shape {raw.shape}, not one (height, width) depth image")
    if raw.dtype.kind == "f":
        with np.errstate(over="ignore"):  # float64 beyond float32's range: inf, no depth (as NaN is)
            depth = raw.astype(np.float32)
    elif raw.dtype.kind in "ui":
        depth = _units_to_m(raw, scale_m)
    else:
        raise InputError(f"{path}: depth of type {raw.dtype}; expected 16-bit integers or float metres")
    return depth


def read_color(path: Path) -> np.ndarray:
    """(H, W, 3) uint8 RGB of a colour image file."""
    path = Path(path)
    image = _open_image(path, "a colour image")
    if image.mode not in ("RGB", "RGBA", "P", "L", "LA"):
        raise InputError(f"{path}: a {image.mode} image, not an 8-bit colour image; give the colour PNG")
    return np.asarray(image if image.mode == "RGB" else image.convert("RGB"))


def color_pair(depth_path: Path, images: ImageSettings) -> Path | None:
    """The colour image the naming rule pairs with ``depth_path`` (`<stem><depth_suffix>.x`
    -> `<stem><color_suffix>.png|.jpg|.x`), when it exists."""
    stem = depth_path.stem
    if not stem.endswith(images.depth_suffix):
        return None
    base = stem[: len(stem) - len(images.depth_suffix)] + images.color_suffix
    for suffix in (".png", ".jpg", ".jpeg", depth_path.suffix):
        candidate = depth_path.with_name(base + suffix)
        if candidate.is_file():
            return candidate
    return None


def frame_name(path: Path, images: ImageSettings | None = None) -> str:
    """The name a depth image's outputs take: its stem without the depth suffix."""
    suffix = or_defaults(images).depth_suffix
    stem = path.stem
    return stem[: len(stem) - len(suffix)] if stem.endswith(suffix) and len(stem) > len(suffix) else stem


def find_intrinsics(depth_path: Path, images: ImageSettings) -> CameraModel:
    """The intrinsics for ``depth_path``: [images] intrinsics when set, else the one
    intrinsics file beside it (several that disagree: an error asking which)."""
    if images.intrinsics:
        return read_intrinsics(images.intrinsics)
    found = [depth_path.parent / n for n in INTRINSICS_NAMES if (depth_path.parent / n).is_file()]
    if not found:
        raise InputError(
            f"{depth_path}: a depth image needs the camera's intrinsics: give --intrinsics FILE (ROS camera_info "
            f'YAML, Open3D JSON, camera_params.json) or --intrinsics "fx fy cx cy", or put one of '
            f"{', '.join(INTRINSICS_NAMES[:3])} beside it"
        )
    models = [read_intrinsics(p) for p in found]
    first = models[0]
    for p, m in zip(found[1:], models[1:]):
        same = (m.fx, m.fy, m.cx, m.cy, m.width, m.height, m.distorted) == (
            first.fx,
            first.fy,
            first.cx,
            first.cy,
            first.width,
            first.height,
            first.distorted,
        ) and (not m.distorted or (m.distortion_model, m.distortion) == (first.distortion_model, first.distortion))
        if not same:
            raise InputError(
                f"{depth_path}: the intrinsics files beside it disagree ({found[0].name}, {p.name}); "
                "name the right one with --intrinsics"
            )
    return first


_executor: ThreadPoolExecutor | None = None


def _decoder() -> ThreadPoolExecutor:
    """One helper thread for decoding colour images, made on first use."""
    global _executor
    if _executor is None:
        _executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="clear-colour")
    return _executor


def read_image_frame(path: Path, images: ImageSettings | None = None, color: Path | None = None) -> Frame:
    """The organized frame of the depth image at ``path`` (see the module)."""
    path = Path(path)
    images = or_defaults(images)
    color_path = Path(color) if color is not None else color_pair(path, images)
    # The colour PNG decodes in a second thread while the depth is read and projected:
    # zlib lets go of the GIL, and the two decodes are most of a pair's reading time.
    pending = _decoder().submit(read_color, color_path) if color_path is not None else None
    try:
        depth = read_depth_m(path, images.depth_scale_m)
        h, w = depth.shape
        if not np.any(np.isfinite(depth) & (depth > 0)):
            raise InputError(f"{path}: every pixel of the depth image is 0 (no reading); is it the right file?")
        model = find_intrinsics(path, images)
        model.check_size(w, h, f"{path} ({w} x {h})")
        points = back_project(depth, model)
    except BaseException:
        if pending is not None:
            pending.cancel()
        raise
    colors = None
    note = ""
    if pending is not None:
        rgb = pending.result()
        if rgb.shape[:2] != (h, w):
            # the depth alone still makes a frame: segmentation runs on geometry and its
            # --json says why there was no colour (a warning on stderr says it too)
            note = (
                f"{color_path}: the colour image is {rgb.shape[1]} x {rgb.shape[0]} but its depth image {path} is "
                f"{w} x {h}; colour left out (give the colour image registered to the depth: aligned_depth_to_color)"
            )
            logging.getLogger(__name__).warning(note)
        else:
            colors = np.ascontiguousarray(rgb.reshape(-1, 3))
    return Frame(points=points, colors=colors, shape=(h, w), source=str(path), color_note=note)
