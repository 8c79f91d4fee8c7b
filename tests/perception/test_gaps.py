"""A gap across the support with a step at it: what stands beyond it stands on another
surface (issue 37, perception/gaps.py). By hand: points of two slabs worked out here;
then the self-made desk_level_behind frames whose desk RANSAC takes into the table's
plane."""

from __future__ import annotations

import numpy as np
import pytest

from clearcli.evaluate.segmentation import score
from clearcli.perception import gaps
from clearcli.perception.payload import segmentation_payload
from clearcli.perception.segment import segment
from clearcli.settings.segment import SegmentSettings
from clearcli.sim.families import REALSENSE_HD, STEREO_NOISE, support_frame

ON = SegmentSettings()
CAMERA_XY = np.array([0.0, -0.8])  # the camera's foot on the plane, in front of the slabs
# the slabs' outline: the hull of both, counter-clockwise
OUTLINE = np.array([[-0.5, 0.0], [0.495, 0.0], [0.495, 0.9975], [-0.5, 0.9975]])


def _slabs(gap_m: float, step_m: float, shadow: tuple[float, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """A table 1 m wide from y = 0 to 0.5 and a desk from 0.5 + ``gap_m`` to 1.0, the desk
    ``step_m`` lower: a point every 5 mm (none in the gap; none in the y-band ``shadow``,
    what a long thing lying across the table hides). Heights as a plane fitted through both
    would leave them: the table half the step above 0, the desk half below."""
    x, y = np.meshgrid(np.arange(-0.5, 0.5, 0.005), np.arange(0.0, 1.0, 0.005) + 0.0025)
    xy = np.stack([x.ravel(), y.ravel()], axis=1)
    keep = (xy[:, 1] < 0.5) | (xy[:, 1] >= 0.5 + gap_m)
    if shadow is not None:
        keep &= (xy[:, 1] < shadow[0]) | (xy[:, 1] >= shadow[1])
    xy = xy[keep]
    h = np.where(xy[:, 1] < 0.5, step_m / 2, -step_m / 2)
    return xy, h


def test_a_gap_with_a_step_is_found_where_it_runs() -> None:
    xy, h = _slabs(0.02, 0.007)
    gap = gaps.gap_behind(xy, h, CAMERA_XY, OUTLINE)
    assert gap is not None
    # the gap runs along x at y 0.50-0.52: its middle 0.51 along +y, away from the camera
    assert gap.direction == pytest.approx([0.0, 1.0], abs=0.01)
    assert gap.at_m == pytest.approx(0.51, abs=0.005)
    assert gap.width_m == pytest.approx(0.02, abs=0.005)
    assert gap.step_m == pytest.approx(0.007, abs=1e-6)  # the desk 7 mm lower
    assert "7.0 mm lower" in gap.why()
    # which objects stand beyond it: one on the desk, one on the table, one astride
    on_desk, on_table = np.array([[0.1, 0.7], [0.12, 0.75]]), np.array([[0.1, 0.3], [0.12, 0.35]])
    astride = np.array([[0.0, 0.45], [0.0, 0.48], [0.0, 0.56]])
    assert gaps.behind_the_gap(gap, [on_desk, on_table, astride]) == [0]


def test_a_turned_desk_is_found_along_its_own_direction() -> None:
    # the slabs turned 20 degrees, the camera's foot where it was: the line of sight now
    # crosses the gap 20 degrees off its normal (over a metre its edges smear by 36 cm);
    # found across the outline's long sides, turned with the slabs
    xy, h = _slabs(0.02, 0.007)
    turn = np.radians(20.0)
    rot = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
    gap = gaps.gap_behind(xy @ rot.T, h, CAMERA_XY, OUTLINE @ rot.T)
    assert gap is not None and gap.step_m == pytest.approx(0.007, abs=1e-6)
    assert gap.direction == pytest.approx(rot @ [0.0, 1.0], abs=1e-9)
    # looked for along the line of sight alone (no outline): not found
    assert gaps.gap_behind(xy @ rot.T, h, CAMERA_XY, np.zeros((0, 2))) is None


def test_no_step_no_gap_or_a_shadow_is_no_other_surface() -> None:
    # two tables side by side at one level: a gap, no step
    assert gaps.gap_behind(*_slabs(0.02, 0.0), CAMERA_XY, OUTLINE) is None
    # one table at two levels with no gap (a warp, a step of the cloth): no gap
    assert gaps.gap_behind(*_slabs(0.0, 0.007), CAMERA_XY, OUTLINE) is None
    # a shadow across the whole table, the table at one level beyond it
    assert gaps.gap_behind(*_slabs(0.0, 0.0, shadow=(0.3, 0.33)), CAMERA_XY, OUTLINE) is None
    # the step under the threshold: none; the threshold at the step's size: found
    assert gaps.gap_behind(*_slabs(0.02, 0.0025), CAMERA_XY, OUTLINE) is None
    assert gaps.gap_behind(*_slabs(0.02, 0.0031), CAMERA_XY, OUTLINE) is not None


@pytest.mark.parametrize(
    ("seed", "camera", "noise"),
    [(19, None, None), (19, REALSENSE_HD, None), (20, REALSENSE_HD, STEREO_NOISE), (24, None, STEREO_NOISE)],
)
def test_what_stands_on_a_desk_at_nearly_the_tables_level_is_excluded(
    seed: int, camera, noise, monkeypatch: pytest.MonkeyPatch
) -> None:
    # a desk 6-9 mm below the table and 2-2.5 cm behind it: one plane with the table; its
    # objects were objects
    view = {} if camera is None else {"camera": camera, "view": (0.6, 35.0)}
    frame = support_frame("desk_level_behind", seed, noise=noise, **view)
    truth = np.asarray(frame.fields["label"])
    seg = segment(frame, ON)
    sc = score(seg.labels(), truth)
    assert sc.true_positives == sc.n_true == sc.n_pred, (sc, [e.reason for e in seg.excluded])
    behind = [e for e in seg.excluded if e.reason.startswith("stands on another surface behind the support")]
    assert len(behind) >= 3
    assert all(np.mean(truth[e.indices] < 10) > 0.9 for e in behind)  # no object's points
    doc = segmentation_payload(seg)
    assert sum("a desk or a table behind" in e["reason"] for e in doc["excluded"]) == len(behind)
    # the step turned off: the desk's things are objects
    monkeypatch.setattr(gaps, "_STEP_MIN_M", np.inf)
    off = score(segment(frame, ON).labels(), truth)
    assert off.n_pred >= off.n_true + 3, off


def test_a_shadow_along_the_rays_is_not_looked_across(monkeypatch: pytest.MonkeyPatch) -> None:
    # a band 3 cm wide along the line of sight, empty the table's whole depth (an
    # object's shadow running to the far edge), the table 3.5 mm higher on its left than
    # on its right (a plane fitted across a warped cloud, mOSD test55: 3.1 mm): the outline's
    # sides across it are 90 degrees off the line of sight, never looked along
    x, y = np.meshgrid(np.arange(-0.5, 0.5, 0.005) + 0.0025, np.arange(0.0, 1.0, 0.005))
    xy = np.stack([x.ravel(), y.ravel()], axis=1)
    xy = xy[(xy[:, 0] < 0.0) | (xy[:, 0] >= 0.03)]
    h = np.where(xy[:, 0] < 0.0, 0.00175, -0.00175)
    assert gaps.gap_behind(xy, h, CAMERA_XY, OUTLINE) is None
    # looked across it (the limit off), the band is a gap with a step
    monkeypatch.setattr(gaps, "_MAX_TURN_RAD", np.pi / 2)
    found = gaps.gap_behind(xy, h, CAMERA_XY, OUTLINE)
    assert found is not None and abs(found.step_m) == pytest.approx(0.0035, abs=1e-6)
