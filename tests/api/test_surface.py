"""The API's public surface (names and signatures, tests/api/surface.py) changes only
with the package's version: the record of the current version must match it."""

from __future__ import annotations

import json

from clearcli import api
from tests.api.surface import RECORD, surface, version


def test_the_surface_changes_only_with_the_version() -> None:
    records = json.loads(RECORD.read_text(encoding="utf-8"))
    assert version() in records, (
        f"no recorded API surface for version {version()}: run `python tests/api/surface.py record` "
        "(older versions' records stay)"
    )
    assert surface() == records[version()], (
        f"clearcli.api changed but the version is still {version()}: raise the version in pyproject.toml "
        "and clearcli/__init__.py, then `python tests/api/surface.py record`"
    )


def test_everything_public_is_listed_and_the_rest_private() -> None:
    public = {n for n, v in vars(api).items() if not n.startswith("_") and getattr(v, "__module__", "") == api.__name__}
    assert public - {"PathLike"} <= set(api.__all__)  # PathLike: a type alias, in the signatures
    assert all(hasattr(api, n) for n in api.__all__)
    assert surface().keys() == set(api.__all__)
