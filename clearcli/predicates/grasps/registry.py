"""The grasp kinds, in preference order: the objects of the modules the registry names
(clearcli/settings/kinds.py, one entry per kind), each checked to be the kind its entry
names. Everything that handles grasp kinds reads them here, when it needs them (a test
may register a kind of its own)."""

from __future__ import annotations

import importlib

from clearcli.predicates.grasps.base import GraspKind
from clearcli.settings import kinds as registered
from clearcli.settings.fields import range_of, set_of_names
from clearcli.settings.plan import PlanSettings

_loaded: tuple[tuple[object, ...], tuple[GraspKind, ...]] = ((), ())


def kinds() -> tuple[GraspKind, ...]:
    """Every registered kind's object, in preference order (the thesis's pinch first)."""
    global _loaded
    entries = registered.entries()
    if _loaded[0] != entries:
        out = []
        for e in entries:
            kind = importlib.import_module(e.module_name).KIND
            if kind.name != e.name:
                raise AssertionError(
                    f"clearcli/settings/kinds.py: {e.module_name}.KIND is {kind.name!r}, not {e.name!r}"
                )
            out.append(kind)
        if not out or not out[0].thesis or any(k.thesis for k in out[1:]):
            raise AssertionError("clearcli/settings/kinds.py: the thesis's pinch comes first, and only it")
        _loaded = (entries, tuple(out))
    return _loaded[1]


def kind(name: str) -> GraspKind:
    """The kind named ``name`` (KeyError when none is)."""
    for k in kinds():
        if k.name == name:
            return k
    raise KeyError(name)


def kind_names() -> tuple[str, ...]:
    return tuple(k.name for k in kinds())


def kind_of_action(action_name: str) -> GraspKind:
    """The kind whose PDDL action is ``action_name`` (KeyError when none is)."""
    for k in kinds():
        if k.facts.action == action_name:
            return k
    raise KeyError(action_name)


def parse_kinds(text: str) -> tuple[str, ...]:
    """ "rim,pinch" -> ("pinch", "rim"); one line SettingsError for anything else: the
    rule of [plan] grasps itself (`clear domain --grasps` and the settings agree)."""
    canonical = set_of_names(f"settings: [plan] grasps = {text!r}", text, range_of(PlanSettings, "grasps"))
    return tuple(canonical.split(","))
