"""benchmarks/foreign_stages.py: an object's pieces read right, the refinements run one
by one give what refine.refine gives, and no frame of the report part is looked at."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import load_script


def _tool():
    return load_script("benchmarks/foreign_stages.py")


def test_pieces_name_the_segments_with_a_tenth_and_whose_they_are() -> None:
    # object 1: 10 points, 6 in segment 0, 3 in segment 2 (with 4 of object 2: object
    # 2's segment), 1 in segment 1 (exactly a tenth: a piece)
    truth = np.array([1] * 10 + [2] * 4 + [2] * 5)
    seg = np.array([0] * 6 + [2] * 3 + [1] + [2] * 4 + [3] * 5)
    text, key = _tool().pieces(seg, truth, 1, 0.1)
    assert text == "0:0.60 1:0.10 2:0.30(of 2)"
    assert key == ["0.10", "0.30(of 2)", "0.60"]
    # renumbered segments: the same key
    _, again = _tool().pieces(np.array([5, 4, 3, 0])[seg], truth, 1, 0.1)
    assert again == key
    # a piece of object 2: only segments with at least a tenth of its 9 points
    assert _tool().pieces(seg, truth, 2, 0.5)[0] == "3:0.56"


def test_the_stages_one_by_one_give_what_refine_gives() -> None:
    from clearcli import pipeline
    from clearcli.perception.refine import STAGES
    from clearcli.settings import Settings
    from clearcli.sim.camera import render
    from clearcli.sim.families import FAMILIES

    frame = render(FAMILIES["dense_mix"](0), seed=0)
    result, snaps, ctx = _tool().staged(frame, Settings())
    assert [name for name, _ in snaps] == ["lccp", *(s.name for s in STAGES)]
    assert ctx is not None
    assert np.array_equal(result.labels(), pipeline.segmented(frame, Settings()).labels())
    # the render is one where refinements change the segments (the planar cuts, a
    # supervoxel-level stage, and the seams, a voxel-level one), else the comparison
    # above says little
    changed = {snaps[k][0] for k in range(1, len(snaps)) if not np.array_equal(snaps[k][1], snaps[k - 1][1])}
    assert {"cuts", "seams"} <= changed


def test_frames_of_the_report_part_are_refused(monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    import sys

    report = _tool()._foreign().names("report")[0]
    monkeypatch.setattr(sys, "argv", ["foreign_stages.py", report])
    with pytest.raises(SystemExit):
        _tool().main()
    assert "not frames of the choose part" in capsys.readouterr().err
