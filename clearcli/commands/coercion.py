"""Command-line values of the plain kinds (str, int, float, bool, Path, lists of them) converted
without pydantic, the same values typer's own conversion gives.

Typer (0.2x) converts every option through a pydantic TypeAdapter it builds on first use:
importing pydantic and building the adapters was ~0.12 s of CPU of `clear schema plan`
on a loaded machine (issue 39), for values that are strings, integers and paths. Here a
parameter of those kinds gets `_Plain` in place of typer's converter: it converts what is
certainly convertible (a decimal integer within its bounds, a plain decimal number, a path
string ...) exactly as pydantic would, and hands anything else (an error, an unusual
spelling, a kind not listed) to typer's own converter, built then: the same result or
the same error message. tests/cli/test_coercion.py compares the two on every parameter of
every command.

Typer's converter is a private attribute of its parameters (`_runtime_param`, built by
`get_runtime_param`); when a typer release no longer has them, `install` does nothing and
typer converts everything itself.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, get_args, get_origin

_INT = re.compile(r"-?(?:0|[1-9][0-9]{0,17})")  # what int() and pydantic read alike
_FLOAT = re.compile(r"-?[0-9]{1,15}(?:\.[0-9]{1,15})?")  # plain decimals only: no exponent, inf, nan


class _NotPlain(Exception):
    """A value `_Plain` leaves to typer's converter."""


def _str(value: Any, info: Any, param: Any, ctx: Any) -> Any:
    if isinstance(value, str):
        return value
    raise _NotPlain


def _int(value: Any, info: Any, param: Any, ctx: Any) -> Any:
    if isinstance(value, int) and not isinstance(value, bool):
        number = value
    elif isinstance(value, str) and _INT.fullmatch(value):
        number = int(value)
    else:
        raise _NotPlain
    if (info.min is not None and number < info.min) or (info.max is not None and number > info.max):
        raise _NotPlain  # typer's message says which bound
    return number


def _float(value: Any, info: Any, param: Any, ctx: Any) -> Any:
    if isinstance(value, float):
        number = value
    elif isinstance(value, int) and not isinstance(value, bool):
        number = float(value)
    elif isinstance(value, str) and _FLOAT.fullmatch(value):
        number = float(value)
    else:
        raise _NotPlain
    if (info.min is not None and number < info.min) or (info.max is not None and number > info.max):
        raise _NotPlain
    return number


def _path(value: Any, info: Any, param: Any, ctx: Any) -> Any:
    from typer._param_types import coerce_cli_path  # noqa: PLC0415  (loaded with typer already)

    if isinstance(value, str) and value and "\x00" not in value:
        value = Path(value)
    if not isinstance(value, Path):
        raise _NotPlain
    # typer's own checks of a path (exists, dir_okay, resolve_path ...), given the Path
    # pydantic would have made
    return coerce_cli_path(value, info, path_type=Path, param=param, ctx=ctx)


def _bool(value: Any, info: Any, param: Any, ctx: Any) -> Any:
    if isinstance(value, bool):
        return value
    raise _NotPlain


_KINDS = {str: _str, int: _int, float: _float, bool: _bool, Path: _path}


def _converter(annotation: Any, info: Any) -> Any:
    """The converter of a parameter's kind, or None (typer's own converter then)."""
    if info.parser is not None or getattr(info, "click_type", None) is not None:
        return None
    if annotation in (int, float) and getattr(info, "clamp", False):
        return None
    if annotation is Path and getattr(info, "path_type", None) is not None:
        return None
    return _KINDS.get(annotation)


class _Plain:
    """A converter with typer's `coerce` signature (typer._coercion.RuntimeParam)."""

    def __init__(self, item: Any, is_list: bool) -> None:
        self._item = item
        self._is_list = is_list
        self._typer: Any = None

    def coerce(self, value: Any, param: Any, ctx: Any) -> Any:
        is_multi = param.multiple or param.nargs == -1
        if value is None:
            return () if is_multi else None  # as typer's RuntimeParam.coerce
        if not (is_multi and isinstance(value, str)):  # typer's error for that one
            try:
                return self._convert(value, param, ctx)
            except Exception:  # _NotPlain, or an error: typer words it, on its own path
                pass
        return self._typers(param).coerce(value, param=param, ctx=ctx)

    def _convert(self, value: Any, param: Any, ctx: Any) -> Any:
        info = param.type_descriptor.parameter_info
        if not self._is_list:
            return self._item(value, info, param, ctx)
        items = value if isinstance(value, list | tuple) else [value]  # typer's parse_list
        return [self._item(v, info, param, ctx) for v in items]

    def _typers(self, param: Any) -> Any:
        if self._typer is None:
            from typer._coercion import build_runtime_param  # noqa: PLC0415  (imports pydantic: the unusual value only)

            self._typer = build_runtime_param(param.type_descriptor)
        return self._typer


def plain_converter(param: Any) -> _Plain | None:
    """`_Plain` for a typer parameter of a plain kind, else None."""
    descriptor = getattr(param, "type_descriptor", None)
    if descriptor is None or getattr(descriptor, "file_annotation", None) is not None:
        return None
    annotation, info = descriptor.annotation, descriptor.parameter_info
    if get_origin(annotation) is list:
        args = get_args(annotation)
        item = _converter(args[0], info) if len(args) == 1 else None
        return _Plain(item, is_list=True) if item is not None else None
    item = _converter(annotation, info)
    return _Plain(item, is_list=False) if item is not None else None


def install() -> None:
    """Typer's parameters get `_Plain` as their converter where their kind allows (typer
    itself builds its converter on first use, in `get_runtime_param`)."""
    from typer import core  # noqa: PLC0415  (loaded with typer already)

    cls = getattr(core, "_TyperParameter", None)
    typers = getattr(cls, "get_runtime_param", None)
    if cls is None or typers is None or getattr(typers, "plain_first", False):
        return

    def get_runtime_param(self: Any) -> Any:
        if getattr(self, "_runtime_param", None) is None:
            plain = plain_converter(self)
            if plain is not None:
                self._runtime_param = plain
        return typers(self)

    get_runtime_param.plain_first = True  # type: ignore[attr-defined]  # a function attribute: mypy does not model them
    cls.get_runtime_param = get_runtime_param
