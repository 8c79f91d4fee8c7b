"""Depth and colour images as input: section [images] (every frame-reading command)."""

from __future__ import annotations

from dataclasses import dataclass

from clearcli.settings.fields import Section, param

# [images] depth_suffix / color_suffix: a name ending, far below the 255 bytes of a file name
MAX_SUFFIX_BYTES = 64


@dataclass(frozen=True)
class ImageSettings(Section):
    NAME = "images"

    # The camera's intrinsics for depth images read from files: a ROS calibration YAML,
    # an Open3D PinholeCameraIntrinsic JSON, a camera_params.json (fx, fy, x_offset,
    # y_offset) or "fx fy cx cy". Empty: the one intrinsics file beside the depth image
    # (`--intrinsics` sets it). Logs carry their own (CameraInfo).
    intrinsics: str = param("", text='"", an intrinsics file, or "fx fy cx cy"')
    # Metres per unit of an integer depth image (16-bit PNG, uint16 NPY, 16UC1 messages):
    # millimetres, as RealSense, Kinect and most datasets write them. Float images are metres.
    # A nanometre is finer than any depth sensor's unit; below it the metres of a unit
    # underflow float32 (every depth 0) and its reciprocal overflows.
    depth_scale_m: float = param(0.001, ge=1e-9, le=10)
    # The naming rule for folders of image pairs: `<stem><depth_suffix>.png` is a depth
    # frame, `<stem><color_suffix>.png` its colour image; outputs are named `<stem>`.
    depth_suffix: str = param("_depth", text="a non-empty name ending")
    color_suffix: str = param("_color", text="a name ending other than depth_suffix")

    def cross_checks(self) -> None:
        for key in ("depth_suffix", "color_suffix"):
            # the ending of a file name beside the depth image: a "/" would name another
            # folder (pathlib refuses it), and a long one a name past the file system's 255 bytes
            value = getattr(self, key)
            if "/" in value or "\x00" in value:
                self.fail(key, "a name ending holds no '/' (nor NUL): it names a file beside the depth image")
            if len(value.encode("utf-8", "surrogatepass")) > MAX_SUFFIX_BYTES:
                self.fail(key, f"a name ending of at most {MAX_SUFFIX_BYTES} bytes")
        if not self.depth_suffix:
            self.fail("depth_suffix", "must not be empty (a folder's colour images would be taken for depth)")
        if self.color_suffix == self.depth_suffix:
            self.fail("color_suffix", "must differ from depth_suffix")
