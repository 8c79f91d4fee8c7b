"""Tests of clearcli/settings/kinds.py: the grasp kinds' registry, the one list a kind is
named in (what [plan] grasps accepts, its default, the --grasps help)."""

from __future__ import annotations

import importlib

import pytest

from clearcli.settings import kinds


def test_the_registered_kinds_in_preference_order_and_the_fingers_ones_on_by_default() -> None:
    assert [e.name for e in kinds.entries()] == ["pinch", "rim", "slide", "suction"]
    assert list(kinds.KIND_NAMES) == ["pinch", "rim", "slide", "suction"] and len(kinds.KIND_NAMES) == 4
    assert kinds.KIND_NAMES[0] == "pinch" and kinds.KIND_NAMES[-1] == "suction"
    assert list(kinds.REQUIRED_KINDS) == ["pinch"]  # the shipped domain's own grasp
    assert "rim" in kinds.KIND_NAMES and "rim" not in kinds.REQUIRED_KINDS and "twist" not in kinds.KIND_NAMES
    # suction takes a cup: off by default (the WAM's default is the thesis's tool, fingers)
    assert kinds.default_kinds() == "pinch,rim,slide"
    assert [kinds.tool_of(n) for n in kinds.KIND_NAMES] == ["fingers", "fingers", "fingers", "cup"]
    assert kinds.kinds_of_tool(("cup",)) == "pinch,suction"
    assert kinds.kinds_of_tool(("fingers", "cup")) == "pinch,rim,slide,suction"


def test_each_kind_names_an_importable_module_holding_its_kind() -> None:
    for entry in kinds.entries():
        assert entry.module_name == f"clearcli.predicates.grasps.{entry.name}"
        module = importlib.import_module(entry.module_name)
        assert hasattr(module, "KIND")
    assert kinds.KindEntry("x", "h", module="pkg.mod").module_name == "pkg.mod"


def test_the_help_lists_each_kind_with_its_words() -> None:
    text = kinds.help_text()
    assert text.startswith("pinch (the thesis's, from above), rim (")
    for entry in kinds.entries():
        assert f"{entry.name} ({entry.help})" in text


def test_the_names_follow_the_registry_as_it_is_now(monkeypatch: pytest.MonkeyPatch) -> None:
    toy = kinds.KindEntry("twist", "a toy kind", module="tests.helpers.toy_kind")
    monkeypatch.setattr(kinds, "GRASP_KINDS", (*kinds.GRASP_KINDS, toy))
    assert list(kinds.KIND_NAMES) == ["pinch", "rim", "slide", "suction", "twist"] and "twist" in kinds.KIND_NAMES
    assert kinds.default_kinds() == "pinch,rim,slide,twist"
    assert list(kinds.REQUIRED_KINDS) == ["pinch"]
    assert "twist (a toy kind)" in kinds.help_text()
    monkeypatch.undo()
    assert "twist" not in kinds.KIND_NAMES and kinds.default_kinds() == "pinch,rim,slide"
