"""`clear simulate` on the command line, as a user or a script runs it."""

from __future__ import annotations

from pathlib import Path

from helpers.replay_session import _clear_inprocess, _lines


def test_simulate_command_writes_a_replayable_log(tmp_path: Path, capsys, monkeypatch) -> None:
    from clearcli.io.mcap import read_summary

    out = tmp_path / "sim.mcap"
    code, stdout, err = _clear_inprocess(
        capsys, monkeypatch, "simulate", str(out), "--scene", "two_touching_boxes", "--truth-segmentation", "--json"
    )
    assert code == 0, err
    (payload,) = _lines(stdout)
    assert payload["schema"] == "clear.simulate" and payload["end"] == "cleared"
    assert payload["objects"] == 2 and payload["remaining"] == [] and payload["actions"] >= 2
    assert payload["frames"] == len(payload["steps"]) == payload["actions"] + 1
    summary = read_summary(out)
    assert summary.count("/camera/depth_registered/points") == payload["frames"]
    assert summary.count("/tf_static") == 1
    code, _, err = _clear_inprocess(capsys, monkeypatch, "simulate", str(out), "--scene", "isolated_box")
    assert code == 8 and "--force" in err
