"""Tests of clearcli/settings/kinds.py: the grasp kinds' registry, the one list a kind is
named in (what [plan] grasps accepts, its default, the --grasps help)."""

from __future__ import annotations

import importlib

import pytest

from clearcli.settings import kinds


def test_the_registered_kinds_are_pinch_rim_slide_in_preference_order() -> None:
    assert [e.name for e in kinds.entries()] == ["pinch", "rim", "slide"]
    assert list(kinds.KIND_NAMES) == ["pinch", "rim", "slide"] and len(kinds.KIND_NAMES) == 3
    assert kinds.KIND_NAMES[0] == "pinch" and kinds.KIND_NAMES[-1] == "slide"
    assert list(kinds.REQUIRED_KINDS) == ["pinch"]  # the shipped domain's own grasp
    assert "rim" in kinds.KIND_NAMES and "rim" not in kinds.REQUIRED_KINDS and "twist" not in kinds.KIND_NAMES
    assert kinds.default_kinds() == "pinch,rim,slide"


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
    assert list(kinds.KIND_NAMES) == ["pinch", "rim", "slide", "twist"] and "twist" in kinds.KIND_NAMES
    assert kinds.default_kinds() == "pinch,rim,slide,twist"
    assert list(kinds.REQUIRED_KINDS) == ["pinch"]
    assert "twist (a toy kind)" in kinds.help_text()
    monkeypatch.undo()
    assert "twist" not in kinds.KIND_NAMES and kinds.default_kinds() == "pinch,rim,slide"
