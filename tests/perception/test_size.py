"""Tests of clearcli/perception/size.py: the sizes a frame's segmentation counts in,
worked out by hand."""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from helpers.segment import S

from clearcli.perception.size import SegmentSize


def test_the_default_sizes_by_hand() -> None:
    """5 mm voxels, 3 cm seeds, 10 cm^2 smallest object, 5 supervoxels smallest segment,
    20 cm^2 a cut's side, 5 cm^2 a depth edge's piece."""
    size = SegmentSize.of(S)
    assert (size.voxel_m, size.seed_m, size.normal_radius_m) == (0.005, 0.03, 0.015)
    assert size.voxel_area_m2 == pytest.approx(25e-6, rel=1e-12)
    assert size.seed_voxels == pytest.approx(36.0)  # (30 mm / 5 mm)^2
    # 10 cm^2 / 0.25 cm^2 = 40 voxels, whichever way it is rounded
    assert size.min_object_voxels == 40 and size.min_object_voxels_unrounded == pytest.approx(40.0)
    assert not size.holds_object_area(np.array([39]))[0] and size.holds_object_area(np.array([40]))[0]
    assert size.min_segment_voxels == 180  # 5 seeds of 36 voxels
    assert size.min_side_voxels == 180  # max(20 cm^2 = 80 voxels, 180)
    assert size.min_side_voxels_stacks == pytest.approx(80.0)  # without LCCP's segment
    assert size.min_edge_piece_voxels == 20  # 5 cm^2 / 0.25 cm^2
    assert size.min_seed_voxels == 3  # a tenth of 36, rounded down


def test_a_finer_voxel_rounds_the_smallest_object_apart() -> None:
    """3 mm voxels (0.09 cm^2): 10 cm^2 is 111.1 voxels. The stages that round down
    leave segments alone below 111, those comparing the unrounded count or the area
    want 112: the reason each keeps its own."""
    size = SegmentSize.of(replace(S, voxel_m=0.003))
    assert size.voxel_area_m2 == pytest.approx(9e-6, rel=1e-12)
    assert size.min_object_voxels == 111
    assert size.min_object_voxels_unrounded == pytest.approx(1000 / 9)
    assert size.holds_object_area(np.array([111, 112])).tolist() == [False, True]
    assert size.seed_voxels == pytest.approx(100.0)  # (30 mm / 3 mm)^2
    assert size.min_segment_voxels == 500
    assert size.min_side_voxels == 500  # max(20 cm^2 = 222.2 voxels, 500)
    assert size.min_side_voxels_stacks == pytest.approx(2000 / 9)
    assert size.min_edge_piece_voxels == 55  # 5 / 0.09 = 55.6
    assert size.min_seed_voxels == 10


def test_a_sparse_cloud_grows_the_voxel_and_everything_counted_in_it() -> None:
    """Points 1 cm apart on a grid: the voxel grows to 1.5 spacings (15 mm, 3 times the
    setting), the seed (9 cm) and the normal radius (4.5 cm) with it. A seed still
    holds 36 voxels; the smallest object, 10 cm^2 of 2.25 cm^2 voxels, is 4.4."""
    g = np.arange(0.0, 0.3, 0.01)
    x, y = np.meshgrid(g, g)
    grid = np.column_stack([x.ravel(), y.ravel(), np.full(x.size, 0.8)])
    size = SegmentSize.of(S, grid)
    assert size.voxel_m == pytest.approx(0.015)
    assert size.seed_m == pytest.approx(0.09) and size.normal_radius_m == pytest.approx(0.045)
    assert size.seed_voxels == pytest.approx(36.0)
    assert size.min_object_voxels == 4 and size.min_object_voxels_unrounded == pytest.approx(40 / 9)
    assert size.holds_object_area(np.array([4, 5])).tolist() == [False, True]
    assert size.min_segment_voxels == 180
    assert size.min_side_voxels_stacks == pytest.approx(80 / 9)  # 20 cm^2 / 2.25 cm^2
    assert size.min_edge_piece_voxels == 2
    # points denser than the grid (2 mm apart), or too few to judge: the settings' sizes
    assert SegmentSize.of(S, grid / 5) == SegmentSize.of(S)
    assert SegmentSize.of(S, grid[:9]) == SegmentSize.of(S)


def test_no_stage_reads_the_density_fitted_lengths_from_the_settings() -> None:
    """voxel_m, seed_m and normal_radius_m grow on a sparse cloud: every perception
    module reads them (and every count made of them) from the frame's SegmentSize."""
    import clearcli.perception as perception

    pattern = re.compile(r"\b(settings|s|scaled|seg_settings)\.(voxel_m|seed_m|normal_radius_m)\b")
    offenders = [
        f"{path.name}:{n}"
        for path in sorted(Path(perception.__file__).parent.glob("*.py"))
        # size.py fits them; resolution.py picks the working grid from the nominal voxel
        # before the frame's SegmentSize exists (that grid is what it is fitted on)
        if path.name not in ("size.py", "resolution.py")
        for n, line in enumerate(path.read_text().splitlines(), 1)
        if pattern.search(line)
    ]
    assert offenders == []
