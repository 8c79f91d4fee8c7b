"""Depth images (clearcli/io/images.py): a 16-bit PNG, a float TIFF or an NPY array, with
its colour image and intrinsics found by the naming rule ([images])."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from clearcli.io.formats.base import SingleFrame, describe_frame
from clearcli.io.sniff import NPY_MAGIC, PNG_MAGIC, TIFF_MAGICS

if TYPE_CHECKING:
    from clearcli.io.frames import Frame
    from clearcli.settings.images import ImageSettings

# Suffixes of depth images (a folder search takes those with the depth suffix in the name).
IMAGE_SUFFIXES = (".png", ".tif", ".tiff", ".npy")


class DepthImage(SingleFrame):
    name = "image"
    what = "a depth image"
    takes_color = True
    suffixes = IMAGE_SUFFIXES

    def recognises(self, path: Path, head: bytes) -> bool:
        return head.startswith(PNG_MAGIC) or head.startswith(TIFF_MAGICS) or head.startswith(NPY_MAGIC)

    def misnamed(self, path: Path) -> str | None:
        if path.suffix.lower() in IMAGE_SUFFIXES:
            return (
                f"{path}: not a {path.suffix[1:].upper()} file (unrecognised first bytes); is it truncated or renamed?"
            )
        return None

    def searched(self, path: Path, images: ImageSettings) -> bool:
        """A depth image by the naming rule (a folder search takes only these: a colour
        image goes with its depth image)."""
        return path.suffix.lower() in IMAGE_SUFFIXES and path.stem.endswith(images.depth_suffix)

    def output_name(self, path: Path, images: ImageSettings) -> str | None:
        if not self.searched(path, images):
            return None
        from clearcli.io.images import frame_name  # noqa: PLC0415  (NumPy and io.images, ~100 ms: see formats/base.py)

        return frame_name(path, images)

    def reads_with(self, path: Path, images: ImageSettings, color: Path | None) -> list[Path] | None:
        """The colour image (--color, or the one the naming rule pairs) and the
        intrinsics file ([images] intrinsics, or the ones beside the image)."""
        if path.suffix.lower() not in IMAGE_SUFFIXES:
            return None
        from clearcli.io.images import INTRINSICS_NAMES, color_pair  # noqa: PLC0415  (NumPy and io.images, ~100 ms: see formats/base.py)

        found: list[Path] = []
        paired = Path(color) if color else color_pair(path, images)
        if paired is not None:
            found.append(paired)
        if images.intrinsics and Path(images.intrinsics).is_file():
            found.append(Path(images.intrinsics))
        elif not images.intrinsics:
            found.extend(path.parent / n for n in INTRINSICS_NAMES)
        return found

    def read(self, path: Path, images: ImageSettings | None, color: Path | None) -> Frame:
        from clearcli.io.images import read_image_frame  # noqa: PLC0415  (NumPy and io.images, ~100 ms: see formats/base.py)

        return read_image_frame(path, images, color)

    def describe(
        self, path: Path, topic: str | None, index: int, images: ImageSettings | None, color: Path | None
    ) -> dict[str, Any]:
        return describe_image(self.read_frame(path, topic, index, images, color), path, images, color)


def describe_image(frame: Frame, path: Path, images: Any = None, color: Path | None = None) -> dict[str, Any]:
    """The info payload of a depth image, from the frame it made: its size, depth range,
    the intrinsics found and the colour image paired with it."""
    from clearcli.io.images import color_pair, find_intrinsics, or_defaults  # noqa: PLC0415  (NumPy and io.images, ~100 ms: see formats/base.py)

    images = or_defaults(images)
    z = frame.points[:, 2]
    valid = z[frame.finite_mask]  # a pixel's depth is its point's z
    model = find_intrinsics(path, images)  # read once already: the reader keeps it
    paired = Path(color) if color is not None else color_pair(path, images)
    assert frame.shape is not None  # depth images make organized frames
    image_part = {
        "width": int(frame.shape[1]),
        "height": int(frame.shape[0]),
        "depth_scale_m": images.depth_scale_m,
        "valid_pixels": int(valid.size),
        "depth_min_m": round(float(valid.min()), 6) if valid.size else None,
        "depth_max_m": round(float(valid.max()), 6) if valid.size else None,
        "intrinsics": {
            "fx": model.fx,
            "fy": model.fy,
            "cx": model.cx,
            "cy": model.cy,
            "width": model.width,
            "height": model.height,
            "distortion_model": model.distortion_model or None,
            "distorted": model.distorted,
            "source": model.source,
        },
        "color": str(paired) if paired is not None else None,
    }
    return {"file": str(path), "format": "depth-image", "image": image_part, "frame": describe_frame(frame, 0)}


FORMAT = DepthImage()
