"""Tests of clearcli/perception/lccp.py."""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np
import pytest
from helpers.segment import S

if TYPE_CHECKING:
    from clearcli.perception.supervoxels import Supervoxels, VoxelCloud


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


# ------------------------------------------------------------------ smoothness near its allowance
def _two_patches(step_m: float) -> tuple[VoxelCloud, Supervoxels]:
    """Two flat patches of 5 x 5 voxels facing +z side by side along x (A at x < 0, B at
    x > 0), B raised by ``step_m`` where they touch; the voxels and the two supervoxels
    (labels 0 and 1, normals +z, one adjacency), their centroids as the voxels give them."""
    from clearcli.perception.size import SegmentSize
    from clearcli.perception.supervoxels import Supervoxels, voxelize

    voxel_m = SegmentSize.of(S).voxel_m
    i, j = np.meshgrid(np.arange(-5, 5), np.arange(5), indexing="ij")
    x = (i.ravel() + 0.5) * voxel_m
    y = (j.ravel() + 0.5) * voxel_m
    z = np.where(x > 0, step_m, 0.0)
    vox = voxelize(np.stack([x, y, z], axis=1), voxel_m)
    label = (vox.centroids[:, 0] > 0).astype(np.int64)
    centroids = np.stack([vox.centroids[label == k].mean(axis=0) for k in (0, 1)])
    sv = Supervoxels(
        voxel_label=label,
        centroids=centroids,
        normals=np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]]),
        n_voxels=np.bincount(label),
        edges=np.array([[0, 1]]),
    )
    return vox, sv


def test_boundary_step_is_the_offset_where_the_patches_touch() -> None:
    from clearcli.perception.lccp import boundary_steps_m

    vox, sv = _two_patches(0.0002)
    # every voxel pair across x = 0 (the 26-neighbourhood: 5 straight, 8 diagonal in y)
    # is offset by the 0.2 mm step along the normals, which are parallel (no tilt)
    assert boundary_steps_m(sv, vox, np.array([0])) == pytest.approx([0.0002], abs=1e-12)
    assert boundary_steps_m(sv, vox, np.zeros(0, dtype=np.int64)).shape == (0,)


def _at_allowance(step_m: float, eps_m: float) -> tuple[VoxelCloud, Supervoxels]:
    """Two patches with ``step_m`` where they touch, their centroids moved as another
    make-up of the supervoxels would put them: B's raised so that their offset along
    the (parallel) normals is the smoothness allowance + ``eps_m``."""
    from clearcli.perception.size import SegmentSize

    allowance_m = S.smoothness_threshold * SegmentSize.of(S).voxel_m
    vox, sv = _two_patches(step_m)
    centroids = sv.centroids.copy()
    centroids[1, 2] = centroids[0, 2] + allowance_m + eps_m
    return vox, dataclasses.replace(sv, centroids=centroids)


@pytest.mark.parametrize("eps_m", [-1e-9, 1e-9])
def test_smoothness_at_its_allowance_is_decided_where_the_patches_touch(eps_m: float) -> None:
    """A pair whose centroids are offset along their normals by the allowance (here
    smoothness_threshold * voxel: parallel normals) +- a nanometre: without the voxels
    the answer flips with the sign of eps; with them it is the boundary's, a 0.2 mm step,
    under the 0.5 mm allowance: smooth either way (issue 37: one voxel more or less in a
    supervoxel moved such an offset by 0.33 mm on gqcnn_primesense_4)."""

    from clearcli.perception.lccp import convex_edges
    from clearcli.perception.size import SegmentSize

    vox, sv = _at_allowance(0.0002, eps_m)
    assert convex_edges(sv, S, SegmentSize.of(S)).tolist() == [eps_m < 0]
    assert convex_edges(sv, S, SegmentSize.of(S), vox=vox).tolist() == [True]


@pytest.mark.parametrize("eps_m", [-1e-9, 1e-9])
def test_a_real_step_at_the_allowance_stays_a_step(eps_m: float) -> None:
    """The same pair with a 0.8 mm step where the patches touch: a step, whichever side
    of the allowance the centroids' offset falls."""

    from clearcli.perception.lccp import convex_edges
    from clearcli.perception.size import SegmentSize

    vox, sv = _at_allowance(0.0008, eps_m)
    assert convex_edges(sv, S, SegmentSize.of(S), vox=vox).tolist() == [False]
