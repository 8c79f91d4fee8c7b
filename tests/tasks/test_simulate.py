"""Tests of clearcli/tasks/simulate.py: a self-made clearing session written as an MCAP
log, its summary the payload of schema clear.simulate.

The log is read back with the mcap library; the payload's counts are checked against it
and against each other."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from clearcli.errors import SettingsError
from clearcli.settings import Settings
from clearcli.tasks import simulate as task

TOPIC = "/camera/depth_registered/points"


def _topics(path: Path) -> dict[str, int]:
    from mcap.reader import make_reader

    counts: dict[str, int] = {}
    with open(path, "rb") as fp:
        for _, channel, _ in make_reader(fp).iter_messages():
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    return counts


def _run(tmp_path: Path, name: str, **given: Any) -> tuple[dict[str, Any], Path]:
    out = tmp_path / f"{name}.mcap"
    payload = task.run(task.Request(Settings(), **given), out)
    assert payload["out"] == str(out)
    return payload, out


def test_a_seeded_session_is_the_same_every_time_and_another_seed_differs(tmp_path: Path) -> None:
    one, first = _run(tmp_path, "a", scene="isolated_box", seed=1, truth_segmentation=True)
    two, second = _run(tmp_path, "b", scene="isolated_box", seed=1, truth_segmentation=True)
    other, third = _run(tmp_path, "c", scene="isolated_box", seed=2, truth_segmentation=True)
    assert {**one, "out": ""} == {**two, "out": ""}
    assert first.read_bytes() == second.read_bytes()  # the log too, byte for byte
    assert other["seed"] == 2
    assert third.read_bytes() != first.read_bytes()  # the seed reaches the camera's noise


def test_the_summary_agrees_with_the_log_it_wrote(tmp_path: Path) -> None:
    payload, out = _run(tmp_path, "two", scene="two_touching_boxes", seed=4, truth_segmentation=True)
    counts = _topics(out)
    assert counts[TOPIC] == payload["frames"]
    assert counts.get("/tf_static") == 1  # the robot base to the camera
    assert payload["scene"] == "two_touching_boxes()" and payload["objects"] == 2
    acted = [s for s in payload["steps"] if s["action"]]
    assert payload["actions"] == len(acted) == sum(payload["actions_per_object"].values())
    assert [s["frame"] for s in payload["steps"]] == list(range(len(payload["steps"])))
    assert payload["end"] == "cleared" and payload["remaining"] == [] and payload["cleared_truly"] is True
    # a cleared session: every frame but the last acted, the last saw an empty table
    assert payload["frames"] == payload["actions"] + 1
    assert payload["steps"][-1]["status"] == "cleared"
    assert (task.SCHEMA, task.VERSION) == ("simulate", 1)


def test_an_action_budget_of_one_stops_after_one_action(tmp_path: Path) -> None:
    payload, out = _run(tmp_path, "budget", scene="two_touching_boxes", max_actions=1, truth_segmentation=True)
    assert payload["actions"] == 1 and payload["max_actions"] == 1
    assert payload["end"] == "budget" and len(payload["remaining"]) == 1
    assert _topics(out)[TOPIC] == payload["frames"]


def test_a_clutter_scene_is_named_by_its_objects_and_seed(tmp_path: Path) -> None:
    payload, _ = _run(tmp_path, "clutter", scene="clutter", objects=2, seed=5, truth_segmentation=True)
    assert payload["scene"] == "clutter(2, seed=5)" and payload["objects"] == 2


def test_an_unknown_scene_is_refused_before_anything_is_written(tmp_path: Path) -> None:
    request = task.Request(Settings(), scene="kitchen")
    with pytest.raises(SettingsError, match="--scene 'kitchen'") as info:
        task.check(request)
    assert all(s in str(info.value) for s in task.SCENES)
    with pytest.raises(SettingsError):
        task.run(request, tmp_path / "never.mcap")
    assert list(tmp_path.iterdir()) == []


def test_a_clutter_the_table_cannot_hold_is_a_settings_error(tmp_path: Path) -> None:
    with pytest.raises(SettingsError, match="no room"):
        task.run(task.Request(Settings(), scene="clutter", objects=100, seed=6), tmp_path / "full.mcap")
    assert not (tmp_path / "full.mcap").exists()


@pytest.mark.xfail(
    strict=True,
    reason="the task takes max_actions <= 0 and objects < 0 (only the CLI's option bounds refuse them): "
    "max_actions=0 still acts once (payload: actions 1, max_actions 0); objects=-1 simulates 'clutter(-1, seed=0)'",
)
@pytest.mark.parametrize("given", [{"max_actions": 0}, {"max_actions": -1}, {"objects": -1, "scene": "clutter"}])
def test_a_request_out_of_bounds_is_refused_or_kept_to(given: dict[str, Any], tmp_path: Path) -> None:
    request = task.Request(Settings(), **{"scene": "isolated_box", "truth_segmentation": True, **given})
    try:
        payload = task.run(request, tmp_path / "x.mcap")
    except SettingsError:
        return
    assert payload["actions"] <= max(request.max_actions, 0)
    assert payload["objects"] >= 0 and request.objects >= 0
