"""`clear schema [NAME] [--json]` on the command line."""

from __future__ import annotations

import json

from helpers import run_clear
from jsonschema import Draft202012Validator

from clearcli import schemas
from clearcli.errors import EXIT_INPUT


def test_a_name_prints_the_shipped_schema() -> None:
    for name in ("plan", "clear.batch", "evaluate.frame"):
        done = run_clear("schema", name, timeout=60)
        assert done.returncode == 0, done.stderr
        printed = json.loads(done.stdout)
        assert printed == schemas.load(name)
        Draft202012Validator.check_schema(printed)
        assert done.stdout.count("\n") > 10  # as shipped: indented, for people too


def test_no_name_lists_them_and_json_is_a_document() -> None:
    done = run_clear("schema", timeout=60)
    assert done.returncode == 0, done.stderr
    listed = [line.split()[0] for line in done.stdout.splitlines()]
    assert listed == schemas.names()
    assert "plan" in listed and "segmentation" in listed
    done = run_clear("schema", "--json", timeout=60)
    doc = json.loads(done.stdout)
    assert doc["schema"] == "clear.schemas" and doc["version"] == 1
    assert [r["name"] for r in doc["schemas"]] == schemas.names()
    plan = next(r for r in doc["schemas"] if r["name"] == "plan")
    assert (plan["schema"], plan["version"]) == ("clear.plan", 5)


def test_an_unknown_name_is_one_line_naming_the_valid_ones() -> None:
    done = run_clear("schema", "plans", timeout=60)
    assert done.returncode == EXIT_INPUT == 3
    assert done.stdout == ""
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr
    assert "'plans'" in lines[0] and "plan, predicates, replay" in lines[0]
