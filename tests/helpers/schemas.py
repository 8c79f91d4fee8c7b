"""Every JSON document the suite sees `clear` write is validated against its published
schema (clearcli/schemas/, draft 2020-12, the `jsonschema` library), so a schema cannot
drift from the code.

Where documents are caught (`install`, at session start):
- `clear` as its own process (`helpers.run_clear`, the harness's `run_subprocess`, each
  module's own `subprocess.run([clear, ...])`): `subprocess.Popen.communicate`, which
  `subprocess.run` calls, is wrapped: when the command is `clear` (the script, or
  `python -m clearcli.cli`), every line of its stdout that is a JSON object;
- in this process (`clearcli.cli.main` under CliRunner, capsys or the harness's
  `run_inprocess`): every line `clearcli.provenance.print_line` writes, the one way a
  document reaches stdout.

A line that is a JSON object must name its schema: ``"schema": "clear.<name>"`` with a
shipped ``<name>.json`` (validated; a batch line's ``document`` too, under its own
schema), or be a schema itself (``"$schema"``: `clear schema NAME`, checked as a draft
2020-12 schema). Anything else, or a document its schema refuses, fails the test: never
a silent pass. The session's count is printed in the terminal summary
(`pytest_terminal_summary`, imported by tests/conftest.py).
"""

from __future__ import annotations

import functools
import json
import os
import subprocess
import sys
from collections import Counter
from pathlib import Path
from typing import Any

import pytest
from jsonschema import Draft202012Validator

from clearcli import provenance, schemas

VALIDATED: Counter[str] = Counter()  # documents validated this session, by schema
SCHEMAS_CHECKED: Counter[str] = Counter()  # `clear schema NAME` outputs checked as schemas
FAILURES: list[str] = []  # what the in-process hook found, raised by the test's teardown


class SchemaMismatch(AssertionError):
    """A document `clear` wrote that its schema refuses (or that names none)."""


@functools.cache
def validator(name: str) -> Draft202012Validator:
    schema = schemas.load(name)
    Draft202012Validator.check_schema(schema)
    return Draft202012Validator(schema)


def validate_document(doc: Any, where: str = "", count: bool = False) -> None:
    """Validate one parsed document against the schema its ``schema`` key names (and a
    batch line's ``document`` against its own); SchemaMismatch when it does not match,
    names no schema or an unknown one. ``count``: a document clear wrote (the hooks),
    counted in the session's figure; a test's own checks are not."""
    if not isinstance(doc, dict):
        raise SchemaMismatch(f"{where}: a JSON line of clear's that is not an object: {str(doc)[:200]}")
    if "$schema" in doc and "schema" not in doc:  # `clear schema NAME`: a schema itself
        Draft202012Validator.check_schema(doc)
        if count:
            SCHEMAS_CHECKED[str(doc.get("title"))] += 1
        return
    name = doc.get("schema")
    if not isinstance(name, str) or not name.startswith(schemas.PREFIX):
        raise SchemaMismatch(f"{where}: a JSON document with no clear schema (schema={name!r}): {str(doc)[:200]}")
    bare = name.removeprefix(schemas.PREFIX)
    if bare not in schemas.names():
        raise SchemaMismatch(f"{where}: {name} has no schema in clearcli/schemas/ ({', '.join(schemas.names())})")
    errors = sorted(validator(bare).iter_errors(doc), key=lambda e: list(e.absolute_path))
    if errors:
        shown = "; ".join(f"at /{'/'.join(map(str, e.absolute_path))}: {e.message[:300]}" for e in errors[:5])
        raise SchemaMismatch(f"{where}: a {name} document its schema refuses ({len(errors)} errors): {shown}")
    if count:
        VALIDATED[name] += 1
    nested = doc.get("document")
    if bare == "batch" and nested is not None:
        validate_document(nested, f"{where} (its document)", count)


def validate_output(stdout: str, where: str = "") -> int:
    """Validate each line of ``stdout`` that is a JSON object; the number validated.
    Lines that are not JSON (a table, a TOML tree, a PDDL file) are the test's business."""
    n = 0
    for line in stdout.splitlines():
        text = line.strip()
        if not text.startswith("{"):
            continue
        try:
            doc = json.loads(text)
        except ValueError:
            continue
        validate_document(doc, where, count=True)
        n += 1
    return n


def _validated_line(original: Any) -> Any:
    @functools.wraps(original)
    def print_line(text: str) -> None:
        try:
            validate_output(text, "in-process clear")
        except SchemaMismatch as exc:  # raised at the test's end: clear's own handlers would hide it
            FAILURES.append(str(exc))
        original(text)

    print_line._clear_schema_hook = True  # type: ignore[attr-defined]
    return print_line


def is_clear(args: Any) -> bool:
    """Whether a subprocess's argv runs `clear` (a shell string is left alone: its
    pipes may cut the output)."""
    if isinstance(args, (str, bytes)) or not args:
        return False
    argv = [os.fsdecode(a) if isinstance(a, (bytes, os.PathLike)) else str(a) for a in args]
    if Path(argv[0]).name in ("clear", "clearcli"):
        return True
    return any(a == "-m" and b in ("clearcli.cli", "clearcli") for a, b in zip(argv, argv[1:]))


def _validated_communicate(original: Any) -> Any:
    @functools.wraps(original)
    def communicate(self: subprocess.Popen[Any], *args: Any, **kwargs: Any) -> Any:
        out, err = original(self, *args, **kwargs)
        if out and is_clear(self.args):
            text = out.decode("utf-8", "replace") if isinstance(out, bytes) else out
            validate_output(text, "clear " + " ".join(map(str, self.args[1:])))
        return out, err

    communicate._clear_schema_hook = True  # type: ignore[attr-defined]
    return communicate


def install() -> None:
    """Wrap `subprocess.Popen.communicate` (`clear` in its own process) and
    `clearcli.provenance.print_line` with the modules that imported it by name before
    (clearcli/batch/run.py; `clear` in this process), so every document is checked."""
    if not getattr(subprocess.Popen.communicate, "_clear_schema_hook", False):
        subprocess.Popen.communicate = _validated_communicate(subprocess.Popen.communicate)  # type: ignore[method-assign]
    original = provenance.print_line
    if getattr(original, "_clear_schema_hook", False):
        return
    hooked = _validated_line(original)
    provenance.print_line = hooked  # type: ignore[assignment]
    for name, module in list(sys.modules.items()):
        if name.startswith("clearcli.") and getattr(module, "print_line", None) is original:
            module.print_line = hooked  # type: ignore[attr-defined]


install()


@pytest.fixture(autouse=True)
def _documents_match_their_schemas():  # type: ignore[no-untyped-def]
    """Fail the test whose in-process `clear` wrote a document its schema refuses."""
    start = len(FAILURES)
    yield
    found = FAILURES[start:]
    if found:
        pytest.fail("clear wrote documents their schemas refuse:\n" + "\n".join(found[:5]), pytrace=False)


def pytest_terminal_summary(terminalreporter: Any) -> None:
    total = sum(VALIDATED.values())
    kinds = ", ".join(f"{k} {v}" for k, v in sorted(VALIDATED.items()))
    terminalreporter.write_line(
        f"schemas: the suite validated {total} documents clear wrote against clearcli/schemas/"
        + (f" ({kinds})" if kinds else "")
        + (f"; {sum(SCHEMAS_CHECKED.values())} printed schemas checked" if SCHEMAS_CHECKED else "")
    )
