"""The public surface of clearcli.api: every name in ``__all__`` with its signature, and
for a class its public methods, properties and fields. tests/api/surface.json records
it per package version; `python tests/api/surface.py record` records the current one
under the current version (a new version keeps the old versions' records)."""

from __future__ import annotations

import dataclasses
import inspect
import json
import sys
from pathlib import Path
from typing import Any

RECORD = Path(__file__).with_name("surface.json")


def surface() -> dict[str, Any]:
    from clearcli import api

    out: dict[str, Any] = {}
    for name in sorted(api.__all__):
        obj = getattr(api, name)
        if inspect.isclass(obj) and issubclass(obj, BaseException):
            out[name] = f"exception({', '.join(b.__name__ for b in obj.__bases__)})"
        elif inspect.isclass(obj):
            members: dict[str, str] = {}
            if dataclasses.is_dataclass(obj):
                for f in dataclasses.fields(obj):
                    if not f.name.startswith("_"):
                        members[f.name] = f"field: {f.type}"
            for attr, value in vars(obj).items():
                if attr.startswith("_") and attr not in ("__init__", "__iter__", "__next__"):
                    continue
                if isinstance(value, (classmethod, staticmethod)):
                    members[attr] = f"{type(value).__name__}{inspect.signature(value.__func__)}"
                elif isinstance(value, property):
                    members[attr] = "property"
                elif inspect.isfunction(value):
                    members[attr] = f"def{inspect.signature(value)}"
            for base in obj.__mro__[1:]:
                if base.__module__ == api.__name__ and not base.__name__.startswith("_"):
                    members["(base)"] = base.__name__
                    break
            out[name] = members
        else:
            out[name] = f"def{inspect.signature(obj)}"
    return out


def version() -> str:
    from clearcli import __version__

    return __version__


if __name__ == "__main__":
    if sys.argv[1:] != ["record"]:
        sys.exit("usage: python tests/api/surface.py record")
    records = json.loads(RECORD.read_text(encoding="utf-8")) if RECORD.exists() else {}
    records[version()] = surface()
    RECORD.write_text(json.dumps(records, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    print(f"recorded the API of clear {version()} in {RECORD}")
