"""Tests of clearcli/perception/cuts.py."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from helpers.segment import S


def _two_box_patches(with_lower_box: bool):  # type: ignore[no-untyped-def]
    """Hand-made supervoxels (table frame, z up, camera at -y) of a 6 cm wide, 10 cm tall
    box A (front face y = -0.025, top z = 0.1) and, touching its right side, a 4 cm wide,
    6 cm tall box B with its front face in A's front plane. Each patch: 5 x 5 voxels
    6 mm apart in its face. Returns (names, Supervoxels, voxel centroids)."""
    from clearcli.perception.supervoxels import Supervoxels

    front, top = np.array([0.0, -1.0, 0.0]), np.array([0.0, 0.0, 1.0])
    patches: dict[str, tuple[tuple[float, float, float], np.ndarray]] = {}
    for i, x in enumerate((-0.045, -0.015)):
        for k, z in enumerate((0.02, 0.05, 0.08)):
            patches[f"af{i}{k}"] = ((x, -0.025, z), front)
        for j, y in enumerate((-0.01, 0.015)):
            patches[f"at{i}{j}"] = ((x, y, 0.1), top)
    if with_lower_box:
        for i, x in enumerate((0.01, 0.03)):
            for k, z in enumerate((0.02, 0.045)):
                patches[f"bf{i}{k}"] = ((x, -0.025, z), front)
            for j, y in enumerate((-0.01, 0.015, 0.035)):
                patches[f"bt{i}{j}"] = ((x, y, 0.06), top)
    names = list(patches)
    cent = np.array([patches[n][0] for n in names])
    nor = np.array([patches[n][1] for n in names])
    grid = np.arange(-2, 3) * 0.006
    u, v = [a.ravel() for a in np.meshgrid(grid, grid)]
    voxels, labels = [], []
    for s, (c, n) in enumerate(zip(cent, nor)):
        # in-face axes: x and the face's other axis
        other = np.array([0.0, 0.0, 1.0]) if n[2] == 0 else np.array([0.0, 1.0, 0.0])
        voxels.append(c + u[:, None] * np.array([1.0, 0.0, 0.0]) + v[:, None] * other)
        labels.append(np.full(u.size, s))
    # adjacent: centroids closer than ~1.4 seed spacings (a patch's 8 neighbours)
    d = np.linalg.norm(cent[:, None] - cent[None], axis=-1)
    a, b = np.nonzero(np.triu(d < 0.042, 1))
    sv = Supervoxels(np.concatenate(labels), cent, nor, np.full(len(names), u.size), np.stack([a, b], axis=1))
    return names, sv, np.concatenate(voxels)


@pytest.mark.parametrize("with_lower_box", [True, False])
def test_planar_cut_splits_coplanar_touching_boxes(with_lower_box: bool) -> None:
    from helpers.refine import hand_context

    from clearcli.perception.cuts import concave_adjacencies, planar_cuts, seam_rise
    from clearcli.perception.lccp import lccp_segments

    names, sv, voxels = _two_box_patches(with_lower_box)
    seg = lccp_segments(sv, S)
    # LCCP alone: one segment, joined through the coplanar front faces
    assert int(seg.max()) == 0
    out = planar_cuts(seg, hand_context(voxels, sv, S))  # the table z = 0, z up
    if not with_lower_box:  # a lone box has only the odd edge adjacencies: no cut
        assert int(out.max()) == 0
        return
    # the seam A's front (its patch above B's top) - B's top: A's patch rises 32 mm out of
    # B's top plane (0.08 + 0.012 - 0.06); the patch beside it reaches 2 mm
    e = [tuple(p) for p in sv.edges.tolist()]
    seam = e.index((names.index("af12"), names.index("bt00")))
    low = e.index((names.index("af11"), names.index("bt00")))
    assert concave_adjacencies(sv, S)[[seam, low]].all()
    rise = seam_rise(sv, voxels, sv.edges[[seam, low]])
    assert rise == pytest.approx([0.032, 0.002], abs=1e-9)
    # the cut is the plane between the boxes: A's patches one side, B's the other
    box_b = np.array([n.startswith("b") for n in names])
    assert int(out.max()) == 1
    assert len(set(out[box_b].tolist())) == 1 and len(set(out[~box_b].tolist())) == 1
    assert out[box_b][0] != out[~box_b][0]
    # off: untouched
    assert np.array_equal(planar_cuts(seg, hand_context(voxels, sv, replace(S, cut_min_score=0.9))), seg)


def test_seam_rise_with_the_contexts_voxels_by_supervoxel_is_the_rise_it_sorts_itself() -> None:
    """The two boxes' patches with their voxels shuffled (a supervoxel's voxels apart in
    the voxel order): given `RefineContext.voxels_by_sv` the rise is the one seam_rise
    works out from its own sort, bit for bit, and still A's 32 mm and 2 mm out of B's
    top; every adjacency's rise on both sides agrees too."""
    from dataclasses import replace as dc_replace

    from helpers.refine import hand_context

    from clearcli.perception.cuts import seam_rise

    names, sv, voxels = _two_box_patches(True)
    perm = np.random.default_rng(3).permutation(voxels.shape[0])
    sv = dc_replace(sv, voxel_label=sv.voxel_label[perm])
    voxels = voxels[perm]
    by_sv = hand_context(voxels, sv, S).voxels_by_sv
    e = [tuple(p) for p in sv.edges.tolist()]
    pick = sv.edges[
        [e.index((names.index("af12"), names.index("bt00"))), e.index((names.index("af11"), names.index("bt00")))]
    ]
    assert seam_rise(sv, voxels, pick, by_sv) == pytest.approx([0.032, 0.002], abs=1e-9)
    assert np.array_equal(seam_rise(sv, voxels, sv.edges, by_sv), seam_rise(sv, voxels, sv.edges))
