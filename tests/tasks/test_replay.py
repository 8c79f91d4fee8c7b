"""Tests of clearcli/tasks/replay.py: a recorded session replayed frame by frame through
the task (Request, run with its report and note callbacks).

fixtures/session.mcap: 4 frames of clutter(10, seed=3), 0.5 s apart from t =
1763683200.0 s; frame 1 pushes object 6, frame 2 has it picked, frame 3 the cylinder
too (fixtures/README.md). Counts are checked against the log read with the mcap library."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from helpers import FIXTURES

from clearcli.errors import ClearError, InputError, PartialLogError
from clearcli.settings import Settings
from clearcli.tasks import replay as task

SESSION = FIXTURES / "session.mcap"
TOPIC = "/camera/depth_registered/points"
START_S = 1_763_683_200.0
PERIOD_S = 0.5


def _messages(path: Path) -> dict[str, list[int]]:
    """Log times of every message, by topic (the mcap library's reader)."""
    from mcap.reader import make_reader

    found: dict[str, list[int]] = {}
    with open(path, "rb") as fp:
        for _, channel, message in make_reader(fp).iter_messages(log_time_order=True):
            found.setdefault(channel.topic, []).append(int(message.log_time))
    return found


def _replay(request: task.Request, log: Path, topic: str | None = None) -> dict[str, Any]:
    reports: list[tuple[Any, int, int | None]] = []
    notes: list[str] = []
    summary, partial = task.run(request, log, topic, lambda r, n, total: reports.append((r, n, total)), notes.append)
    return {"reports": reports, "notes": notes, "summary": summary, "partial": partial}


@pytest.fixture(scope="module")
def every_other(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """Frames 0 and 2 of the session, with an annotated log."""
    out = tmp_path_factory.mktemp("replay") / "annotated.mcap"
    done = _replay(task.Request(Settings(), every=2, out=out), SESSION)
    done["out"] = out
    return done


def test_one_report_per_replayed_frame(every_other: dict[str, Any]) -> None:
    in_log = len(_messages(SESSION)[TOPIC])
    assert in_log == 4
    reports = every_other["reports"]
    assert [r.index for r, _, _ in reports] == [0, 2]
    # frames read so far (the skipped one counted) and the topic's count from the index
    assert [(n, total) for _, n, total in reports] == [(1, in_log), (3, in_log)]
    for report, _, _ in reports:
        line = report.to_json()
        assert line["type"] == "frame" and line["index"] == report.index
        assert line["stamp_s"] == pytest.approx(START_S + PERIOD_S * report.index)
        assert line["time_s"] == pytest.approx(PERIOD_S * report.index)
        assert line["status"] == "ok" and line["first_action"] is not None
        assert line["plan_length"] >= 1
    summary = every_other["summary"].to_json()
    assert (summary["frames_read"], summary["frames"], summary["ok"]) == (4, 2, 2)
    assert every_other["partial"] is None


def test_objects_keep_their_ids_between_frames(every_other: dict[str, Any]) -> None:
    (first, _, _), (second, _, _) = every_other["reports"]
    ids0 = {o.track_id for o in first.objects}
    ids2 = {o.track_id for o in second.objects}
    # fixtures/README.md: 10 objects in frame 0, object 6 picked by frame 2: 9 left
    assert 9 <= len(ids0) <= 10 and len(ids2) == 9
    assert all(o.new for o in first.objects)
    # at most one object changes its id: the pushed-then-picked box leaves, the rest stay
    assert len(ids2 - ids0) <= 1 and set(second.gone) <= ids0
    assert not any(o.new for o in second.objects if o.track_id in ids0)


def test_the_annotated_log_holds_the_replayed_frames(every_other: dict[str, Any]) -> None:
    source = _messages(SESSION)[TOPIC]
    written = _messages(every_other["out"])
    # the replayed input frames, copied at their own log times, each with its annotations
    assert written[TOPIC] == [source[0], source[2]]
    assert written["/clear/scene"] == written[TOPIC]
    assert written["/clear/plan"] == written[TOPIC] and written["/clear/predicates"] == written[TOPIC]


def test_a_pcd_is_replayed_as_one_frame() -> None:
    done = _replay(task.Request(Settings()), FIXTURES / "isolated_box.pcd")
    ((report, n, total),) = done["reports"]
    assert (report.index, n, total) == (0, 1, 1)
    assert report.status == "ok" and len(report.objects) == 1
    assert report.first_action().kind == "grasp"  # type: ignore[union-attr]


def test_a_truncated_log_gives_its_complete_frames_then_the_break(tmp_path: Path) -> None:
    data = SESSION.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * 0.3)])  # /tf_static and one complete frame
    done = _replay(task.Request(Settings()), cut)
    assert [r.index for r, _, _ in done["reports"]] == [0]
    partial = done["partial"]
    assert isinstance(partial, PartialLogError) and partial.exit_code == 9  # returned, not raised
    assert done["summary"].to_json()["stopped"]


def test_the_base_frame_named_is_looked_up_in_the_logs_transforms() -> None:
    # the session's /tf_static holds table -> camera_rgb_optical_frame (fixtures/README.md)
    done = _replay(task.Request(Settings(), base_frame="table", to_s=0.0), SESSION)
    assert [r.index for r, _, _ in done["reports"]] == [0]
    assert done["notes"] == ["robot base: table -> camera_rgb_optical_frame from the log's transforms"]


@pytest.mark.parametrize(
    ("given", "topic", "match"),
    [
        ({"from_s": 100.0, "to_s": 200.0}, None, "select no frame"),
        ({"from_s": 1.0, "to_s": 0.2}, None, "select no frame"),
        ({}, "/nope", "no topic '/nope'"),
    ],
)
def test_a_replay_of_nothing_is_an_input_error(given: dict[str, Any], topic: str | None, match: str) -> None:
    with pytest.raises(InputError, match=match):
        _replay(task.Request(Settings(), **given), SESSION, topic)


def test_a_missing_log_is_a_clear_error(tmp_path: Path) -> None:
    with pytest.raises(ClearError) as info:
        _replay(task.Request(Settings()), tmp_path / "none.mcap")
    assert info.value.exit_code == 3
