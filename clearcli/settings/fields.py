"""What a setting is: a typed field with its default and its valid range, in one place.

A section is a frozen dataclass deriving from `Section`, each field declared with `param`
(default, bounds or choices). Building a section checks every value, whoever builds it
(a file, `--set`, a flag, a test): a wrong type, NaN, an infinity or a value out of range
raises `SettingsError` naming the key, the value and what is accepted. Bounds are
inclusive unless said otherwise; every float must be finite. Upper bounds on iteration
counts and sizes are there to keep a frame's work under a minute.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, get_type_hints

from clearcli.errors import SettingsError


@dataclass(frozen=True)
class Range:
    """Accepted values of one setting (numbers: bounds; strings: choices; tuples: each
    item within the bounds, at most ``max_items``)."""

    ge: float | None = None
    gt: float | None = None
    le: float | None = None
    lt: float | None = None
    choices: Sequence[str] = ()
    max_items: int | None = None
    lengths: tuple[int, ...] = ()  # allowed tuple lengths (empty: any up to max_items)
    text: str = ""  # free text (a path, a name): what it may be, checked where it is used
    # a set of names written "a,b" (strings only): each of ``members`` at most once, in
    # any order, ``required`` among them; kept in ``members``' order
    members: tuple[str, ...] = ()
    required: tuple[str, ...] = ()

    def describe(self) -> str:
        if self.text:
            return self.text
        if self.members:
            need = f" that includes {', '.join(self.required)}" if self.required else ""
            return f"a comma-separated list of {', '.join(self.members)} (any order, each at most once){need}"
        if self.choices:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        parts = []
        for op, v in ((">=", self.ge), (">", self.gt), ("<=", self.le), ("<", self.lt)):
            if v is not None:
                parts.append(f"{op} {v:g}")
        text = " and ".join(parts) if parts else "any finite number"
        if self.lengths:
            return f"a list of {' or '.join(map(str, self.lengths))} numbers, each {text}"
        if self.max_items is not None:
            return f"a list of at most {self.max_items} numbers, each {text}"
        return text

    def holds(self, v: float) -> bool:
        return (
            math.isfinite(v)
            and (self.ge is None or v >= self.ge)
            and (self.gt is None or v > self.gt)
            and (self.le is None or v <= self.le)
            and (self.lt is None or v < self.lt)
        )


def param(default: Any, **bounds: Any) -> Any:
    """A setting: its default and its range (``ge``, ``gt``, ``le``, ``lt``, ``choices``,
    ``max_items``, ``lengths``; ``text`` for free text, saying what it may be). ``choices``
    may be a live sequence (the robot profiles' names, settings/profiles.py): kept as it
    is, read when a value is checked; a list or a set is taken as a tuple."""
    if "choices" in bounds and isinstance(bounds["choices"], (list, set, frozenset)):
        bounds["choices"] = tuple(bounds["choices"])
    for key in ("lengths", "members", "required"):
        # (members, required: a live sequence too, the grasp kinds' names, settings/kinds.py)
        if key in bounds and isinstance(bounds[key], (list, set, frozenset)):
            bounds[key] = tuple(bounds[key])
    return dataclasses.field(default=default, metadata={"range": Range(**bounds)})


def range_of(cls: type, key: str) -> Range:
    for f in dataclasses.fields(cls):
        if f.name == key:
            return f.metadata.get("range", Range())
    raise KeyError(key)


def _type_name(typ: Any) -> str:
    return {bool: "true or false", int: "an integer", float: "a number", str: "a string"}.get(typ, "a list of numbers")


def set_of_names(where: str, text: Any, rng: Range) -> str:
    """ "rim, pinch" -> "pinch,rim": a set of ``rng.members`` in their order; SettingsError
    (naming ``where``) for an unknown name, a repeat, an empty item or a required one
    missing. One rule for a file, --set and a flag that is its alias (--grasps)."""
    items = [x.strip() for x in text] if isinstance(text, (list, tuple)) else str(text).split(",")
    items = [x.strip() if isinstance(x, str) else x for x in items]
    if (
        not all(isinstance(x, str) and x in rng.members for x in items)
        or len(set(items)) != len(items)
        or not set(rng.required) <= set(items)
    ):
        raise SettingsError(f"{where}: must be {rng.describe()}")
    return ",".join(m for m in rng.members if m in items)


def check_value(section: str, key: str, typ: Any, rng: Range, value: Any) -> Any:
    """``value`` as ``typ`` when it is of that type and within ``rng``; else SettingsError."""
    where = f"settings: [{section}] {key} = {value!r}"
    wanted = f"must be {_type_name(typ)}"
    if typ is bool:
        if not isinstance(value, bool):
            raise SettingsError(f"{where}: {wanted}")
        return value
    if typ is str and rng.members:
        if not isinstance(value, (str, list, tuple)):
            raise SettingsError(f"{where}: must be {rng.describe()}")
        return set_of_names(where, value, rng)
    if typ is str:
        if not isinstance(value, str):
            raise SettingsError(f"{where}: {wanted}")
        if rng.choices and value not in rng.choices:
            raise SettingsError(f"{where}: must be {rng.describe()}")
        if "\x00" in value:
            # no file name, frame or topic holds one, and the OS refuses it in a path
            raise SettingsError(f"{where}: holds a NUL character; give {rng.text or _type_name(typ)} without it")
        return value
    if typ is int or typ is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SettingsError(f"{where}: {wanted}")
        if typ is int and not isinstance(value, int):
            if not (isinstance(value, float) and math.isfinite(value) and value.is_integer()):
                raise SettingsError(f"{where}: {wanted} ({rng.describe()})")
            value = int(value)
        if not rng.holds(float(value)):
            raise SettingsError(f"{where}: out of range; accepted: {rng.describe()}")
        return typ(value)
    # tuple[float, ...]
    if not isinstance(value, (list, tuple)):
        raise SettingsError(f"{where}: must be a list of numbers ({rng.describe()})")
    items = []
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not rng.holds(float(v)):
            raise SettingsError(f"{where}: out of range; accepted: {rng.describe()}")
        items.append(float(v))
    if (rng.lengths and len(items) not in rng.lengths) or (rng.max_items is not None and len(items) > rng.max_items):
        raise SettingsError(f"{where}: out of range; accepted: {rng.describe()}")
    return tuple(items)


class Section:
    """Base of every settings section: values are checked when the section is built.

    ``NAME`` is the section's TOML table. ``cross_checks`` may add rules between keys
    (e.g. the closing width below the opening), raising SettingsError."""

    NAME: ClassVar[str] = ""
    if TYPE_CHECKING:  # every section class is a dataclass (its own decorator makes it one)
        __dataclass_fields__: ClassVar[dict[str, dataclasses.Field[Any]]]

    def __post_init__(self) -> None:
        hints = _hints(type(self))
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            checked = check_value(self.NAME, f.name, hints[f.name], f.metadata.get("range", Range()), value)
            if checked is not value:
                object.__setattr__(self, f.name, checked)
        self.cross_checks()

    def cross_checks(self) -> None:
        pass

    def fail(self, key: str, message: str) -> None:
        raise SettingsError(f"settings: [{self.NAME}] {key} = {getattr(self, key)!r}: {message}")


_HINTS: dict[type, dict[str, Any]] = {}


def _hints(cls: type) -> dict[str, Any]:
    got = _HINTS.get(cls)
    if got is None:
        raw = get_type_hints(cls)
        got = {}
        for name, typ in raw.items():
            got[name] = tuple if getattr(typ, "__origin__", None) is tuple else typ
        _HINTS[cls] = got
    return got
