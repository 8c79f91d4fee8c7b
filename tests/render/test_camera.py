"""clearcli/render/camera.py: the camera's colour picture with segments outlined on it."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from clearcli.render.camera import outlined


def test_outlines_are_drawn_inside_their_segment_and_every_other_pixel_is_the_images() -> None:
    rng = np.random.default_rng(0)
    h, w = 40, 60
    rgb = rng.integers(0, 256, size=(h * w, 3), dtype=np.uint8)
    rows, cols = np.mgrid[10:20, 15:35]  # a 10 x 20 rectangle
    box = (rows * w + cols).ravel()
    out = outlined(rgb, (h, w), [box], [(1.0, 0.0, 0.0)], width_px=2)
    image = rgb.reshape(h, w, 3)
    painted = np.any(out != image, axis=2)
    # the outline: two pixels wide along the rectangle's border, inside it, pure red
    ring = np.zeros((h, w), bool)
    ring[10:20, 15:35] = True
    ring[12:18, 17:33] = False
    assert np.array_equal(painted & ~ring, np.zeros_like(painted))  # nothing painted off the ring
    assert np.all(out[ring] == (255, 0, 0))
    assert np.array_equal(out[~ring], image[~ring])  # the image's own pixels everywhere else


def test_the_segmentation_picture_of_a_colour_frame_shows_the_camera_image(tmp_path: Path) -> None:
    from helpers import shared_path
    from PIL import Image

    from clearcli import pipeline
    from clearcli.io.read import read_frame
    from clearcli.render.segment_png import render_segmentation
    from clearcli.settings import Settings

    depth = shared_path("rgbd/uois/uois_0003_depth.png")
    frame = read_frame(depth)
    seg = pipeline.segmented(frame, Settings())
    with_colour, without = tmp_path / "c.png", tmp_path / "g.png"
    render_segmentation(with_colour, frame, seg)
    from dataclasses import replace

    render_segmentation(without, replace(frame, colors=None), seg)

    def n_colours(p: Path) -> int:
        return len(np.unique(np.asarray(Image.open(p).convert("RGB")).reshape(-1, 3), axis=0))

    # the camera's picture carries the image's colours: several times the colours of the
    # same picture with segments painted flat (whose only shades are antialiasing)
    assert n_colours(with_colour) > 4 * n_colours(without)
