"""Tests of clearcli/render/segment_png.py: the picture of a segmentation."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from helpers import FIXTURES

from clearcli.render.segment_png import label_colors
from clearcli.settings import Settings
from clearcli.tasks import segment as task
from clearcli.tasks.base import Outputs, Source

TAB20_FIRST = (0x1F / 255, 0x77 / 255, 0xB4 / 255)  # matplotlib's tab20, colour 0


def test_label_colours_by_hand() -> None:
    cols = label_colors(np.array([0, 1, 10, 20, 10]), 2)
    np.testing.assert_allclose(cols[0], (0.93, 0.93, 0.93))  # no label: pale
    np.testing.assert_allclose(cols[1], (0.78, 0.78, 0.78))  # table: grey
    np.testing.assert_allclose(cols[2], TAB20_FIRST, atol=1e-3)  # object 0
    assert not np.allclose(cols[3], cols[2])  # object 1 differs
    np.testing.assert_allclose(cols[4], cols[2])  # the same object, the same colour


def _pixels_near(img: np.ndarray, rgb: tuple[float, float, float], tol: float = 0.02) -> int:
    return int((np.abs(img[..., :3] - np.array(rgb)) < tol).all(axis=-1).sum())


def test_picture_shows_the_object_in_its_colour(tmp_path: Path) -> None:
    import matplotlib.image

    png = tmp_path / "seg.png"
    out = task.run(task.Request(Settings(), Outputs.of(png=png)), Source(str(FIXTURES / "isolated_box.pcd")))
    assert len(out.payload["objects"]) == 1 and out.written == (png,)
    img = matplotlib.image.imread(png)
    assert img.shape[:2] == (520, 1300)  # 13 x 5.2 inches at 100 dpi
    # the box in object 0's colour: filled in the top view, outlined over the camera's
    # own colours in the camera view (the fixture has colour)
    assert _pixels_near(img, TAB20_FIRST) > 200
    assert _pixels_near(img, (0.78, 0.78, 0.78)) > 5000  # the table
