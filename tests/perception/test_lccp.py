"""Tests of clearcli/perception/lccp.py."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from helpers.segment import S


# ------------------------------------------------------------------ 3. supervoxels + LCCP
def _fold(sign: float) -> np.ndarray:
    """A 20 x 20 cm sheet folded along y at x = 0, seen from the origin: sign +1 a ridge
    towards the camera (convex), -1 a valley (concave). 1.5 mm sampling."""
    x, y = np.meshgrid(np.arange(-0.1, 0.1, 0.0015), np.arange(-0.1, 0.1, 0.0015))
    z = 0.8 + sign * 0.8 * np.abs(x)
    return np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)


@pytest.mark.parametrize("sign, n_segments", [(1.0, 1), (-1.0, 2)])
def test_lccp_joins_convex_and_cuts_concave(sign: float, n_segments: int) -> None:
    from clearcli.perception.lccp import lccp_segments
    from clearcli.perception.supervoxels import compute_supervoxels, voxelize

    vox = voxelize(_fold(sign), S.voxel_m)
    # the 26-neighbourhood on a regular grid: interior voxels have neighbours
    assert vox.edges.shape[0] > vox.n_voxels
    sv = compute_supervoxels(vox, np.zeros(3), S)
    # about one supervoxel per seed cell of the (tilted) sheet
    assert 50 <= sv.centroids.shape[0] <= 300
    assert np.all(np.einsum("ij,ij->i", sv.normals, -sv.centroids) > 0)  # facing the camera
    seg = lccp_segments(sv, S)
    assert int(seg.max()) + 1 == n_segments
    if n_segments == 2:  # the cut is the fold
        xs = sv.centroids[:, 0]
        far = np.abs(xs) > 0.02
        assert len(set(zip((xs[far] > 0).tolist(), seg[far].tolist()))) == 2


def _shallow_valley(slope: float) -> np.ndarray:
    """A 20 x 20 cm sheet bent along y at x = 0 into a valley away from the origin
    camera: the halves' normals differ by 2 atan(slope). 1.5 mm sampling."""
    x, y = np.meshgrid(np.arange(-0.1, 0.1, 0.0015), np.arange(-0.1, 0.1, 0.0015))
    z = 0.8 - slope * np.abs(x)
    return np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)


@pytest.mark.parametrize(
    "slope, two_colours, n_segments",
    [
        (0.0, False, 1),  # a flat face of one colour
        (0.0, True, 1),  # a print on a flat face: no seam, stays one
        (0.18, False, 1),  # a 20 degree valley of one colour: within the 30 degree tolerance
        (0.18, True, 2),  # ... of two colours: two objects meeting in a shallow seam
    ],
)
def test_lccp_colour_cue_cuts_shallow_seams_between_colours(slope: float, two_colours: bool, n_segments: int) -> None:
    from clearcli.perception.lccp import lccp_segments
    from clearcli.perception.supervoxels import compute_supervoxels, voxelize

    vox = voxelize(_shallow_valley(slope), S.voxel_m)
    sv = compute_supervoxels(vox, np.zeros(3), S)
    # red (L 50, a 60) left of the seam, blue-grey (L 50, a -10, b -20) right: dE 73
    right = sv.centroids[:, 0] > 0
    lab = np.where(right[:, None] & two_colours, [50.0, -10.0, -20.0], [50.0, 60.0, 0.0])
    cue = dataclasses.replace(S, lccp_color_delta=40.0, lccp_color_tolerance_deg=10.0)
    seg = lccp_segments(sv, cue, sv_lab=lab)
    assert int(seg.max()) + 1 == n_segments
    # off, or without colour, the tolerance alone decides: one segment
    assert int(lccp_segments(sv, dataclasses.replace(S, lccp_color_delta=0.0), sv_lab=lab).max()) == 0
    assert int(lccp_segments(sv, cue).max()) == 0
