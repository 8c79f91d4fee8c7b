"""clearcli/io/images.py: depth images (+ colour, + intrinsics) read as the frame a PCD gives."""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest
from helpers import shared_path

from clearcli.errors import InputError
from clearcli.io.images import read_image_frame
from clearcli.io.pcd import read_pcd
from clearcli.io.read import read_frame
from clearcli.settings.images import ImageSettings

UOIS = "rgbd/uois"


def _pair(k: int) -> tuple[Path, Path]:
    return shared_path(f"{UOIS}/uois_{k:04d}_depth.png"), shared_path(f"scenes/uois_realsense/uois_image_{k:04d}.pcd")


@pytest.mark.parametrize("k", range(9))
def test_the_png_pair_is_the_pcd_point_for_point_with_its_colour(k: int) -> None:
    depth, pcd = _pair(k)
    got, want = read_frame(depth), read_pcd(pcd)
    assert got.shape == want.shape == (480, 640)
    np.testing.assert_array_equal(got.points, want.points)  # NaN where NaN, float for float
    np.testing.assert_array_equal(got.colors, want.colors)


def test_segmentation_of_the_png_pair_equals_the_pcds() -> None:
    from clearcli import pipeline
    from clearcli.settings import Settings

    settings = Settings()
    for k in range(9):
        depth, pcd = _pair(k)
        a = pipeline.segmented(read_frame(depth), settings).labels()
        b = pipeline.segmented(read_pcd(pcd), settings).labels()
        np.testing.assert_array_equal(a, b)


def _copy_uois(tmp_path: Path, k: int = 3, intrinsics: bool = True) -> Path:
    depth, _ = _pair(k)
    for name in (depth.name, depth.name.replace("_depth", "_color")) + (("camera_params.json",) if intrinsics else ()):
        shutil.copy(depth.parent / name, tmp_path / name)
    return tmp_path / depth.name


def test_float_tiff_and_npy_in_metres_and_other_units_give_the_same_points(tmp_path: Path) -> None:
    from PIL import Image

    png = _copy_uois(tmp_path)
    want = read_frame(png)
    mm = np.asarray(Image.open(png)).astype(np.float32)
    metres = mm / np.float32(1000)
    Image.fromarray(metres, mode="F").save(tmp_path / "m_depth.tif")
    np.save(tmp_path / "n_depth.npy", metres)
    np.save(tmp_path / "u_depth.npy", (mm * 10).astype(np.uint32))  # tenths of a millimetre
    for name, scale in (("m_depth.tif", 0.001), ("n_depth.npy", 0.001), ("u_depth.npy", 0.0001)):
        got = read_image_frame(tmp_path / name, ImageSettings(depth_scale_m=scale))
        np.testing.assert_allclose(got.points, want.points, rtol=1e-6, atol=1e-7, equal_nan=True)
        assert got.colors is None  # no m_color.png beside it: no colour, not a wrong one


def test_intrinsics_as_four_numbers_equal_the_file(tmp_path: Path) -> None:
    png = _copy_uois(tmp_path, intrinsics=False)
    got = read_image_frame(png, ImageSettings(intrinsics="612.937 613.173 322.549 248.158"))
    np.testing.assert_array_equal(got.points, read_frame(_pair(3)[0]).points)


def test_a_colour_image_is_never_taken_for_depth(tmp_path: Path) -> None:
    png = _copy_uois(tmp_path)
    with pytest.raises(InputError, match="8-bit RGB image, not a depth image.*--color"):
        read_frame(png.with_name("uois_0003_color.png"))


@pytest.mark.parametrize(
    "damage, words",
    [
        ("truncated", "damaged or truncated"),
        ("not_png", "not a PNG file"),
        ("all_zero", "every pixel of the depth image is 0"),
        ("intrinsics_size", "the intrinsics .* are for 1280 x 720"),
        ("no_intrinsics", "needs the camera's intrinsics"),
        ("fx_zero", "fx"),
    ],
)
def test_bad_image_inputs_are_one_input_error(tmp_path: Path, damage: str, words: str) -> None:
    import json

    from PIL import Image

    png = _copy_uois(tmp_path, intrinsics=damage != "no_intrinsics")
    png.with_name("uois_0003_color.png")
    params = tmp_path / "camera_params.json"
    if damage == "truncated":
        data = png.read_bytes()
        png.write_bytes(data[: len(data) // 2])
    elif damage == "not_png":
        png.write_bytes(b"this is not an image at all\n" * 10)
    elif damage == "all_zero":
        Image.fromarray(np.zeros((480, 640), np.uint16)).save(png)
    elif damage in ("intrinsics_size", "fx_zero"):
        p = json.loads(params.read_text())
        p.update({"img_width": 1280, "img_height": 720} if damage == "intrinsics_size" else {"fx": 0})
        params.write_text(json.dumps(p))
    with pytest.raises(InputError, match=words):
        read_frame(png)


def test_a_colour_image_of_another_size_is_left_out_and_said_so(tmp_path: Path) -> None:
    # the depth alone makes the frame (segmentation runs on geometry); the frame says why
    # it has no colour, for --json
    from PIL import Image

    png = _copy_uois(tmp_path)
    color = png.with_name("uois_0003_color.png")
    Image.open(color).resize((320, 240)).save(color)
    got = read_frame(png)
    assert got.colors is None and got.n_points == 640 * 480
    assert "colour image is 320 x 240 but its depth image" in got.color_note and "left out" in got.color_note


def test_intrinsics_files_beside_it_that_disagree_ask_which(tmp_path: Path) -> None:
    png = _copy_uois(tmp_path)
    (tmp_path / "intrinsics.json").write_text(
        '{"fx": 600, "fy": 600, "x_offset": 320, "y_offset": 240, "img_width": 640, "img_height": 480}'
    )
    with pytest.raises(InputError, match="disagree.*--intrinsics"):
        read_frame(png)
    assert read_image_frame(png, ImageSettings(intrinsics=str(tmp_path / "intrinsics.json"))).n_points == 640 * 480


def test_float64_depth_beyond_float32_is_no_depth_and_no_warning(tmp_path: Path) -> None:
    from clearcli.io.images import read_depth_m

    depth = np.full((3, 4), 0.75)
    depth[1, 2] = 1e300  # a flipped exponent bit: no sensor's depth
    np.save(tmp_path / "f_depth.npy", depth)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        metres = read_depth_m(tmp_path / "f_depth.npy", 0.001)
    assert metres.dtype == np.float32 and np.isinf(metres[1, 2])
    assert (np.delete(metres.ravel(), 1 * 4 + 2) == np.float32(0.75)).all()


def test_a_truncated_tiff_is_one_error_and_no_library_warning(tmp_path: Path) -> None:
    from PIL import Image

    from clearcli.io.images import read_depth_m

    Image.fromarray(np.full((48, 64), 0.8, np.float32)).save(tmp_path / "whole.tif")
    (tmp_path / "cut.tif").write_bytes((tmp_path / "whole.tif").read_bytes()[:30])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(InputError, match="cut.tif: "):
            read_depth_m(tmp_path / "cut.tif", 0.001)
