"""Tests of clearcli/perception/colors.py (colour splits, off by default), by hand."""

from __future__ import annotations

import numpy as np

from clearcli.perception.supervoxels import Supervoxels

RED = [50.0, 70.0, 50.0]  # CIELAB
BLUE = [30.0, 20.0, -60.0]


def _patches(wall: bool) -> tuple[Supervoxels, np.ndarray]:
    """Two red patches on a horizontal top, two blue ones beside them: a wall rising
    from the top's edge (``wall``: the seam is concave, a can on a tin) or the same top
    going on (a print)."""
    if wall:
        centroids = [[0.0, 0, 0], [-0.03, 0, 0], [0.02, 0, 0.02], [0.02, 0, 0.05]]
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


def test_colour_splits_a_concave_seam_not_a_print() -> None:
    from clearcli.perception.colors import color_splits

    one = np.zeros(4, dtype=np.int64)
    sv, lab = _patches(wall=True)
    out = color_splits(one, sv, lab, 25.0, 60)
    assert out[0] == out[1] and out[2] == out[3] and out[0] != out[2]
    sv, lab = _patches(wall=False)
    assert np.all(color_splits(one, sv, lab, 25.0, 60) == 0)
    # colours closer than the threshold: nothing to cut
    sv, lab = _patches(wall=True)
    assert np.all(color_splits(one, sv, np.array([RED, RED, RED, RED]), 25.0, 60) == 0)
    # pieces smaller than the smallest object join back
    assert np.all(color_splits(one, sv, lab, 25.0, 1000) == 0)
