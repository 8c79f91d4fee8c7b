"""Tests of clearcli/tasks/sources.py: from the inputs a user names to a batch's frames."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from helpers import FIXTURES

from clearcli.errors import InputError
from clearcli.tasks.sources import (
    BadInput,
    FrameRef,
    check_unique_names,
    expand,
    natural_key,
)


def test_natural_key_orders_numbers_by_value() -> None:
    names = ["learn10.pcd", "learn2.pcd", "learn1.pcd", "a.pcd"]
    assert sorted(names, key=lambda n: natural_key(Path(n))) == ["a.pcd", "learn1.pcd", "learn2.pcd", "learn10.pcd"]


def test_natural_key_of_names_with_other_digits() -> None:
    """Superscripts are digits to str.isdigit but not numbers to int(): "1²3.pcd" once
    made a folder's batch an internal error (and an int against a str in the sort).
    Decimal digits of other scripts are numbers, as \\d finds them."""
    names = ["1²3.pcd", "a².pcd", "12.pcd", "\u0663.pcd", "2.pcd"]  # \u0663: ARABIC-INDIC DIGIT THREE
    keys = [natural_key(Path(n)) for n in names]
    assert keys[0] == ("", 1, "²", 3, ".pcd") and keys[3] == ("", 3, ".pcd")
    assert sorted(names, key=lambda n: natural_key(Path(n))) == ["1²3.pcd", "2.pcd", "\u0663.pcd", "12.pcd", "a².pcd"]


def test_folder_expands_to_its_frames_in_natural_order(tmp_path: Path) -> None:
    for name in ("f10.pcd", "f2.pcd", "f1.pcd"):
        shutil.copy(FIXTURES / "isolated_box.pcd", tmp_path / name)
    (tmp_path / "notes.txt").write_text("not a frame")
    (tmp_path / ".f3.pcd.part").write_text("a temporary a killed batch left")
    sub = tmp_path / "sub"
    sub.mkdir()
    shutil.copy(FIXTURES / "box_on_box.pcd", sub / "g.pcd")
    items = expand([tmp_path])
    assert all(isinstance(it, FrameRef) for it in items)
    assert [it.name for it in items] == ["f1", "f2", "f10", "g"]
    assert [Path(it.source).name for it in items] == ["f1.pcd", "f2.pcd", "f10.pcd", "g.pcd"]
    assert all(it.index == 0 and not it.is_log for it in items)


def test_a_log_gives_one_frame_or_every_nth_named_by_index() -> None:
    log = FIXTURES / "session.mcap"
    (one,) = expand([log], frame=2)
    assert (one.index, one.name, one.is_log) == (2, "session_f2", True)
    every = expand([log], every=2)
    assert [it.index for it in every] == list(range(0, len(every) * 2, 2))
    assert all(it.name == f"session_f{it.index}" for it in every)


def test_what_yields_no_frame_is_a_bad_input_line(tmp_path: Path) -> None:
    empty = tmp_path / "empty"
    empty.mkdir()
    missing = tmp_path / "missing.pcd"
    items = expand([missing, empty])
    assert [type(it) for it in items] == [BadInput, BadInput]
    assert items[0].exit_code == 3 and "file not found" in items[0].message
    assert "holds no .pcd, .mcap or .bag" in items[1].message


def test_two_frames_writing_the_same_name_are_refused(tmp_path: Path) -> None:
    for d in ("a", "b"):
        (tmp_path / d).mkdir()
        shutil.copy(FIXTURES / "isolated_box.pcd", tmp_path / d / "x.pcd")
    items = expand([tmp_path / "a", tmp_path / "b"])
    with pytest.raises(InputError, match="would both write outputs named 'x'"):
        check_unique_names(items)
    check_unique_names(expand([tmp_path / "a"]))  # one of them alone is fine
