"""Tests of clearcli/perception/occlusion.py."""

from __future__ import annotations

from dataclasses import replace

import pytest
from helpers import shared_path
from helpers.foreign import judged
from helpers.segment import S

from clearcli.evaluate.segmentation import score


def test_occlusion_merge_on_a_real_occluded_frame() -> None:
    """learn28: a tall box in front cuts the box behind it in two; LCCP alone gives
    three segments, the occlusion merge two."""
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment

    frame = read_frame(shared_path("mosd/learn/learn28.pcd"))
    off = score(segment(frame, replace(S, occlusion_merge=False)).labels(), frame.fields["label"])
    on = score(segment(frame, S).labels(), frame.fields["label"])
    assert (off.n_pred, off.over_segmented) == (3, 1)
    assert (on.n_pred, on.true_positives, on.f1) == (2, 2, 1.0)


def _sheet_over_two_boxes(T_camera_table: object = None):  # -> Frame
    """Two 8 x 8 x 4 cm boxes 12 cm apart and a 16 x 12 x 3 cm package lying across
    them: their tops stand on one plane at one height, and the package hides the gap
    between them, 3 cm in front of it over a 16-20 cm span (a ratio near 0.2)."""
    import numpy as np

    from clearcli.sim.camera import render
    from clearcli.sim.scene import Box, make_scene

    objs = [
        Box(0, 0.08, 0.08, 0.04, x_m=-0.10, y_m=0.0),
        Box(1, 0.08, 0.08, 0.04, x_m=0.10, y_m=0.0),
        Box(2, 0.16, 0.12, 0.03, x_m=0.0, y_m=0.0, base_z_m=0.04),
    ]
    T = None if T_camera_table is None else np.asarray(T_camera_table, dtype=float)
    return render(make_scene("package over two boxes", objs, T_camera_table=T), seed=1)


# the default oblique camera, and one 0.8 m straight above the table (a bin's camera)
_TOP_DOWN = [[1, 0, 0, 0], [0, -1, 0, 0], [0, 0, -1, 0.8], [0, 0, 0, 1]]


@pytest.mark.parametrize("T_camera_table", [None, _TOP_DOWN], ids=["oblique", "top_down"])
def test_a_flat_package_lying_over_two_boxes_does_not_join_them(
    T_camera_table: object, monkeypatch: pytest.MonkeyPatch
) -> None:
    from clearcli.evaluate.exact import exact_report
    from clearcli.perception import colors
    from clearcli.perception.segment import segment

    frame = _sheet_over_two_boxes(T_camera_table)
    on = exact_report(segment(frame, S).labels(), frame.fields["label"])
    assert on.verdicts == ("right", "right", "right")
    # without the depth ratio the package passes for an occluder and the boxes join; the
    # colour stage parts them again since stop 64 (two boxes of two colours, colors.py
    # step 5): with that off too, they stay joined
    off = exact_report(segment(frame, replace(S, occlusion_min_depth_ratio=0.0)).labels(), frame.fields["label"])
    assert off.verdicts == ("right", "right", "right")
    monkeypatch.setattr(colors, "_PART_DE", float("inf"))
    off = exact_report(segment(frame, replace(S, occlusion_min_depth_ratio=0.0)).labels(), frame.fields["label"])
    assert off.verdicts == ("merged", "merged", "right")


def test_no_joins_under_the_package_in_a_bin() -> None:
    """gqcnn_phoxi_dexnet4_0 (choose part): a card package lies across a bin's clutter;
    the segments it covers at one height were joined (a yellow case with a Neosporin
    box and a white cup, a grey comb with a beige package) though it stands only 0.15-0.21
    of the gap in front of the gap lines."""
    verdicts, _, _ = judged("gqcnn_phoxi_dexnet4_0")
    assert verdicts["yellow case"] == "right" and verdicts["grey comb"] == "right"
    # the LCCP colour cue alone keeps the yellow case apart: off too, to see the ratio's part
    off, _, _ = judged("gqcnn_phoxi_dexnet4_0", occlusion_min_depth_ratio=0.0, lccp_color_delta=0.0)
    assert off["yellow case"] == "merged" and off["grey comb"] == "merged"
