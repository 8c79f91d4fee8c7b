"""The support is the surface the objects stand on (issue 37, perception/support.py), on
self-made frames (clearcli.sim.families.SUPPORT_FAMILIES), each shown to need the step:
with ``support_by_standing`` off the same frame takes the wrong surface. Seeds 0-4 of
each family are looked at (tests, choices); 5-9 are kept for reporting."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from clearcli.errors import EXIT_SCENE, SceneError
from clearcli.evaluate.segmentation import score
from clearcli.io.frames import LABEL_TABLE, Frame, object_label
from clearcli.perception import support, table
from clearcli.perception.payload import segmentation_payload
from clearcli.perception.segment import segment
from clearcli.settings.segment import SegmentSettings
from clearcli.settings.sim import DepthNoise
from clearcli.sim.families import REALSENSE_HD, STEREO_NOISE, support_frame

ON = SegmentSettings()
OFF = dataclasses.replace(ON, support_by_standing=False)


def _right(frame: Frame, settings: SegmentSettings) -> bool:
    sc = score(segment(frame, settings).labels(), frame.fields["label"])
    return sc.true_positives == sc.n_true == sc.n_pred


@pytest.mark.parametrize("seed", [1, 7])
def test_a_large_bowl_is_one_object_and_what_stands_in_it_apart(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    # the bowl 36-42 cm across, its floor and its wall apart after LCCP (a concave seam
    # all round): the vessels stage rebuilds it from its rim, sought wider than
    # ring_max_radius_m (15 cm) up to vessel_max_radius_m (25 cm) where no narrower rim
    # is found (before: the bowl stayed in two pieces), and what stands on its floor
    # below the rim stays apart (`vessels._standing_inside`; before, only what rose above
    # the rim did: two or three objects went with the bowl). Every object exactly right.
    from clearcli.evaluate.exact import exact_report
    from clearcli.perception import vessels

    frame = support_frame("large_bowl", seed)
    truth = np.asarray(frame.fields["label"])
    r = exact_report(segment(frame, ON).labels(), truth)
    assert r.right == r.n_objects and r.spurious == 0, r
    narrow = exact_report(segment(frame, dataclasses.replace(ON, vessel_max_radius_m=0.15)).labels(), truth)
    assert narrow.split == 1 and narrow.right == r.n_objects - 1, narrow  # the bowl in two
    monkeypatch.setattr(vessels, "_standing_inside", lambda *args: [])
    taken = exact_report(segment(frame, ON).labels(), truth)
    assert taken.merged >= 2, taken  # the bowl and what stands in it, one segment


@pytest.mark.parametrize("seed", [3, 5])
def test_what_stands_on_a_bowls_floor_deep_inside_the_table_stands_on_no_other_furniture(
    seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    # large_bowl(3) and (5) (choose seeds): a box or two stand in the bowl, the bowl's
    # floor all round them 1.5-2.5 cm up: no table is seen round them. They stand 21-24 cm
    # inside the table's outline, so not beyond its edge (exclude.DEEP_INSIDE_M, 5 cm):
    # every object exactly right. Before (the rule judged at any depth), they were set
    # aside as standing on another surface behind the table
    import clearcli.perception.segment as seg
    from clearcli.evaluate.exact import exact_report

    frame = support_frame("large_bowl", seed)
    truth = np.asarray(frame.fields["label"])
    result = segment(frame, ON)
    r = exact_report(result.labels(), truth)
    assert r.right == r.n_objects and r.spurious == 0, r
    assert not any("beyond the support's edge" in e.reason for e in result.excluded)
    monkeypatch.setattr(seg, "DEEP_INSIDE_M", 10.0)  # no point that deep: judged everywhere
    before = segment(frame, ON)
    gone = [e for e in before.excluded if "beyond the support's edge" in e.reason]
    assert len(gone) == {3: 1, 5: 2}[seed]
    assert exact_report(before.labels(), truth).missed == len(gone)


@pytest.mark.parametrize("seed", [1, 2])
def test_a_raised_surface_beats_the_floor_around_it(seed: int) -> None:
    # objects on a stool's top 75 cm above a floor that holds the stool's body and bags:
    # the floor has more points standing on it, the top holds the objects
    frame = support_frame("raised_surface", seed)
    seg = segment(frame, ON)
    assert _right(frame, ON)
    chosen = [v for v in seg.support if v.chosen]
    assert len(chosen) == 1 and "raised surface" in chosen[0].why
    assert any("floor around a raised surface" in v.why for v in seg.support if not v.chosen)
    doc = segmentation_payload(seg)
    assert doc["support"]["why"] == chosen[0].why
    assert any("floor" in r["why"] for r in doc["support"]["rejected"])
    # the step off: the floor is taken and the stool's body and the bags become objects
    off = segment(frame, OFF)
    assert not _right(frame, OFF)
    assert abs(off.table.offset) > abs(seg.table.offset) + 0.5


@pytest.mark.parametrize("seed", [4, 5])
def test_the_mat_the_objects_stand_on_is_the_support(seed: int) -> None:
    # a mat or board 10-16 mm thick on the table: the objects stand on it; the table's
    # plane leaves the mat in the prism, an "object" under the real ones
    frame = support_frame("mat_on_table", seed)
    seg = segment(frame, ON)
    assert _right(frame, ON)
    assert "mat or board" in next(v.why for v in seg.support if v.chosen)
    assert not _right(frame, OFF)


@pytest.mark.parametrize(("seed", "noise"), [(0, None), (26, None), (25, STEREO_NOISE)])
def test_a_mat_smaller_than_a_table_is_the_support(
    seed: int, noise: DepthNoise | None, monkeypatch: pytest.MonkeyPatch
) -> None:
    # placemats of 39 x 25, 39 x 26 and 35 x 27 cm, whose plane shows 0.082-0.088 m^2 round the
    # objects on it: under table_min_area_m2 (0.1 m^2), over support.MAT_MIN_AREA_M2. The
    # mat is the support, the table's verdict says it is one support with it, and the
    # mat is no object
    frame = support_frame("mat_on_table", seed, noise=noise)
    seg = segment(frame, ON)
    assert _right(frame, ON)
    chosen = next(v for v in seg.support if v.chosen)
    assert "mat or board" in chosen.why
    assert support.MAT_MIN_AREA_M2 <= chosen.area_m2 < ON.table_min_area_m2
    assert any(v.why.startswith("one support with the mat") for v in seg.support if not v.chosen)
    assert sum(v.chosen for v in seg.support) == 1
    # a plane under a table's area no candidate for the mat rule: the mat is an "object"
    monkeypatch.setattr(table, "MAT_MIN_AREA_M2", ON.table_min_area_m2)
    off = segment(frame, ON)
    assert not _right(frame, ON)
    assert len(off.objects) > len(seg.objects)
    assert not any("mat or board" in v.why for v in off.support if v.chosen)


def test_a_camera_looking_down_at_a_floor_still_has_its_support() -> None:
    # the plain scene (one plane holding the objects) is unchanged by the step
    frame = support_frame("mat_on_table", 2)
    assert _right(frame, ON)
    seg = segment(frame, ON)
    assert [v.chosen for v in seg.support].count(True) == 1


def test_no_surface_holding_anything_is_exit_4_naming_the_surfaces() -> None:
    # a frame of a small patch only: no surface of table size; the one line names what
    # was considered
    frame = support_frame("mat_on_table", 2)
    pts = frame.points.copy()
    keep = np.zeros(frame.shape, dtype=bool)
    keep[300:315, :] = True  # a strip of table 15 pixels tall (a few cm)
    keep = keep.ravel()
    pts[~keep] = np.nan
    bad = dataclasses.replace(frame, points=pts)
    with pytest.raises(SceneError) as err:
        segment(bad, ON)
    assert err.value.exit_code == EXIT_SCENE
    assert "\n" not in str(err.value) and "considered" in str(err.value)


def _matched(frame: Frame, seg_labels: np.ndarray) -> dict[int, bool]:
    """Each true object's label: is it matched (IoU >= 0.5)?"""
    sc = score(seg_labels, frame.fields["label"])
    return {10 * t: iou >= 0.5 for t, iou in zip(sc.true_ids, sc.matched_iou)}  # ids are label // 10


@pytest.mark.parametrize("seed", [0, 2])
def test_the_inside_of_a_large_bowl_is_never_the_support(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    # a bowl 36-42 cm across, its floor 1.5-2.5 cm above the table, objects in it and
    # beside it. Its floor is a plane over the table holding objects: the standing rule
    # would take it for a mat, and the objects beside the bowl, off its outline, would be
    # lost. It is concave (the bowl's wall rises at its edge all round): never the support.
    # Without the standing rule (support_by_standing off) the floor does not win either:
    # the table holds more. So the step shown needed here is the concave test inside the
    # standing rule, turned off by asking for more walled sides than there are.
    # (The bowl itself: test_a_large_bowl_is_one_object_and_what_stands_in_it_apart.)
    frame = support_frame("large_bowl", seed)
    truth = np.asarray(frame.fields["label"])
    bowl = object_label(0)
    beside = [t for t in np.unique(truth).tolist() if t >= object_label(10)]
    inside = [t for t in np.unique(truth).tolist() if object_label(1) <= t < object_label(10)]
    assert beside and inside
    seg = segment(frame, ON)
    chosen = next(v for v in seg.support if v.chosen)
    assert chosen.why == "the most points standing on it"
    # the table stays, and the bowl's floor turned down says why (in --json's support list)
    assert any(v.why.startswith("concave: a wall rises around it") for v in seg.support if not v.chosen), [
        v.why for v in seg.support
    ]
    assert abs(seg.table.offset - segment(frame, OFF).table.offset) < 0.005  # the table, as without the rule
    labels = seg.labels()
    assert np.mean(labels[truth == bowl] == LABEL_TABLE) < 0.05  # the bowl's floor is not support
    found = _matched(frame, labels)
    assert all(found[t] for t in beside + inside), found
    # the concave test off: the bowl's floor is taken for a mat; what stands beside the
    # bowl is outside the support, lost
    monkeypatch.setattr(support, "_WALLED_MIN", support._SECTORS + 1)
    wrong = segment(frame, ON)
    assert "mat or board" in next(v for v in wrong.support if v.chosen).why
    assert abs(wrong.table.offset - seg.table.offset) > 0.01
    lost = _matched(frame, wrong.labels())
    assert not any(lost[t] for t in beside), lost


def test_a_raised_surface_seen_from_low_is_over_the_floor_where_the_floor_is_out_of_view(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # raised_surface(12) seen from 0.54 m above the stool's top, 38 degrees down: the
    # image's bottom edge cuts the floor 0.67 m out, and the top's near half (from 0.49 m)
    # lies over floor the camera never sees; only 48 % of its outline is inside the floor's.
    # Where the camera's rays do not reach the floor, nothing says the top is not over it
    frame = support_frame("raised_surface", 12, view=(0.541, 38.4))
    seg = segment(frame, ON)
    chosen = next(v for v in seg.support if v.chosen)
    assert "raised surface" in chosen.why and abs(chosen.offset_m) < 0.6
    assert _right(frame, ON)
    # "over" by the floor's outline alone (as before): the floor is taken, its stool's body
    # and bags are objects and the objects on the top are lost
    monkeypatch.setattr(
        support, "_over", lambda lower, outline, rise, every: float(lower.inside(outline, support._OVER_GROW_M).mean())
    )
    wrong = segment(frame, ON)
    assert abs(next(v for v in wrong.support if v.chosen).offset_m) > 1.2
    assert not _right(frame, ON)


def test_a_raised_surface_seen_close_is_over_the_floor_its_body_hides(monkeypatch: pytest.MonkeyPatch) -> None:
    # raised_surface(14) seen by a RealSense at 1280x720 with stereo noise, 0.6 m over the
    # stool's top, 35 degrees down: the floor is seen from 0.9 m out only, and the feet of
    # the top's far corners (1.02 m out) lie behind the stool's front, which the camera's
    # ray meets 0.50-0.54 m before the floor there: 4 of the outline's 15 corners were
    # neither over the floor's outline nor out of view (73 %, under the 80 % asked). The
    # stool's top is the support and every object is right; without `_hidden` (a ray's
    # nearer point never counted) the floor is taken and the stool is one "object"
    frame = support_frame("raised_surface", 14, camera=REALSENSE_HD, view=(0.6, 35.0), noise=STEREO_NOISE)
    seg = segment(frame, ON)
    assert "raised surface" in next(v for v in seg.support if v.chosen).why
    assert _right(frame, ON)
    monkeypatch.setattr(support, "_HIDDEN_M", np.inf)
    wrong = segment(frame, ON)
    assert "raised surface" not in next(v for v in wrong.support if v.chosen).why
    assert not _right(frame, ON)


def test_flat_things_lying_apart_are_no_mat() -> None:
    """thin_flat(1): a notebook 15 mm thick and other flat things lying apart on the table,
    their tops one plane (joined across the gaps) holding points between them. The table
    shows through that plane's outline (76 % of the points at the two levels there), so
    it is no mat: the table stays the support, with its verdict saying why; with the test
    off (`mat_below_seen_max_share` 1) the notebooks' plane is taken for a mat and every
    object on the table is lost."""
    from clearcli.evaluate.exact import exact_report

    frame = support_frame("thin_flat", 1)
    seg = segment(frame, ON)
    assert not any("mat or board" in v.why for v in seg.support if v.chosen)
    assert any(v.why.startswith("no mat: the plane below shows") for v in seg.support)
    assert exact_report(seg.labels(), frame.fields["label"]).missed <= 3
    off = dataclasses.replace(ON, mat_below_seen_max_share=1.0)
    seg_off = segment(frame, off)
    assert "mat or board" in next(v.why for v in seg_off.support if v.chosen)
    assert exact_report(seg_off.labels(), frame.fields["label"]).missed == 7


def test_below_seen_share_by_hand() -> None:
    """A square surface 1 cm above the plane z = 0 (outline 0-0.4 m, its edge band 2 cm):
    inside off the band, 30 points at its level, 10 at the lower level, 5 of an object
    3 cm above it (at neither level) and 20 in the band (not counted): 10 of 40."""
    lower = support.Surface(
        np.array([0.0, 0.0, 1.0]),
        0.0,
        np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
        np.zeros(3),
        np.array([[0.0, 0.0], [0.4, 0.0], [0.4, 0.4], [0.0, 0.4]]),
    )
    upper = dataclasses.replace(lower, offset=-0.01, origin=np.array([0.0, 0.0, 0.01]))
    rng = np.random.default_rng(0)

    def at(n: int, z: float, lo: float = 0.05, hi: float = 0.35) -> np.ndarray:
        return np.column_stack([rng.uniform(lo, hi, (n, 2)), np.full(n, z)])

    every = np.vstack([at(30, 0.0105), at(10, 0.0002), at(5, 0.04), at(20, 0.01, 0.001, 0.015)])
    assert support._below_seen_share(upper, every, 0.01, 0.005) == pytest.approx(10 / 40)


def test_a_shelf_over_the_table_is_no_raised_surface() -> None:
    """shelf_above(0): a shelf board 30 cm over the table's far part, its side boards on the
    floor beyond the table's ends. The board is over the table, held up from it and holds
    the shelf's things, as a stool's top would be; but the table goes on beneath it (47 %
    of the points at the two levels within its outline), so the table stays the support
    and its five objects are right; with the test off (`raised_below_seen_max_share` 1)
    the board is taken for a raised surface and all five are lost."""
    from clearcli.evaluate.exact import exact_report

    frame = support_frame("shelf_above", 0)
    seg = segment(frame, ON)
    assert not any("raised surface" in v.why for v in seg.support if v.chosen)
    assert any(v.why.startswith("no raised surface: the plane below goes on beneath it") for v in seg.support)
    assert exact_report(seg.labels(), frame.fields["label"]).right == 5
    seg_off = segment(frame, dataclasses.replace(ON, raised_below_seen_max_share=1.0))
    assert "raised surface" in next(v.why for v in seg_off.support if v.chosen)
    assert exact_report(seg_off.labels(), frame.fields["label"]).missed == 5


def test_inside_convex_of_several_margins_is_one_call_each() -> None:
    # by hand: the unit square grown by 1 cm and shrunk by 3 cm (walled_sectors' band)
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    xy = np.array([[0.5, 0.5], [0.98, 0.5], [1.005, 0.5], [1.02, 0.5]])
    outer, inner = support._inside_convex(xy, square, 0.01, -0.03)
    assert outer.tolist() == [True, True, True, False]
    assert inner.tolist() == [True, False, False, False]
    # the same verdicts, to the point, as one call per margin (a polygon of many edges,
    # points on both sides of each grown outline)
    rng = np.random.default_rng(11)
    angles = np.sort(rng.uniform(0, 2 * np.pi, 40))
    poly = np.stack([np.cos(angles), np.sin(angles)], axis=1) * 0.4
    pts = rng.uniform(-0.5, 0.5, (20000, 2))
    both = support._inside_convex(pts, poly, 0.01, -0.03)
    assert both.shape == (2, 20000)
    assert np.array_equal(both[0], support._inside_convex(pts, poly, 0.01))
    assert np.array_equal(both[1], support._inside_convex(pts, poly, -0.03))
    assert 0 < both[1].sum() < both[0].sum() < 20000


# an oblique RealSense at 1280x720, 0.6 m above the floor's table level, 35 degrees down
# (benchmarks/support.py's ``hd`` view)
OBLIQUE = {"camera": REALSENSE_HD, "view": (0.6, 35.0)}


def test_a_floor_thickened_by_stereo_noise_leaves_room_for_the_raised_surface(monkeypatch: pytest.MonkeyPatch) -> None:
    # objects on a stool's top seen obliquely by a stereo sensor (seed 4): the floor, 1.35
    # m off, comes out of RANSAC as three parallel planes a centimetre apart, each of table
    # size (1.6, 0.13, 0.13 m^2). Counted as tries they used up the four candidates before
    # the stool's top was sought, a face of the stool was taken and the frame refused
    # ("seen from below"). A residue of a surface found is no try, whatever its size
    frame = support_frame("raised_surface", 4, noise=STEREO_NOISE, **OBLIQUE)
    seg = segment(frame, ON)
    assert _right(frame, ON)
    chosen = [v for v in seg.support if v.chosen]
    assert len(chosen) == 1 and abs(chosen[0].offset_m) < 0.65  # the stool's top, 0.6 m off
    floors = [v for v in seg.support if abs(abs(v.offset_m) - 1.35) < 0.02 and v.area_m2 >= ON.table_min_area_m2]
    assert len(floors) == 3  # the floor and its two residues, all seen and rejected
    # residues counted as tries again: the top is never a candidate
    monkeypatch.setattr(table, "_residue", lambda *args: False)
    with pytest.raises(SceneError, match="seen from below"):
        segment(frame, ON)


def test_a_face_with_its_body_behind_it_is_no_support() -> None:
    # the stool seen obliquely (seed 17): its front face, 0.71 m off and seen 35 degrees
    # from face-on, has the stool's body behind it as the camera sees it (858 points
    # behind, 13 before): more across it than the top has standing on it, so the score
    # (what stands on one side, less the other) took it and the frame was refused ("more
    # points behind it than standing on it"). The top holds points before it: it is the
    # support, and the face is rejected saying why
    frame = support_frame("raised_surface", 17, **OBLIQUE)
    seg = segment(frame, ON)
    assert _right(frame, ON)
    (chosen,) = [v for v in seg.support if v.chosen]
    faces = [v for v in seg.support if v.why.startswith("more points behind it than standing on it")]
    assert len(faces) == 1 and "a face with its body behind it" in faces[0].why
    assert abs(faces[0].offset_m - 0.71) < 0.02 and abs(chosen.offset_m - 0.60) < 0.02
    # by the score alone the face wins: what the fallback turns down
    assert faces[0].standing_points > chosen.standing_points


@pytest.mark.parametrize("seed", [32, 39])
def test_a_desks_face_with_the_objects_before_it_is_no_rolled_cameras_table(
    seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    # a second desk behind the table (seeds 32, 39), seen from a Kinect: the objects on
    # the table stand before the desk's front face, so the face has as many points
    # "standing" on it as the table (1173 against 1111 on seed 32) and was taken; its
    # normal points down the image, so the image was read as a rolled camera's, turned,
    # and the face segmented as the support. Nothing rests on the face (0 points within
    # 3 cm of it), hundreds on the table, which the image is upright for: the table is
    # the support and the image is read as it is
    frame = support_frame("desk_behind", seed)
    seg = segment(frame, ON)
    assert _right(frame, ON)
    (chosen,) = [v for v in seg.support if v.chosen]
    assert chosen.normal[1] < -0.5  # up the image: no turn
    faces = [v for v in seg.support if v.why.startswith("nothing rests on it")]
    assert len(faces) == 1 and faces[0].normal[1] > 0.5
    assert faces[0].standing_points >= chosen.standing_points  # by the score alone it wins
    # without the rule the face is taken as the support (the image turned for it)
    monkeypatch.setattr(table, "_RESTING_M", -1.0)  # no point rests on any plane
    (off,) = [v for v in segment(frame, ON).support if v.chosen]
    assert off.normal[1] > 0.5 and abs(off.offset_m - faces[0].offset_m) < 0.01
    # and the same view by a stereo sensor at 1280x720 was refused ("seen from below")
    if seed == 32:
        stereo = support_frame("desk_behind", seed, noise=STEREO_NOISE, **OBLIQUE)
        with pytest.raises(SceneError, match="seen from below"):
            segment(stereo, ON)
        monkeypatch.undo()
        assert len(segment(stereo, ON).objects) >= 4
