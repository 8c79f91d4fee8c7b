"""Tests of clearcli/replay/tracking.py."""

from __future__ import annotations

import numpy as np
import pytest

from clearcli.replay.tracking import (
    ExpectedEffect,
    Observation,
    TrackerState,
    TrackingParams,
    check_execution,
    shape_signature,
    update,
)

BOX = shape_signature((0.06, 0.10, 0.08))  # (0.10, 0.08, 0.06)


CAN = shape_signature((0.066, 0.066, 0.12))


BOTTLE = shape_signature((0.07, 0.07, 0.25))


FLAT = shape_signature((0.15, 0.10, 0.03))


def obs(x: float, y: float, shape=BOX, z: float = 0.8, name: str = "") -> Observation:
    return Observation(centroid=(x, y, z), extents_m=shape, name=name)


def test_shape_signature_ignores_axis_order() -> None:
    assert shape_signature((0.02, 0.3, 0.1)) == (0.3, 0.1, 0.02)
    assert shape_signature(np.array([0.1, 0.3, 0.02])) == (0.3, 0.1, 0.02)


def test_first_frame_numbers_objects_in_order() -> None:
    state, a = update(TrackerState(), [obs(0, 0), obs(0.2, 0), obs(0, 0.2, CAN)], 0)
    assert a.ids == (0, 1, 2)
    assert a.new == (0, 1, 2)
    assert a.gone == ()
    assert state.next_id == 3


def test_ids_survive_shuffled_order_and_jitter() -> None:
    first = [obs(0.0, 0.0), obs(0.12, 0.0, CAN), obs(0.0, 0.12, FLAT), obs(0.12, 0.12)]
    state, a0 = update(TrackerState(), first, 0)
    rng = np.random.default_rng(3)
    for frame in range(1, 6):
        order = rng.permutation(len(first))
        jittered = [
            Observation(
                centroid=tuple(np.add(first[k].centroid, rng.normal(0, 0.005, 3))),  # type: ignore[arg-type]
                extents_m=tuple(np.add(first[k].extents_m, rng.normal(0, 0.004, 3))),  # type: ignore[arg-type]
            )
            for k in order
        ]
        state, a = update(state, jittered, frame)
        assert [a.ids[i] for i in np.argsort(order)] == list(a0.ids)
        assert a.new == () and a.gone == ()


def test_pushed_object_keeps_its_id_only_with_the_expected_effect() -> None:
    # object 0 pushed 0.15 m along +x, stopping short after 0.11 m and turning, so that
    # its box reads 2 cm longer from the camera; object 1 stands aside, untouched
    before = [obs(0.0, 0.0), obs(0.0, 0.15, CAN)]
    turned = (BOX[0] + 0.02, BOX[1], BOX[2])
    after = [obs(0.0, 0.15, CAN), obs(0.11, 0.01, turned)]
    state, _ = update(TrackerState(), before, 0)
    effect = ExpectedEffect(
        kind="push",
        track_id=0,
        start_centroid=(0.0, 0.0, 0.8),
        unit_vector=(1.0, 0.0, 0.0),
        push_length_m=0.15,
        extents_m=BOX,
    )
    _, with_effect = update(state, after, 1, effect)
    assert with_effect.ids == (1, 0)
    assert with_effect.new == () and with_effect.gone == ()
    # without knowing about the push, 0.11 m is beyond the gate: a new object, 0 gone
    _, without = update(state, after, 1, None)
    assert without.ids == (1, 2)
    assert without.gone == (0,)


def test_object_moved_unexpectedly_keeps_its_id_when_its_size_matches() -> None:
    # nothing was planned for object 0, yet it is 9 cm away with the same size (a
    # recorded action other than the replayed plan's): the second pass keeps its id
    state, _ = update(TrackerState(), [obs(0.0, 0.0), obs(0.3, 0.0, CAN)], 0)
    _, a = update(state, [obs(0.3, 0.0, CAN), obs(0.0, 0.09)], 1)
    assert a.ids == (1, 0) and a.new == () and a.gone == ()
    # a different size there is another object
    _, a = update(state, [obs(0.3, 0.0, CAN), obs(0.0, 0.09, FLAT)], 1)
    assert a.ids == (1, 2) and a.gone == (0,)
    # and too far is another object too
    _, a = update(state, [obs(0.3, 0.0, CAN), obs(0.0, 0.2)], 1)
    assert a.ids == (1, 2)


def test_object_shoved_by_a_push_keeps_its_id() -> None:
    # object 1 sits right in front of object 0's push and is shoved 0.09 m along
    before = [obs(0.0, 0.0), obs(0.09, 0.0, CAN)]
    after = [obs(0.08, 0.0), obs(0.18, 0.01, CAN)]
    state, _ = update(TrackerState(), before, 0)
    effect = ExpectedEffect("push", 0, (0.0, 0.0, 0.8), "", (1.0, 0.0, 0.0), 0.10, BOX)
    _, a = update(state, after, 1, effect)
    assert a.ids == (0, 1)


def test_new_object_new_id_removed_object_gone() -> None:
    state, _ = update(TrackerState(), [obs(0, 0), obs(0.2, 0), obs(0, 0.2)], 0)
    state, a = update(state, [obs(0.2, 0), obs(0, 0), obs(-0.3, 0.3, CAN)], 1)
    assert a.ids == (1, 0, 3)
    assert a.new == (3,)
    assert a.gone == (2,)
    # gone is said once: the next frame does not repeat it
    state, a = update(state, [obs(0.2, 0), obs(0, 0), obs(-0.3, 0.3, CAN)], 2)
    assert a.gone == () and a.ids == (1, 0, 3)


def test_shape_change_breaks_identity() -> None:
    # a box replaced in place by a bottle is another object
    state, _ = update(TrackerState(), [obs(0, 0, BOX)], 0)
    _, a = update(state, [obs(0, 0, BOTTLE)], 1)
    assert a.ids == (1,) and a.gone == (0,)


def test_missed_object_comes_back_with_its_id_within_the_memory() -> None:
    params = TrackingParams(max_missing_frames=2)
    state, _ = update(TrackerState(), [obs(0, 0), obs(0.2, 0)], 0, params=params)
    state, a = update(state, [obs(0.2, 0)], 1, params=params)
    assert a.gone == (0,)
    state, a = update(state, [obs(0, 0), obs(0.2, 0)], 2, params=params)
    assert a.ids == (0, 1) and a.new == ()
    # missing for longer than the memory: forgotten, the state stays bounded
    for frame in range(3, 7):
        state, _ = update(state, [obs(0.2, 0)], frame, params=params)
    assert [t.track_id for t in state.tracks] == [1]
    _, a = update(state, [obs(0, 0), obs(0.2, 0)], 7, params=params)
    assert a.ids == (2, 1)


def test_grasp_monitoring() -> None:
    state, _ = update(TrackerState(), [obs(0, 0), obs(0.2, 0)], 0)
    effect = ExpectedEffect("grasp", 0, (0.0, 0.0, 0.8), "(grasp #0)")
    _, a = update(state, [obs(0.2, 0)], 1, effect)
    report = check_execution(effect, [obs(0.2, 0)], a)
    assert report.outcome == "done"
    # a failed grasp leaves the object where it was: it keeps its id, and it is reported
    after = [obs(0.2, 0), obs(0.004, 0.002)]
    _, a = update(state, after, 1, effect)
    assert a.ids == (1, 0)
    report = check_execution(effect, after, a)
    assert report.outcome == "failed"
    assert "still on the table" in report.detail


@pytest.mark.parametrize(("moved", "outcome"), [(0.12, "done"), (0.076, "done"), (0.05, "failed"), (0.0, "failed")])
def test_push_monitoring(moved: float, outcome: str) -> None:
    u = np.array([0.6, 0.8, 0.0])
    start = (0.0, 0.0, 0.8)
    state, _ = update(TrackerState(), [Observation(start, BOX)], 0)
    effect = ExpectedEffect("push", 0, start, "(push #0 dir1)", tuple(u), 0.15, BOX)  # type: ignore[arg-type]
    landed = tuple(np.add(start, moved * u + np.array([0.8, -0.6, 0.0]) * 0.01))
    after = [Observation(landed, BOX)]  # type: ignore[arg-type]
    _, a = update(state, after, 1, effect)
    assert a.ids == (0,)
    report = check_execution(effect, after, a)
    assert report.outcome == outcome
    assert report.moved_along_m == pytest.approx(moved, abs=1e-9)
    assert report.moved_across_m == pytest.approx(0.01, abs=1e-9)


def test_push_monitoring_lost_object() -> None:
    state, _ = update(TrackerState(), [obs(0, 0)], 0)
    effect = ExpectedEffect("push", 0, (0.0, 0.0, 0.8), "", (1.0, 0.0, 0.0), 0.1, BOX)
    _, a = update(state, [], 1, effect)
    assert a.gone == (0,)
    assert check_execution(effect, [], a).outcome == "failed"
