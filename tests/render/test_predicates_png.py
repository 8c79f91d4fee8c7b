"""Tests of clearcli/render/predicates_png.py: the top view of the symbolic state."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from helpers import FIXTURES

from clearcli.settings import Settings
from clearcli.tasks import predicates as task
from clearcli.tasks.base import Outputs, Source


def test_predicates_picture_is_the_table_seen_from_above(tmp_path: Path) -> None:
    import matplotlib.image

    png = tmp_path / "pred.png"
    out = task.run(task.Request(Settings(), outputs=Outputs.of(png=png)), Source(str(FIXTURES / "box_on_box.pcd")))
    assert "(on o1 o0)" in out.payload["facts"] or "(on o0 o1)" in out.payload["facts"]
    img = matplotlib.image.imread(png)
    assert img.shape[:2] == (900, 900)  # 9 x 9 inches at 100 dpi
    table = (np.abs(img[..., :3] - 0.93) < 0.01).all(axis=-1).sum()
    assert table > 10000  # the table polygon, light grey
    colours = {tuple(c) for c in np.round(img[..., :3].reshape(-1, 3), 2)}
    assert len(colours) > 20  # objects, arrows and labels besides the table
