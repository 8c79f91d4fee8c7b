"""The grasp kinds' registry: one entry per kind, in preference order (the cheapest and
surest first: the thesis's pinch, which the shipped PDDL domain holds, comes first).

This is the one list a grasp kind is named in, with the tool part it takes (fingers or
a cup: a profile's tool offers only the kinds it has the part for). The settings' allowed `[plan] grasps`
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
    # the part of the robot profile's tool it takes (clearcli/settings/profiles.py
    # ``tools``): "fingers" or "cup"; a profile's tool without it is not offered the kind
    tool: str = "fingers"
    # in [plan] grasps by default; a kind that is not is turned on by the profiles whose
    # tool takes it (their [plan] grasps default), or by --grasps
    default: bool = True

    @property
    def module_name(self) -> str:
        return self.module or f"clearcli.predicates.grasps.{self.name}"


# In preference order. (A test may replace this tuple: everything reads it when used.)
GRASP_KINDS: tuple[KindEntry, ...] = (
    KindEntry("pinch", "the thesis's, from above", required=True),
    KindEntry("rim", "an open container's wall"),
    KindEntry("slide", "a flat object slid to a seen table edge"),
    # a vacuum cup: only profiles whose tool has one (panda-hybrid, panda-suction, ...)
    KindEntry("suction", "a cup on a flat face, from above or the side", tool="cup", default=False),
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
    """ "pinch,rim,slide": the registered kinds on by default (the default of [plan]
    grasps; the fingers' kinds, which every profile's default tool takes)."""
    return ",".join(e.name for e in GRASP_KINDS if e.default)


def kinds_of_tool(tools: Sequence[str]) -> str:
    """ "pinch,rim,slide,suction": the registered kinds a tool with ``tools`` takes (a
    profile's [plan] grasps default when its tool is not the fingers alone). The pinch is
    always named (the domain's own grasp): with no fingers it is offered to nothing."""
    return ",".join(e.name for e in GRASP_KINDS if e.required or e.tool in tools)


def tool_of(name: str) -> str:
    """The tool part kind ``name`` takes (KeyError when none is registered)."""
    for e in GRASP_KINDS:
        if e.name == name:
            return e.tool
    raise KeyError(name)


def help_text() -> str:
    """ "pinch (the thesis's, from above), rim (...), ...": the kinds as --help lists them."""
    return ", ".join(f"{e.name} ({e.help})" for e in GRASP_KINDS)
