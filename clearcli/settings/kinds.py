"""The grasp kinds' registry: one entry per kind, in preference order (the cheapest and
surest first: the thesis's pinch, which the shipped PDDL domain holds, comes first).

This is the one list a grasp kind is named in. The settings' allowed `[plan] grasps`
(its members and default), the `--grasps` help and, through
`clearcli.predicates.grasps.registry`, the facts, the domain text, the SAS+ compiler,
backtracking, pictures, replay and the simulated world are made from it. It lives in
the settings package, the bottom layer, so that the settings tree and every layer above
can read it; a kind's module is named here by its text, never imported from here (the
tree stays below the predicates). A new kind is its module (one object ``KIND``
implementing `clearcli.predicates.grasps.base.GraspKind`) and one entry below.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class KindEntry:
    """One registered grasp kind: ``module`` (dotted, importable) holds its ``KIND``;
    ``help`` says in a few words what it takes and how (``--grasps``); a ``required``
    kind is always allowed (the pinch: the shipped domain's own grasp)."""

    name: str
    help: str
    module: str = ""  # "" = clearcli.predicates.grasps.<name>
    required: bool = False

    @property
    def module_name(self) -> str:
        return self.module or f"clearcli.predicates.grasps.{self.name}"


# In preference order. (A test may replace this tuple: everything reads it when used.)
GRASP_KINDS: tuple[KindEntry, ...] = (
    KindEntry("pinch", "the thesis's, from above", required=True),
    KindEntry("rim", "an open container's wall"),
    KindEntry("slide", "a flat object slid to a seen table edge"),
)


class _Names(Sequence[str]):
    """The registered names in order, as the registry holds them now (``required``: the
    required ones only): what `[plan] grasps` accepts."""

    def __init__(self, required: bool = False) -> None:
        self._required = required

    def _now(self) -> tuple[str, ...]:
        return tuple(e.name for e in GRASP_KINDS if e.required or not self._required)

    def __getitem__(self, index: Any) -> Any:
        return self._now()[index]

    def __len__(self) -> int:
        return len(self._now())

    def __iter__(self) -> Iterator[str]:
        return iter(self._now())

    def __contains__(self, name: object) -> bool:
        return name in self._now()

    def __repr__(self) -> str:
        return repr(self._now())


KIND_NAMES: Sequence[str] = _Names()
REQUIRED_KINDS: Sequence[str] = _Names(required=True)


def entries() -> tuple[KindEntry, ...]:
    """The registered kinds, in preference order, as the registry holds them now."""
    return tuple(GRASP_KINDS)


def default_kinds() -> str:
    """ "pinch,rim,slide": every registered kind (the default of [plan] grasps)."""
    return ",".join(KIND_NAMES)


def help_text() -> str:
    """ "pinch (the thesis's, from above), rim (...), ...": the kinds as --help lists them."""
    return ", ".join(f"{e.name} ({e.help})" for e in GRASP_KINDS)
