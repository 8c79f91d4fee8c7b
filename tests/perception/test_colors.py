"""Tests of clearcli/perception/colors.py (colour splits where one object lies on or
against another), by hand."""

from __future__ import annotations

import numpy as np

from clearcli.perception.supervoxels import Supervoxels

RED = [50.0, 70.0, 50.0]  # CIELAB
BLUE = [30.0, 20.0, -60.0]
GREEN = [60.0, -60.0, 50.0]
RISE_M = 0.01


def _patches(wall: bool, rise_m: float = 0.02) -> tuple[Supervoxels, np.ndarray]:
    """Two red patches on a horizontal top, two blue ones beside them: a wall rising
    ``rise_m`` from the top's edge (``wall``: another object standing against it) or
    the same top going on (a print)."""
    if wall:
        centroids = [[0.0, 0, 0], [-0.03, 0, 0], [0.02, 0, rise_m], [0.02, 0, rise_m + 0.03]]
        normals = [[0, 0, 1.0], [0, 0, 1], [-1, 0, 0], [-1, 0, 0]]
    else:
        centroids = [[0.0, 0, 0], [-0.03, 0, 0], [0.03, 0, 0], [0.06, 0, 0]]
        normals = [[0, 0, 1.0]] * 4
    sv = Supervoxels(
        voxel_label=np.arange(4),
        centroids=np.array(centroids),
        normals=np.array(normals, dtype=float),
        n_voxels=np.full(4, 50),
        edges=np.array([[0, 1], [0, 2], [2, 3]]),
    )
    return sv, np.array([RED, RED, BLUE, BLUE])


def test_colour_splits_a_rising_seam_not_a_print() -> None:
    from clearcli.perception.colors import color_splits

    one = np.zeros(4, dtype=np.int64)
    sv, lab = _patches(wall=True)
    out = color_splits(one, sv, sv.centroids, lab, 25.0, RISE_M, 60)
    assert out[0] == out[1] and out[2] == out[3] and out[0] != out[2]
    sv, lab = _patches(wall=False)
    assert np.all(color_splits(one, sv, sv.centroids, lab, 25.0, RISE_M, 60) == 0)
    # colours closer than the threshold: nothing to cut
    sv, lab = _patches(wall=True)
    assert np.all(color_splits(one, sv, sv.centroids, np.array([RED, RED, RED, RED]), 25.0, RISE_M, 60) == 0)
    # pieces smaller than the smallest object join back
    assert np.all(color_splits(one, sv, sv.centroids, lab, 25.0, RISE_M, 1000) == 0)


def test_a_shallow_concave_bend_joins_back() -> None:
    """The blue pair continues the red top with a 10 degree concave bend (a label on a
    curved lid, a bowl's wall): concave, but neither patch rises 10 mm out of the
    other's plane (3 and 2 mm), so one object."""
    from clearcli.perception.colors import color_splits

    tilt = np.radians(10.0)
    bent = [-np.sin(tilt), 0.0, np.cos(tilt)]
    sv = Supervoxels(
        voxel_label=np.arange(4),
        centroids=np.array([[0.0, 0, 0], [-0.03, 0, 0], [0.03, 0, 0.003], [0.06, 0, 0.008]]),
        normals=np.array([[0, 0, 1.0], [0, 0, 1], bent, bent]),
        n_voxels=np.full(4, 50),
        edges=np.array([[0, 1], [0, 2], [2, 3]]),
    )
    lab = np.array([RED, RED, BLUE, BLUE])
    one = np.zeros(4, dtype=np.int64)
    assert np.all(color_splits(one, sv, sv.centroids, lab, 25.0, RISE_M, 60) == 0)
    # the same seam with a lower threshold is a seam
    out = color_splits(one, sv, sv.centroids, lab, 25.0, 0.002, 60)
    assert out[0] == out[1] and out[2] == out[3] and out[0] != out[2]


def test_pieces_apart_stay_apart_through_a_third_piece() -> None:
    """A red top with a blue wall standing on it (apart) and a small green patch touching
    both with flat seams: the green patch joins one of them, and red and blue stay two."""
    from clearcli.perception.colors import color_splits

    centroids = [[0.0, 0, 0], [0.02, 0, 0.02], [0.0, 0.03, 0.0], [0.02, 0.03, 0.0]]
    normals = [[0, 0, 1.0], [-1, 0, 0], [0, 0, 1], [0, 0, 1]]
    sv = Supervoxels(
        voxel_label=np.arange(4),
        centroids=np.array(centroids),
        normals=np.array(normals, dtype=float),
        n_voxels=np.array([80, 80, 80, 10]),
        edges=np.array([[0, 1], [0, 2], [2, 3], [3, 1]]),
    )
    lab = np.array([RED, BLUE, RED, GREEN])
    out = color_splits(np.zeros(4, dtype=np.int64), sv, sv.centroids, lab, 25.0, RISE_M, 60)
    assert out[0] == out[2] and out[0] != out[1]
    assert out[3] in (out[0], out[1])
    # two segments at the start: nothing joins across them
    seg = np.array([0, 0, 1, 1])
    out = color_splits(seg, sv, sv.centroids, lab, 25.0, RISE_M, 60)
    assert len({int(out[0]), int(out[2])}) == 2


def test_a_segment_in_two_parts_stays_one_without_a_seam() -> None:
    """Two red patches and two blue ones, the colours touching only across a gap (one
    object whose middle a nearer one hides, joined by occlusion.py): no adjacency, no
    seam, one segment."""
    from clearcli.perception.colors import color_splits

    sv = Supervoxels(
        voxel_label=np.arange(4),
        centroids=np.array([[0.0, 0, 0], [-0.03, 0, 0], [0.1, 0, 0.0], [0.13, 0, 0.0]]),
        normals=np.array([[0, 0, 1.0]] * 4),
        n_voxels=np.full(4, 50),
        edges=np.array([[0, 1], [2, 3], [1, 0]]),
    )
    lab = np.array([RED, BLUE, RED, BLUE])
    out = color_splits(np.zeros(4, dtype=np.int64), sv, sv.centroids, lab, 25.0, RISE_M, 60)
    assert np.all(out == 0)


def test_a_piece_split_off_joins_the_object_of_its_colour() -> None:
    """Segment 0: a red top and the lower part of a blue wall standing on it (LCCP left
    the wall's foot with the top); segment 1: the rest of the blue wall. The foot is apart
    from the top (its seam rises) and continues the blue wall (same colour, flat seam):
    it joins segment 1. Without the blue wall beside it, it stays a segment of its own."""
    from clearcli.perception.colors import color_splits

    sv = Supervoxels(
        voxel_label=np.arange(4),
        centroids=np.array([[0.0, 0, 0], [-0.03, 0, 0], [0.02, 0, 0.02], [0.02, 0, 0.05]]),
        normals=np.array([[0, 0, 1.0], [0, 0, 1], [-1, 0, 0], [-1, 0, 0]]),
        n_voxels=np.array([80, 80, 70, 70]),
        edges=np.array([[0, 1], [0, 2], [2, 3]]),
    )
    lab = np.array([RED, RED, BLUE, BLUE])
    out = color_splits(np.array([0, 0, 0, 1]), sv, sv.centroids, lab, 25.0, RISE_M, 60)
    assert out[0] == out[1] and out[2] == out[3] and out[0] != out[2]
    # the rest of the wall green: the foot is a segment of its own
    out = color_splits(np.array([0, 0, 0, 1]), sv, sv.centroids, np.array([RED, RED, BLUE, GREEN]), 25.0, RISE_M, 60)
    assert len({int(out[0]), int(out[2]), int(out[3])}) == 3


def test_a_segment_in_two_parts_of_two_colours_is_two_without_any_cut() -> None:
    """A red part and a blue part of one segment that touch nowhere (occlusion.py joined
    two objects seen either side of a nearer one), each of one colour: no adjacency
    differs in colour, so no colour cut anywhere in the frame, and still the parts are
    judged by their mean colours (step 5): two segments. One colour: one segment."""
    from clearcli.perception.colors import color_splits

    sv = Supervoxels(
        voxel_label=np.arange(4),
        centroids=np.array([[0.0, 0, 0], [-0.03, 0, 0], [0.1, 0, 0.0], [0.13, 0, 0.0]]),
        normals=np.array([[0, 0, 1.0]] * 4),
        n_voxels=np.full(4, 50),
        edges=np.array([[0, 1], [2, 3]]),
    )
    one = np.zeros(4, dtype=np.int64)
    out = color_splits(one, sv, sv.centroids, np.array([RED, RED, BLUE, BLUE]), 25.0, RISE_M, 60)
    assert out[0] == out[1] and out[2] == out[3] and out[0] != out[2]
    assert np.all(color_splits(one, sv, sv.centroids, np.array([RED, RED, RED, RED]), 25.0, RISE_M, 60) == 0)
