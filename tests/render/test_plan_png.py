"""Tests of clearcli/render/plan_png.py: the plan drawn over the table, robot base frame."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from helpers import FIXTURES

from clearcli.settings import Settings
from clearcli.tasks import plan as task
from clearcli.tasks.base import Outputs, Source

GOAL_RGB = (0x4C / 255, 0x9A / 255, 0x2A / 255)
TABLE_RGB = (0xE8 / 255, 0xE2 / 255, 0xD0 / 255)


def _pixels_near(img: np.ndarray, rgb: tuple[float, float, float], tol: float = 0.02) -> int:
    return int((np.abs(img[..., :3] - np.array(rgb)) < tol).all(axis=-1).sum())


def test_plan_picture_draws_the_table_and_the_objects_it_removes(tmp_path: Path) -> None:
    import matplotlib.image

    png = tmp_path / "plan.png"
    out = task.run(
        task.Request(Settings(), outputs=Outputs.of(png=png)), Source(str(FIXTURES / "two_touching_boxes.pcd"))
    )
    assert out.payload["status"] == "complete" and len(out.payload["goal"]) == 2
    img = matplotlib.image.imread(png)
    # the fixture has colour: the camera's picture (7 x 7 inches) beside the top view (7 x 7) at 110 dpi
    assert img.shape[:2] == (770, 1540)
    assert _pixels_near(img, TABLE_RGB) > 2000
    # both boxes in the goal's colour, drawn at alpha 0.75 over the table
    over_table = tuple(0.75 * g + 0.25 * t for g, t in zip(GOAL_RGB, TABLE_RGB))
    assert _pixels_near(img, over_table) > 150
    assert _pixels_near(img, GOAL_RGB) > 50  # and its legend patch
