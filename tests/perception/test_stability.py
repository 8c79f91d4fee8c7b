"""Segmentation is stable under rounding-sized changes (issue 37): every frame of the
shared mOSD set (50), the nine uois RealSense frames and the fixtures, moved by a
uniform +-1 micrometre per coordinate (fixed seed), gives the same objects: as many,
each matched at IoU >= 0.95. Without ../shared/data the shared sets skip (and fail
under CLEAR_REQUIRE_SHARED=1). benchmarks/stability.py finds the step a flip starts in.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers import FIXTURES, shared_path


def _changed(paths: list[Path]) -> list[str]:
    """The frames of ``paths`` whose objects change under +-1 um, each with how (a frame
    refused for want of a table must be refused as well when moved)."""
    from clearcli.errors import ClearError
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment
    from clearcli.perception.stability import object_matches, perturbed, same_objects
    from clearcli.settings.segment import SegmentSettings

    settings = SegmentSettings()
    out = []
    for path in paths:
        frame = read_frame(path)
        try:
            before = segment(frame, settings)
        except ClearError:
            try:
                segment(perturbed(frame, 1e-6, seed=0), settings)
            except ClearError:
                continue
            out.append(f"{path.name}: refused, but not when moved")
            continue
        after = segment(perturbed(frame, 1e-6, seed=0), settings)
        if not same_objects(before, after):
            worst = min([1.0, *object_matches(before, after), *object_matches(after, before)])
            out.append(f"{path.name}: {len(before.objects)} -> {len(after.objects)} objects, worst IoU {worst:.3f}")
    return out


@pytest.mark.parametrize(
    ("where", "pattern", "count"),
    [("mosd", "*/*.pcd", 50), ("scenes/uois_realsense", "*.pcd", 9)],
    ids=["mosd", "uois"],
)
def test_shared_frames_keep_their_objects_under_a_micrometre(where: str, pattern: str, count: int) -> None:
    paths = sorted(shared_path(where).glob(pattern))
    assert len(paths) == count, f"{where}: {len(paths)} frames, expected {count}"
    assert _changed(paths) == []


# The other labs' frames: the target names only the sets above, but a user's frames come
# from sensors like these. Two Asus Xtion frames stored in float metres (points anywhere
# relative to the voxel grid, where whole-millimetre depth keeps off its boundaries)
# still change: a micrometre creates or empties voxels of one point and moves points
# between voxels, whose full weight in the normals' PCA (the 30 nearest centroids, most
# neighbourhoods cut at the 30th) turns neighbouring normals by up to 13 degrees, and
# the supervoxels' first assignments follow. Weighing a voxel by its points (up to 4)
# mended both but changed cleargrasp_000000130 and split three uois frames more (stop
# 46's note); weights falling smoothly to 0 at the normal radius mended them and PCL's
# milk_cartoon_all_small_clorox (which flips under seeds 1 and 2, not the 0 used here)
# but split mOSD learn42 and the wide_objects family more (h3-stab's experiment, reverted).
# Neither was taken. gqcnn_primesense_4's flip under seed 0 (a pair of supervoxels whose
# smoothness margin was 0.02 mm) was mended at LCCP, by deciding pairs near the
# smoothness allowance at their boundary (lccp.boundary_steps_m). The test fails on a new
# flip, and on a known one mended, so that this list is kept true.
_KNOWN_FLIPS = {"gqcnn_primesense_3.pcd"}


@pytest.mark.parametrize(
    ("where", "count"),
    [("scenes/gqcnn", 7), ("scenes/cleargrasp_d435", 4), ("scenes/pcl", 6), ("scenes/industrial", 2)],
    ids=["gqcnn", "cleargrasp", "pcl", "industrial"],
)
def test_other_labs_frames_change_under_a_micrometre_only_where_known(where: str, count: int) -> None:
    paths = sorted(shared_path(where).rglob("*.pcd"))  # pcl's grabber_sequence in its folder
    assert len(paths) == count, f"{where}: {len(paths)} frames, expected {count}"
    changed = _changed(paths)
    assert {line.split(":")[0] for line in changed} == _KNOWN_FLIPS & {p.name for p in paths}, changed


# Frames allowed for choosing whose objects the default voxel normals changed under
# these perturbation seeds (benchmarks/flips.py, seeds 0-19: gqcnn_primesense_4 under 4
# of 20, 4 6 11 18, uois_image_0000 under 2), each flip starting at the supervoxels
# (a few voxels change supervoxel and the supervoxels' normals turn by tens of degrees:
# flips.py --margins). uois_image_0000's two are mended since at the vessels stage
# (test_a_handle_cut_by_the_walls_boundary_keeps_its_objects); gqcnn_primesense_4's remain.
_FLIPPING_SEEDS = {"gqcnn/gqcnn_primesense_4.pcd": (4, 6, 11), "uois_realsense/uois_image_0000.pcd": (5, 9)}
# Seeds under which gqcnn_primesense_4 flipped before LCCP decided pairs near the
# smoothness allowance at their boundary: one voxel more in a supervoxel of 26 moved the
# offset of a pair of near-parallel patches from 0.02 mm under the allowance to 0.31 mm
# over it; the step where the two touch moved by 0.02 mm (0.65 -> 0.63 mm).
_SMOOTHNESS_SEEDS = (0, 8, 17, 19)


def test_pairs_near_the_smoothness_allowance_keep_gqcnn_primesense_4_objects() -> None:
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment
    from clearcli.perception.stability import perturbed, same_objects
    from clearcli.settings.segment import SegmentSettings

    settings = SegmentSettings()
    frame = read_frame(shared_path("scenes") / "gqcnn/gqcnn_primesense_4.pcd")
    before = segment(frame, settings)
    changed = [s for s in _SMOOTHNESS_SEEDS if not same_objects(before, segment(perturbed(frame, 1e-6, s), settings))]
    assert changed == []


def test_a_handle_cut_by_the_walls_boundary_keeps_its_objects() -> None:
    """uois_image_0000 under seeds 5 and 9: the supervoxels' boundary moves by a few voxels
    and LCCP's boundary between the mug's two wall segments with it; it runs through the
    handle, which `vessels` judged part by part (each segment's leftover on its own), the
    lower part taken for something leaning on the mug and the upper part given to the mug,
    so 69 of the handle's 300 points went from one to the other (IoU 0.77). The rim
    holders' leftovers are now judged as one piece wherever they touch (vessels.py), and
    the frame keeps its objects under both seeds (it failed under both before)."""
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment
    from clearcli.perception.stability import perturbed, same_objects
    from clearcli.settings.segment import SegmentSettings

    settings = SegmentSettings()
    frame = read_frame(shared_path("scenes") / "uois_realsense/uois_image_0000.pcd")
    before = segment(frame, settings)
    changed = [s for s in (5, 9) if not same_objects(before, segment(perturbed(frame, 1e-6, s), settings))]
    assert changed == []


@pytest.mark.parametrize("name", sorted(_FLIPPING_SEEDS))
def test_stencil_normals_keep_the_objects_the_default_flips(name: str) -> None:
    """With normal_stencil (supervoxels.weighted_voxel_normals: the points of a fixed
    stencil of cells, a voxel weighing up to 4 points) the frames keep their objects
    under the seeds that change them with the default normals (issue 37). Off by default:
    it loses 4 of 89 objects on the foreign choose part (settings.segment)."""
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment
    from clearcli.perception.stability import perturbed, same_objects
    from clearcli.settings.segment import SegmentSettings

    settings = SegmentSettings(normal_stencil=True)
    frame = read_frame(shared_path("scenes") / name)
    before = segment(frame, settings)
    changed = [
        s for s in _FLIPPING_SEEDS[name] if not same_objects(before, segment(perturbed(frame, 1e-6, s), settings))
    ]
    assert changed == []


# Where each of these flips starts (hE-flips, benchmarks/flips.py and /tmp traces of
# supervoxel_labels): gqcnn_primesense_4 under seeds 4, 6, 11 and 18 moves one point
# (0.605 um under a cell side in x) into the next voxel; the seed voxel it leaves (3 -> 2
# points) moves 0.73 mm and its normal, the least eigenvector of its 30 nearest centroids
# whose two least eigenvalues are nearly equal (1.48 and 1.74e-5 m^2), turns 17 degrees;
# the first assignment around it follows (cost margins 0.23-0.36). uois_image_0000 under
# seed 9: a first assignment within 1.6e-4 of a tie (5 um of distance) passes one voxel
# between two seeds, the seeds move, three voxels follow in the second assignment (margins
# 0.03-0.11) and join two pieces of one seed, and 22 voxels change supervoxel; under seed
# 5 a voxel of 1 -> 2 points (cost margin 0.003) passes to another seed, and in the second
# assignment a voxel joins a supervoxel of 17 whose normal's source switches (eigenvalue
# ratio 3.44 -> 4.27) and turns 36 degrees.
_TENSOR_SEEDS = {"gqcnn/gqcnn_primesense_4.pcd": (4, 6, 11, 18), "uois_realsense/uois_image_0000.pcd": (5, 9)}


@pytest.mark.parametrize("name", sorted(_TENSOR_SEEDS))
def test_seed_normal_tensors_keep_the_objects_the_default_flips(name: str) -> None:
    """With seed_normal_spread 1 (supervoxels.seed_normal_tensors: the first normal of a
    seed whose two least eigenvalues lie within a factor 2 spreads over both directions,
    continuously) the frames keep their objects under the seeds that change them by default. Off by default: it
    brings flips on uois_image_0006 and splits 2 foreign choose objects (settings.segment)."""
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment
    from clearcli.perception.stability import perturbed, same_objects
    from clearcli.settings.segment import SegmentSettings

    settings = SegmentSettings(seed_normal_spread=1.0)
    frame = read_frame(shared_path("scenes") / name)
    before = segment(frame, settings)
    changed = [s for s in _TENSOR_SEEDS[name] if not same_objects(before, segment(perturbed(frame, 1e-6, s), settings))]
    assert changed == []


def test_fixtures_keep_their_objects_under_a_micrometre() -> None:
    paths = sorted(FIXTURES.glob("*.pcd"))
    assert len(paths) >= 4
    assert _changed(paths) == []


def test_the_perturbation_moves_every_coordinate_by_at_most_a_micrometre() -> None:
    from clearcli.io.frames import Frame
    from clearcli.perception.stability import perturbed

    pts = np.random.default_rng(3).uniform(0.2, 2.0, size=(5000, 3)).astype(np.float32)
    moved = perturbed(Frame(points=pts), 1e-6, seed=0).points
    step = moved.astype(np.float64) - pts.astype(np.float64)
    assert moved.dtype == np.float32
    assert np.abs(step).max() <= 1e-6 + 2e-7  # float32 rounding at 2 m is 1.2e-7
    assert (step != 0).mean() > 0.9  # a move under half a float32 step (6e-8 at 1-2 m) rounds away
    assert np.array_equal(moved, perturbed(Frame(points=pts), 1e-6, seed=0).points)  # fixed seed


def test_same_objects_sees_a_changed_object() -> None:
    from clearcli.perception.stability import same_objects
    from clearcli.perception.types import Segmentation, SegmentedObject, TablePlane

    def seg(*groups: range) -> Segmentation:
        objs = tuple(
            SegmentedObject(np.array(g), np.zeros(3), np.zeros(3), np.eye(3), np.ones(3), np.eye(3)) for g in groups
        )
        return Segmentation(1000, TablePlane(np.array([0.0, 0.0, 1.0]), 0.0), np.zeros((0, 3)), np.zeros(0, int), objs)

    base = seg(range(0, 100), range(100, 400))
    assert same_objects(base, seg(range(0, 100), range(100, 400)))
    assert same_objects(base, seg(range(0, 98), range(98, 400)))  # 2 of 100 points: IoU 0.98
    assert not same_objects(base, seg(range(0, 90), range(90, 400)))  # IoU 0.90
    assert not same_objects(base, seg(range(0, 400)))  # merged
    assert not same_objects(base, seg(range(0, 100), range(100, 250), range(250, 400)))  # split


def test_depth_in_whole_millimetres_stays_in_its_voxel() -> None:
    """Real depth is stored in whole millimetres: a fifth of the points lie on a multiple
    of the 5 mm voxel. The grid's boundaries lie off the millimetre, so a micrometre moves
    none of them (floor(z / 5 mm) put each on either side by float rounding)."""
    from clearcli.io.frames import Frame
    from clearcli.perception.stability import perturbed
    from clearcli.perception.supervoxels import grid_cells

    rng = np.random.default_rng(5)
    z = rng.integers(500, 1500, size=20000) / 1000.0  # whole millimetres
    xy = rng.uniform(-0.3, 0.3, size=(20000, 2)) * z[:, None]
    pts = np.column_stack([xy, z]).astype(np.float32)
    moved = perturbed(Frame(points=pts), 1e-6, seed=1).points
    a = grid_cells(pts.astype(np.float64), 0.005)
    b = grid_cells(moved.astype(np.float64), 0.005)
    on_boundary = np.abs(z * 1000 / 5 - np.round(z * 1000 / 5)) < 1e-9
    assert on_boundary.mean() > 0.15  # a fifth of the depths are multiples of 5 mm
    # x and y are on no lattice: a point within a micrometre of a boundary may move
    # (about 2e-4 of them); none moves along z
    assert (a[:, 2] == b[:, 2]).all()
    assert (a != b).any(axis=1).mean() < 1e-3
