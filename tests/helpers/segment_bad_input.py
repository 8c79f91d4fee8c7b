"""Helpers that several test modules share (from the tests of segment_bad_input)."""

from __future__ import annotations

import numpy as np

from clearcli.io.frames import Frame
from clearcli.settings.segment import SegmentSettings
from clearcli.sim.scene import (
    TABLE_SIZE_X_M,
    TABLE_SIZE_Y_M,
    Box,
    Cylinder,
    Scene,
    make_scene,
)

S = SegmentSettings()


# 2 cm^2 of visible surface (8 voxels of 5 mm): less than each tiny object shows above the
# prism, where the default (10 cm^2) is more than some of them do
LOW_AREA_M2 = 0.0002


# ------------------------------------------------------------------ helpers
def _tiny_scene() -> Scene:
    """Five objects 1.5-2.5 cm across, 1.5-2.5 cm tall, apart: 130-220 points each at
    ~0.9 m, of which the prism (its floor 1.4 cm above the table at that range) keeps
    the upper part."""
    return make_scene(
        "tiny",
        [
            Box(0, 0.02, 0.02, 0.02, x_m=-0.15, y_m=-0.05, yaw_rad=0.3),
            Cylinder(1, 0.01, 0.025, x_m=0.0, y_m=0.05),
            Box(2, 0.015, 0.015, 0.015, x_m=0.12, y_m=-0.08),
            Box(3, 0.025, 0.02, 0.02, x_m=0.18, y_m=0.1, yaw_rad=-0.5),
            Cylinder(4, 0.0125, 0.02, x_m=-0.1, y_m=0.12),
        ],
    )


# One object spanning the table, and what makes each one hard: `height` is the height of
# its top above the table, which is what segmentation should take for the support.
SPANNING: dict[str, tuple[Scene, float]] = {
    # a board covering the whole table: no table in view, and the board's front side
    # (3 cm, too small to be a plane of its own) is seen below its top
    "board": (make_scene("board", [Box(0, TABLE_SIZE_X_M, TABLE_SIZE_Y_M, 0.03, 0.0, 0.0)]), 0.03),
    # the same with a box on it: the box is the one object
    "board_with_box": (
        make_scene(
            "board_with_box",
            [
                Box(0, TABLE_SIZE_X_M, TABLE_SIZE_Y_M, 0.03, 0.0, 0.0),
                Box(1, 0.05, 0.04, 0.08, x_m=0.1, y_m=0.0, yaw_rad=0.4, base_z_m=0.03),
            ],
        ),
        0.03,
    ),
    # a tall box leaving a 5 cm rim of table, less than a table's least area
    # (`table_min_area_m2`): its front face is a big plane facing the camera, a wall
    "tall_box": (make_scene("tall_box", [Box(0, 0.70, 0.50, 0.25, 0.0, 0.0)]), 0.25),
    # a tall box as big as the table
    "tall_full": (make_scene("tall_full", [Box(0, TABLE_SIZE_X_M, TABLE_SIZE_Y_M, 0.30, 0.0, 0.0)]), 0.30),
}


def _two_boxes() -> Scene:
    return make_scene(
        "two_boxes",
        [
            Box(0, 0.05, 0.04, 0.08, x_m=-0.1, y_m=0.0, yaw_rad=0.4),
            Box(1, 0.06, 0.05, 0.06, x_m=0.1, y_m=0.05),
        ],
    )


def _unorganized(frame: Frame, seed: int) -> Frame:
    """The frame as an unorganized cloud: NaN rows dropped, points shuffled, no grid;
    colours and labels follow their points."""
    finite = np.flatnonzero(frame.finite_mask)
    order = finite[np.random.default_rng(seed).permutation(finite.size)]
    return Frame(
        points=frame.points[order],
        colors=None if frame.colors is None else frame.colors[order],
        shape=None,
        fields={"label": frame.fields["label"][order]},
        source=f"{frame.source} (unorganized)",
    )
