"""The JSON Schemas (draft 2020-12) of every document and line `clear` writes with --json.

One file per schema, ``<name>.json`` beside this module, shipped as package data
(pyproject's [tool.setuptools.package-data]) and read with importlib.resources, so a wheel
installed outside the checkout has them too. A document's ``schema`` key names its file
(``clear.plan`` -> ``plan.json``) and its ``version`` is the file's ``version`` const: a
schema rises with its document (clearcli/provenance.py `envelope`). The test suite
validates every document it produces against these (tests/helpers/schemas.py), so they
cannot drift from the code.
"""

from __future__ import annotations

import json
from importlib import resources
from typing import Any

from clearcli.errors import SettingsError

__all__ = ["load", "names", "text"]

PREFIX = "clear."


def names() -> list[str]:
    """The schema names, sorted (``plan``, ``segmentation``, ``evaluate.frame``, ...)."""
    folder = resources.files(__name__)
    return sorted(p.name.removesuffix(".json") for p in folder.iterdir() if p.name.endswith(".json"))


def text(name: str) -> str:
    """The schema ``name`` as shipped (JSON text). ``name`` may carry the ``clear.``
    prefix a document's ``schema`` key has. An unknown name is a SettingsError (exit 3)
    naming the valid ones."""
    bare = name.removeprefix(PREFIX)
    known = names()
    if bare not in known:
        raise SettingsError(f"no schema {name!r}; the schemas are: {', '.join(known)}")
    return resources.files(__name__).joinpath(f"{bare}.json").read_text(encoding="utf-8")


def load(name: str) -> dict[str, Any]:
    """The schema ``name`` as a dict (see `text`)."""
    schema: dict[str, Any] = json.loads(text(name))
    return schema
