"""Segmentation on other labs' frames (benchmarks/foreign): one test per failure kind the
foreign work fixed, each on a labelled frame of the choose part, and each shown to be
needed: with its step off, the same frame fails the same way it did before."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.foreign import judged, labelled


@pytest.mark.parametrize(
    "frame, cup",
    [("table_scene_mug_stereo_textured", "mug"), ("uois_image_0000", "blue cup")],
)
def test_a_mug_with_its_handle_is_one_object(frame: str, cup: str) -> None:
    verdicts, _, _ = judged(frame)
    assert verdicts[cup] == "right"


@pytest.mark.parametrize(
    "frame, cup",
    [
        ("table_scene_mug_stereo_textured", "mug"),
        pytest.param(
            "uois_image_0000",
            "blue cup",
            marks=pytest.mark.xfail(
                strict=True,
                reason="since the voxel grid's boundaries left the whole millimetre (issue 37, 6a58839) the blue "
                "cup's walls join without the rim stages too: this frame no longer shows what they do",
            ),
        ),
    ],
)
def test_without_the_rim_stages_the_mug_splits(frame: str, cup: str) -> None:
    # rings.fit_rim: the rim circle fitted without the band points far off it (the
    # handle); with none allowed off the circle, and without the vessels stage (which
    # rebuilds the cup from its rim as well, its handle going with it), the walls stay
    # two segments
    verdicts, _, _ = judged(frame, ring_max_off_share=0.0, vessel_rebuild=False)
    assert verdicts[cup] == "split"


def test_a_chair_behind_the_table_is_not_an_object() -> None:
    # uois_image_0004: a low round table, a chair behind it whose seat lies within 2 cm
    # of the table's plane. table.beyond_the_edge drops the seat from the table (the
    # camera sees the floor through the gap between them), the hull shrinks, and the
    # chair's back is outside it
    verdicts, report, seg = judged("uois_image_0004")
    assert report.spurious == 0
    assert seg.beyond_edge_m2 > 0.1
    assert [verdicts[k] for k in ("wipes canister", "cashew can", "purple cup")] == ["right"] * 3
    # the plane's pieces say which was taken and what was dropped
    assert [p.chosen for p in seg.support].count(True) == 1 and seg.support[0].chosen
    _, off, seg_off = judged("uois_image_0004", beyond_edge_check=False)
    assert off.spurious >= 1 and seg_off.beyond_edge_m2 == 0.0
    assert len(seg_off.objects) > len(seg.objects)


def _polygon_pixels(frame, polygon) -> np.ndarray:
    from matplotlib.path import Path as Polygon

    h, w = frame.shape
    v, u = np.mgrid[0:h, 0:w]
    inside = Polygon(np.asarray(polygon, dtype=np.float64)).contains_points(np.column_stack([u.ravel(), v.ravel()]))
    return np.flatnonzero(inside & np.isfinite(frame.points).all(axis=1))


def test_a_flat_marker_is_found() -> None:
    # uois_image_0006: a black marker lying on a light wooden table a metre away stands
    # 2-8 mm above the plane, inside the table's noise; flat.py finds it by its colour
    # and its relief. Judged against the polygon drawn round it on the colour image (the
    # depth-cut label lies ~2 px off the colour here: the sensor's registration)
    from helpers.foreign import labelled

    frame, _, spec = labelled("uois_image_0006")
    marker = _polygon_pixels(frame, next(o for o in spec["object"] if o["name"] == "black marker")["polygon"])

    def best(seg) -> tuple[float, float]:
        scores = [(np.isin(o.indices, marker).mean(), np.isin(marker, o.indices).mean()) for o in seg.objects]
        return max(scores, key=lambda s: s[0] * s[1])

    # the object's points are where its depth stands up, beside the colour (flat.py, 4.):
    # most of them within the polygon, and the polygon's depth-cut label exactly right
    verdicts, _, seg = judged("uois_image_0006")
    inside, covered = best(seg)
    assert inside >= 0.5 and covered >= 0.5
    assert verdicts["black marker"] == "right"
    # the green marker lies against the blue container: 5 % of its pixels within the
    # clearance, judged on the rest (flat.py, 2.)
    assert verdicts["green marker"] == "right"
    assert seg.color_used and "flat objects" in seg.color_note
    _, _, seg = judged("uois_image_0006", flat_objects=False)
    inside, covered = best(seg)
    assert covered < 0.1


def test_a_flat_markers_points_are_where_its_depth_stands_up() -> None:
    # uois_image_0006's black marker: its colour lies ~6 px beside its raised depth. On
    # the colour's pixels alone (no pixel is 5 cm above the table: the raised pixels are
    # never half the candidate's) the object takes the table's points beside the marker
    # and only 0.63 of the marker's labelled (depth-cut) points: IoU 0.42, missed
    verdicts, _, _ = judged("uois_image_0006", flat_grow_min_m=0.05)
    assert verdicts["black marker"] == "missed"
    verdicts, _, _ = judged("uois_image_0006")
    assert verdicts["black marker"] == "right"


def test_a_bowl_with_a_can_in_it_is_two_objects() -> None:
    # uois_image_0002: a teal bowl with a can standing in it, a drill lying against its
    # rim. vessels.py rebuilds the bowl from its rim circle: its wall left and right of
    # the can, behind the can and against the drill is one segment again, the can and
    # the drill each another. (The can is "split" by the exact measure only because its
    # polygon, drawn a little wide, takes ~500 pixels of the bowl's wall beside it.)
    from helpers.foreign import labelled

    frame, truth, spec = labelled("uois_image_0002")
    names = [o["name"] for o in spec["object"]]

    def best(seg, name: str) -> tuple[int, float]:
        obj = truth == 10 * (names.index(name) + 1)
        labels = seg.labels()
        ids, counts = np.unique(labels[obj & (labels >= 10)], return_counts=True)
        k = int(ids[np.argmax(counts)])
        return k, float((obj & (labels == k)).sum() / (obj | (labels == k)).sum())

    verdicts, _, seg = judged("uois_image_0002")
    assert verdicts["teal bowl"] == "right" and verdicts["drill"] == "right"
    (bowl, bowl_iou), (can, can_iou), (drill, _) = (best(seg, n) for n in ("teal bowl", "small can", "drill"))
    assert bowl_iou >= 0.8 and can_iou >= 0.7 and len({bowl, can, drill}) == 3
    # needed: without it the bowl is in pieces, one of them with the drill
    verdicts, _, seg = judged("uois_image_0002", vessel_rebuild=False)
    assert verdicts["teal bowl"] == "split"
    assert best(seg, "teal bowl")[1] < 0.5


def test_a_low_bowl_with_a_large_foot_keeps_it_held_to_its_outline(monkeypatch: pytest.MonkeyPatch) -> None:
    # uois_image_0000's white bowl (4.6 cm tall) has a foot under the prism's floor as
    # large as itself: its lower wall, and a dark grain of the table's wood beside it,
    # of its shaded side's colour. It does not lie flat (its points' median height 16
    # mm above the floor, a notebook's 0.5-3.6 mm), so the foot is held to the bowl's
    # outline; joined whole, the grain reached 32 cm across the table. Since stop 64 the
    # grain's pixels of another colour than the foot's also leave it (flat._SPLIT_DE):
    # both rules off, the bowl reaches over the grain
    import clearcli.perception.flat as flat
    import clearcli.perception.segment as seg
    from clearcli.io.frames import object_label

    def bowl_extent_m() -> float:
        verdicts, _, s = judged("uois_image_0000")
        assert verdicts["white bowl"] == "right"
        _, truth, spec = labelled("uois_image_0000")
        label = object_label(next(k for k, o in enumerate(spec["object"]) if o["name"] == "white bowl"))
        bowl = max(s.objects, key=lambda o: int(np.count_nonzero(truth[o.indices] == label)))
        return float(bowl.obb_extents.max())

    assert bowl_extent_m() < 0.18
    monkeypatch.setattr(seg, "_FLAT_TOP_M", float("inf"))
    assert bowl_extent_m() < 0.18
    monkeypatch.setattr(flat, "_SPLIT_DE", float("inf"))
    assert bowl_extent_m() > 0.3
