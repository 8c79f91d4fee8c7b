"""Tests of clearcli/perception/segment.py."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from helpers import shared_path
from helpers.segment import (
    S,
    _render,
    box_frame,  # noqa: F401  (fixtures)
)
from helpers.segment_bad_input import (
    LOW_AREA_M2,
    SPANNING,
    _tiny_scene,
    _two_boxes,
    _unorganized,
)

from clearcli.evaluate.segmentation import score
from clearcli.io.frames import Frame
from clearcli.perception.segment import segment
from clearcli.perception.types import Segmentation
from clearcli.sim.camera import render
from clearcli.sim.scene import Box, Cylinder, Scene, make_scene


# ------------------------------------------------------------------ 4. whole stage, synthetic
def test_isolated_box_one_object_true_size(box_frame: Frame) -> None:
    from clearcli.perception.segment import segment

    seg = segment(box_frame, S)
    assert len(seg.objects) == 1
    obj = seg.objects[0]
    assert obj.obb_extents == pytest.approx([0.05, 0.04, 0.08], abs=0.01)
    # the box axes: third along the table normal, first along the 5 cm side (30 deg yaw)
    assert np.allclose(obj.obb_axes[2], seg.table.normal)
    assert np.allclose(obj.obb_axes @ obj.obb_axes.T, np.eye(3), atol=1e-9)
    assert np.linalg.det(obj.principal_axes) == pytest.approx(1.0)
    # the bottom of the box is on the table, its top 8 cm above
    bottom = seg.table.height_of(obj.obb_center) - obj.obb_extents[2] / 2
    assert bottom == pytest.approx(0.0, abs=1e-9)
    assert score(seg.labels(), box_frame.fields["label"]).f1 == 1.0
    assert set(seg.timings_s) >= {"filter", "table", "supervoxels", "lccp", "total"}
    # indices point into the original frame (NaN rows kept in place)
    assert np.isfinite(box_frame.points[obj.indices]).all()


def test_timings_keep_their_names_order_and_sums(box_frame: Frame) -> None:
    """`segment` times its steps by name with one clock: the keys the JSON reports, in
    their order; "merge" every refinement but the planar cuts; the named steps within
    the total."""
    from clearcli.perception.refine import STAGES
    from clearcli.perception.segment import STEPS, TIMINGS, segment

    stages = [st.name for st in STAGES]
    # a key each: every named step, every refinement, "merge" and "total"
    assert len(set(TIMINGS)) == len(TIMINGS)
    assert set(TIMINGS) == {st.name for st in STEPS if st.name} | set(stages) | {"merge", "total"}
    # in the JSON's order: the first stages and the depth edges, the refinements in the
    # order they run, the steps after them, the total
    n = len(stages)
    assert TIMINGS[:6] == ("filter", "table", "supervoxels", "lccp", "merge", "edges")
    assert TIMINGS[6 : 6 + n] == tuple(stages) and TIMINGS[6 + n :] == (
        "flat",
        "objects",
        "exclude",
        "openings",
        "total",
    )
    t = segment(box_frame, S).timings_s
    assert list(t) == list(TIMINGS)
    assert t["merge"] == sum(t[k] for k in stages if k != "cuts")
    steps = (
        "filter",
        "table",
        "supervoxels",
        "edges",
        "lccp",
        "cuts",
        "merge",
        "objects",
        "flat",
        "exclude",
        "openings",
    )
    assert min(t.values()) >= 0.0 and sum(t[k] for k in steps) <= t["total"]


def test_two_touching_boxes_are_two() -> None:
    from clearcli.perception.segment import segment
    from clearcli.sim.scene import Box, make_scene

    # in contact along x; the smaller one set back 1.5 cm, so no face is shared in a
    # plane: LCCP alone separates them
    a = Box(0, 0.06, 0.05, 0.10, x_m=-0.03, y_m=0.0)
    b = Box(1, 0.04, 0.07, 0.06, x_m=0.02, y_m=0.025)
    frame = _render(make_scene("touching", [a, b]))
    seg = segment(frame, S)
    sc = score(seg.labels(), frame.fields["label"])
    assert (sc.n_pred, sc.true_positives) == (2, 2)
    assert min(sc.matched_iou) > 0.8


@pytest.mark.parametrize("seed", [0, 3, 5, "fixture"])
def test_touching_boxes_with_coplanar_fronts_are_two(seed: int | str) -> None:
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment
    from clearcli.sim.camera import render
    from clearcli.sim.scene import two_touching_boxes

    # front faces in one plane: LCCP joins the boxes through it, the planar cut at the
    # seam of the lower box's top and the taller box's front separates them (on by
    # default, see SegmentSettings.planar_cuts)
    if seed == "fixture":
        frame = read_frame(Path(__file__).resolve().parents[2] / "fixtures" / "two_touching_boxes.pcd")
    else:
        frame = render(two_touching_boxes(), seed=int(seed))
    sc = score(segment(frame, S).labels(), frame.fields["label"])
    assert (sc.n_pred, sc.true_positives) == (2, 2)
    assert min(sc.matched_iou) > 0.8
    if seed == 0:  # and without the cut, LCCP's blind spot
        off = score(segment(frame, replace(S, planar_cuts=False, step_split=False)).labels(), frame.fields["label"])
        assert off.n_pred == 1


def test_box_on_box_is_two() -> None:
    """The box on a box, on several noise seeds and as the committed fixture (one
    render per test hid that the fixture came out as one object)."""
    from helpers import FIXTURES

    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment
    from clearcli.sim.camera import render
    from clearcli.sim.scene import box_on_box

    frames = [render(box_on_box(), seed=seed) for seed in range(5)] + [read_frame(FIXTURES / "box_on_box.pcd")]
    for frame in frames:
        seg = segment(frame, S)
        sc = score(seg.labels(), frame.fields["label"])
        assert (sc.n_pred, sc.true_positives) == (2, 2), frame.source
        upper = min(seg.objects, key=lambda o: o.n_points)
        assert seg.table.height_of(upper.obb_center) > 0.06  # it stands on the lower box


def test_unorganized_and_table_frame_clouds(box_frame: Frame) -> None:
    from clearcli.perception.segment import segment

    finite = box_frame.finite_mask
    pts = box_frame.points[finite]
    flat = Frame(points=pts, shape=None)
    seg = segment(flat, S)
    assert len(seg.objects) == 1
    assert seg.objects[0].obb_extents == pytest.approx([0.05, 0.04, 0.08], abs=0.01)
    # the same cloud moved into the table's frame (z up, origin on the table): no camera
    ref = segment(box_frame, S)
    n = ref.table.normal
    x = np.cross([0.0, 0.0, 1.0], n)
    x /= np.linalg.norm(x)
    R = np.stack([x, np.cross(n, x), n])  # rows: table axes in the camera frame
    origin = -ref.table.offset * n
    up = ((pts.astype(np.float64) - origin) @ R.T).astype(np.float32)
    seg_up = segment(Frame(points=up), S)
    assert len(seg_up.objects) == 1
    assert seg_up.table.normal[2] > 0.999
    assert seg_up.objects[0].obb_extents == pytest.approx([0.05, 0.04, 0.08], abs=0.01)


def test_settings_are_used() -> None:
    from clearcli.perception.segment import segment
    from clearcli.sim.scene import isolated_box

    frame = _render(isolated_box())
    # an object smaller than the minimum area is dropped
    assert segment(frame, replace(S, min_object_area_m2=0.05)).objects == ()
    with pytest.raises(Exception, match="outlier_method"):
        segment(frame, replace(S, outlier_method="bogus"))


# ------------------------------------------------------------------ real frames
@pytest.mark.parametrize(
    "name, floor",
    [("mosd/learn/learn3.pcd", 0.99), ("mosd/learn/learn21.pcd", 0.99), ("mosd/test/test55.pcd", 0.9)],
)
def test_mosd_frames_score(name: str, floor: float) -> None:
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment

    frame = read_frame(shared_path(name))
    seg = segment(frame, S)
    sc = score(seg.labels(), frame.fields["label"])
    assert sc.f1 >= floor, sc
    # the table: normal up (towards the camera), about 0.6 m below it
    assert 0.5 < seg.table.offset < 0.75


def test_mosd_cylindrical_category_keeps_containers_whole() -> None:
    """mOSD's cylindrical frames (bowls, mugs, pots; learn33-44): mean F1 >= 0.93 (the
    issue's target; 0.857 before the rings stage). The six where a container's inner
    and outer walls came apart are here; without the rings stage and the vessels stage
    they fall below (either alone mends them: the vessels stage rebuilds a container
    whose wall is in two segments, whatever the two are)."""
    from clearcli.io.read import read_frame
    from clearcli.perception.segment import segment

    frames = [read_frame(shared_path(f"mosd/learn/learn{i}.pcd")) for i in range(33, 39)]
    on = [score(segment(f, S).labels(), f.fields["label"]).f1 for f in frames]
    off = [
        score(segment(f, replace(S, ring_merge=False, vessel_rebuild=False)).labels(), f.fields["label"]).f1
        for f in frames
    ]
    assert np.mean(on) >= 0.93, on
    assert np.mean(off) < 0.8, off


SEEDS = (0, 1, 2)


def _specks_scene() -> Scene:
    """Three objects 1.5 cm across: each shows less visible surface than the smallest
    object segmentation keeps (`min_object_area_m2`)."""
    return make_scene(
        "specks",
        [
            Box(0, 0.015, 0.015, 0.015, x_m=-0.12, y_m=0.0, yaw_rad=0.5),
            Cylinder(1, 0.0075, 0.02, x_m=0.0, y_m=0.08),
            Box(2, 0.015, 0.015, 0.015, x_m=0.14, y_m=-0.06),
        ],
    )


def _owners(seg: Segmentation, truth: np.ndarray, what: str) -> list[int]:
    """Asserts every object is sound: its points real and not the table's, at least 90 %
    of them one true object, and no true object split between two objects. Returns the
    true label each object is."""
    owners: list[int] = []
    for k, obj in enumerate(seg.objects):
        assert obj.n_points > 0 and np.unique(obj.indices).size == obj.n_points, (what, k)
        assert np.intersect1d(obj.indices, seg.table_indices).size == 0, (what, k)
        labels, counts = np.unique(truth[obj.indices], return_counts=True)
        top = int(labels[np.argmax(counts)])
        assert top >= 10, f"{what}: object {k} is mostly label {top} (table or nothing), not an object"
        assert counts.max() >= 0.9 * obj.n_points, f"{what}: object {k} mixes {dict(zip(labels, counts))}"
        owners.append(top)
    assert len(set(owners)) == len(owners), f"{what}: a true object split in several: {owners}"
    return owners


def _assert_table_at(seg: Segmentation, scene: Scene, height_m: float, what: str) -> None:
    """The support found is the plane ``height_m`` above the scene's table, facing up."""
    T = scene.T_camera_table
    up = T[:3, 2]  # the table's z axis in the camera frame
    assert float(seg.table.normal @ up) > 0.995, (what, seg.table.normal)
    # the camera is -(up . t) above the table (sim placement), so height_m less above this
    assert seg.table.offset == pytest.approx(-(up @ T[:3, 3]) - height_m, abs=0.01), what


# ------------------------------------------------------------------ every object tiny
@pytest.mark.parametrize("seed", SEEDS)
def test_tiny_objects_are_found_sound_or_dropped_by_the_size_limit(seed: int) -> None:
    """A result, not an error: what clears the documented size limit
    (`min_object_area_m2`, the smallest object kept) is found, each object one true
    object; what does not is dropped, smallest first; the table is the table. Lowering
    the limit (`--min-object-area-m2`) finds all five, still sound."""
    scene = _tiny_scene()
    frame = render(scene, seed=seed)
    truth = frame.fields["label"]
    true_points = {int(k): int(np.count_nonzero(truth == k)) for k in np.unique(truth[truth >= 10])}
    assert len(true_points) == 5 and max(true_points.values()) < 300  # tiny, as meant

    seg = segment(frame, S)
    _assert_table_at(seg, scene, 0.0, f"seed {seed}")
    assert np.mean((truth[seg.table_indices] >= 1) & (truth[seg.table_indices] < 10)) > 0.99
    found = set(_owners(seg, truth, f"seed {seed}"))
    missed = set(true_points) - found
    assert found, f"seed {seed}: no tiny object kept"
    if missed:  # the limit drops the smallest: never a larger one while keeping a smaller
        assert min(true_points[k] for k in found) > max(true_points[k] for k in missed), (found, true_points)

    low = segment(frame, replace(S, min_object_area_m2=LOW_AREA_M2))
    assert sorted(_owners(low, truth, f"seed {seed}, low limit")) == sorted(true_points)


@pytest.mark.parametrize("seed", SEEDS)
def test_objects_all_under_the_size_limit_leave_an_empty_table(seed: int) -> None:
    """Objects under the smallest object kept are not objects (settings.py): the frame is
    a table with nothing on it, the documented result with zero objects, not an error."""
    scene = _specks_scene()
    frame = render(scene, seed=seed)
    seg = segment(frame, S)
    assert seg.objects == ()
    _assert_table_at(seg, scene, 0.0, f"seed {seed}")
    assert seg.table_indices.size > 50_000


# ------------------------------------------------------------------ one object spanning the table
@pytest.mark.parametrize("name", sorted(SPANNING))
def test_object_as_big_as_the_table_is_the_support(name: str) -> None:
    """With the table hidden (or less of it in view than a table's least area), the top
    of the big object is the support surface: from the points alone a board as big as
    the table is a thicker table. So the result is that top as the table, facing up, and
    what stands on it as the objects: never a wall (the tall box's front face) taken
    for the table, a strip of the real table taken for an object, or a "seen from
    below" error for a camera above the table. The same from an unorganized cloud, where
    no pixel grid tells a wall facing the camera from a table seen from above."""
    scene, height = SPANNING[name]
    for seed in SEEDS:
        frame = render(scene, seed=seed)
        clouds = [frame]
        # unorganized once per scene where it differs (the wall; an object on the board)
        if seed == SEEDS[0] and name in ("tall_box", "board_with_box"):
            clouds.append(_unorganized(frame, seed))
        for cloud in clouds:
            what = f"{name}, seed {seed}, {'organized' if cloud.shape else 'unorganized'}"
            lab = cloud.fields["label"]
            seg = segment(cloud, S)
            _assert_table_at(seg, scene, height, what)
            assert np.mean(lab[seg.table_indices] == 10) > 0.99, what  # the big object's top
            owners = _owners(seg, lab, what)
            assert owners == ([20] if scene.n_objects == 2 else []), what
            if owners:
                sc = score(seg.labels(), lab)
                # matched_iou is by true id: the board is 1 (label 10), the box on it 2
                assert sc.n_pred == 1 and sc.matched_iou[1] >= 0.5, (what, sc)


# ------------------------------------------------------------------ unorganized cloud
@pytest.mark.parametrize("seed", SEEDS)
def test_unorganized_cloud_finds_the_objects(seed: int) -> None:
    """No pixel grid (the stages that need it are skipped) and no point order: both boxes,
    each whole and alone, about their true size."""
    scene = _two_boxes()
    flat = _unorganized(render(scene, seed=seed), seed)
    assert not flat.is_organized and np.isfinite(flat.points).all()
    truth = flat.fields["label"]
    seg = segment(flat, S)
    _assert_table_at(seg, scene, 0.0, f"seed {seed}")
    sc = score(seg.labels(), truth)
    assert (sc.n_true, sc.n_pred, sc.true_positives) == (2, 2, 2), sc
    assert min(sc.matched_iou) > 0.7, sc
    owners = _owners(seg, truth, f"seed {seed}")
    for obj, owner in zip(seg.objects, owners):
        box = scene.objects[owner // 10 - 1]
        assert isinstance(box, Box)
        assert sorted(obj.obb_extents[:2]) == pytest.approx(sorted([box.size_x_m, box.size_y_m]), abs=0.01)
        assert obj.obb_extents[2] == pytest.approx(box.size_z_m, abs=0.01)


def test_row_mean_is_numpys_mean_bit_for_bit() -> None:
    """`row_mean` (exclude.py; einsum's sum of the rows) is ``mean(axis=0)`` to the last bit, on
    sizes around NumPy's block and buffer lengths, C-ordered, Fortran-ordered (the
    mean itself then), strided and float32."""
    from clearcli.perception.exclude import row_mean as _row_mean

    # by hand: (1 + 2 + 4) / 3, (0.1 + 0.2 + 0.3) / 3 with its rounding, -1
    p = np.array([[1.0, 0.1, -1.0], [2.0, 0.2, -1.0], [4.0, 0.3, -1.0]])
    assert _row_mean(p).tolist() == [7.0 / 3.0, ((0.1 + 0.2) + 0.3) / 3, -1.0]
    rng = np.random.default_rng(7)
    for n in (1, 2, 3, 7, 8, 9, 16, 17, 127, 128, 129, 8191, 8192, 8193, 65537):
        for scale in (1e-3, 1.0, 1e3):
            q = rng.normal(size=(n, 3)) * scale + rng.normal(size=3)
            # (and two columns: the footprints `_face` averages)
            for arr in (q, np.asfortranarray(q), q[::2], q.astype(np.float32), np.ascontiguousarray(q[:, :2])):
                if arr.shape[0]:
                    assert np.array_equal(_row_mean(arr), arr.mean(axis=0))


def _principal_axes(points: np.ndarray, mean: np.ndarray) -> np.ndarray:
    # the per-object rule make_objects replaced (kept here as its oracle): (3, 3) rows,
    # unit PCA axes, largest variance first, right-handed
    from clearcli.transforms import cross3

    if points.shape[0] < 2:
        return np.eye(3)
    c = points - mean
    _, vecs = np.linalg.eigh(c.T @ c)
    axes = vecs[:, ::-1].T.copy()
    axes[2] = cross3(axes[0], axes[1])
    return axes


def test_make_objects_are_make_object_s_one_by_one_bit_for_bit() -> None:
    """`make_objects` (every object's box and axes, the scatter matrices decomposed in one
    call) gives each object what its own calls give: the box of `table_aligned_box`, the
    centroid of `row_mean`, the axes of the per-object rule, to the last bit; one point: the
    identity as axes."""
    from clearcli.perception.exclude import row_mean
    from clearcli.perception.segment import make_objects, table_aligned_box
    from clearcli.perception.types import TablePlane

    rng = np.random.default_rng(7)
    n = np.array([0.1, -0.7, -0.5])
    table = TablePlane(n / np.linalg.norm(n), 0.8)
    found = [
        (np.arange(k, k + m), rng.normal(size=(m, 3)) * rng.uniform(0.01, 0.2, size=3) + rng.normal(size=3), r)
        for k, (m, r) in enumerate([(300, 0.02), (1, 0.02), (57, np.inf), (2, 0.0), (1000, 0.01)])
    ]
    made = make_objects(found, table)
    assert len(made) == len(found)
    for (idx, p, rests), obj in zip(found, made, strict=True):
        center, axes, extents = table_aligned_box(p, table, rests)
        assert obj.indices.dtype == np.int64 and obj.indices.tolist() == idx.tolist()
        assert np.array_equal(obj.centroid, row_mean(p))
        assert np.array_equal(obj.obb_center, center)
        assert np.array_equal(obj.obb_axes, axes)
        assert np.array_equal(obj.obb_extents, extents)
        assert np.array_equal(obj.principal_axes, _principal_axes(p, row_mean(p)))
    assert np.array_equal(made[1].principal_axes, np.eye(3))  # one point: no direction
    # the box axes: the third is the table's normal; the first two in its plane
    assert np.allclose(made[0].obb_axes[2], table.normal)
    assert abs(float(made[0].obb_axes[0] @ table.normal)) < 1e-12


def test_an_image_in_opengl_convention_gives_the_optical_frames_objects_turned() -> None:
    # Open3D's tutorials turn a camera's cloud by diag(1, -1, -1) (y up, looking along -z),
    # and ARKit and Unity write them so. Before, such an image was refused: "the table is
    # seen from below: its top faces down the image". Now it is turned to the optical
    # frame for the steps and the results turned back: the same pixels in each object,
    # every point and direction exactly turned (negating is exact in floats)
    from clearcli.sim.scene import clutter

    frame = _render(clutter(6, 2))
    optical = segment(frame, S)
    turn = np.array([1.0, -1.0, -1.0])
    gl = segment(replace(frame, points=frame.points * turn.astype(np.float32)), S)
    assert len(gl.objects) == len(optical.objects) >= 4
    assert np.array_equal(gl.labels(), optical.labels())
    assert np.array_equal(gl.table.normal, optical.table.normal * turn) and gl.table.offset == optical.table.offset
    assert np.array_equal(gl.table_polygon, optical.table_polygon * turn)
    for a, b in zip(optical.objects, gl.objects, strict=True):
        assert np.array_equal(b.centroid, a.centroid * turn) and np.array_equal(b.obb_center, a.obb_center * turn)
        assert np.array_equal(b.obb_axes, a.obb_axes * turn) and np.array_equal(b.obb_extents, a.obb_extents)
        assert np.array_equal(b.principal_axes, a.principal_axes * turn)
    assert [v.normal for v in gl.support] == [(x, -y, -z) for x, y, z in (v.normal for v in optical.support)]
    assert [(e.seen, e.why) for e in gl.table_edges] == [(e.seen, e.why) for e in optical.table_edges]
    for a, b in zip(optical.table_edges, gl.table_edges, strict=True):
        assert np.array_equal(b.start, a.start * turn) and np.array_equal(b.end, a.end * turn)
    # the table's normal points up, towards the camera at the origin, in the cloud's own
    # frame: the table lies along -z, and its normal has +z there
    assert float(np.nanmedian(frame.points[:, 2] * -1.0)) < 0 and gl.table.normal[2] > 0.5


@pytest.mark.parametrize("variant", ["opengl", "camera_link", "upside_down", "on_its_side", "camera_link_upside_down"])
def test_an_image_in_another_convention_or_rolled_gives_the_same_objects(variant: str) -> None:
    # the same view as other cameras and conventions write it: another axis convention
    # (OpenGL's, ROS camera_link's), a camera mounted upside down or on its side, both.
    # Each is turned into the upright optical image (orientation.py): the same objects, pixel
    # for pixel; before, the first two and the upside-down ones were refused ("seen from
    # below") or segmented otherwise (camera_link: 2 objects more on a cluttered frame)
    from clearcli.sim.conventions import variants
    from clearcli.sim.scene import clutter

    frame = _render(clutter(6, 2))
    upright = segment(frame, S)
    turned, pixels = variants(frame)[variant]
    seg = segment(turned, S)
    back = np.zeros(frame.n_points, dtype=np.int32)
    back[pixels] = seg.labels()
    assert len(seg.objects) == len(upright.objects) >= 4
    assert np.array_equal(back, upright.labels())
    # --json's chosen support says how the frame was read
    expected = {
        "opengl": "x, y, z = x, -y, -z",
        "camera_link": "x, y, z = -y, -z, x",
        "upside_down": "the image turned 180 degrees to be the right way up",
        # the variant is np.rot90's counter-clockwise quarter turn: undone clockwise
        "on_its_side": "the image turned 90 degrees clockwise",
        "camera_link_upside_down": "the image turned 180 degrees",
    }[variant]
    assert seg.support[0].chosen and expected in seg.support[0].why, seg.support[0].why
    assert "turned" not in upright.support[0].why
    # every point and direction in the variant's own coordinates: its points' own centroid,
    # the normal towards the camera at its origin
    for o in seg.objects:
        assert np.allclose(o.centroid, turned.points[o.indices].astype(np.float64).mean(axis=0), atol=1e-6)
    table_points = turned.points[seg.table_indices].astype(np.float64)
    assert np.abs(seg.table.height_of(table_points)).max() < 0.02
    assert seg.table.offset > 0.3  # the camera (origin) 0.3 m or more above the table
