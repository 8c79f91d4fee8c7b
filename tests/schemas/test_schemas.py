"""The published schemas (clearcli/schemas/): each a valid draft 2020-12 schema tied to its
document's name and version, each met by a real document here, and each able to fail."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import pytest
from helpers import FIXTURES, run_clear
from helpers.schemas import FAILURES, SchemaMismatch, validate_document, validator
from jsonschema import Draft202012Validator

from clearcli import provenance, schemas

NAMES = schemas.names()


def code_versions() -> dict[str, int]:
    """Each document's (name, version) where the code keeps it: a schema file must match."""
    from clearcli.batch.run import BATCH_SCHEMA_VERSION
    from clearcli.perception.payload import SCHEMA as SEG
    from clearcli.perception.payload import VERSION as SEG_V
    from clearcli.tasks import evaluate, info, plan, predicates, replay, robots, simulate

    found = {SEG: SEG_V, "batch": BATCH_SCHEMA_VERSION, "evaluate.segmentation": 1, "schemas": 1}
    for task in (evaluate, info, plan, predicates, replay, robots, simulate):
        found[task.SCHEMA] = task.VERSION
    return found


def test_every_document_kind_has_a_schema_and_no_schema_is_stray() -> None:
    assert set(NAMES) == set(code_versions())


@pytest.mark.parametrize("name", NAMES)
def test_each_schema_is_draft_2020_12_and_names_its_document(name: str) -> None:
    schema = schemas.load(name)
    Draft202012Validator.check_schema(schema)
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    version = code_versions()[name]
    assert schema["properties"]["schema"] == {"const": f"clear.{name}"}
    assert schema["properties"]["version"] == {"const": version}
    assert schema["title"] == f"clear.{name} version {version}"
    assert schema["$id"] == f"urn:clear:schema:clear.{name}:{version}"
    assert {"schema", "version", "clear"} <= set(schema["required"])
    # closed: a typo'd key fails (info leaves other input formats their own keys)
    assert schema.get("additionalProperties") is False or schema.get("unevaluatedProperties") is False or name == "info"


def test_the_loader_names_the_valid_ones_for_an_unknown_name() -> None:
    from clearcli.errors import EXIT_INPUT, SettingsError

    with pytest.raises(SettingsError) as caught:
        schemas.load("plans")
    assert caught.value.exit_code == EXIT_INPUT
    assert "plan, predicates" in str(caught.value)
    assert schemas.load("clear.plan") == schemas.load("plan")


# ----------------------------------------------------------------------------- real documents


def _docs(stdout: str) -> list[dict[str, Any]]:
    return [json.loads(line) for line in stdout.splitlines() if line.startswith("{")]


@pytest.fixture(scope="module")
def documents(tmp_path_factory: pytest.TempPathFactory) -> dict[str, list[dict[str, Any]]]:
    """One run of each command on the shipped fixtures; the documents by schema (a batch
    line's document under its own name too). run_clear validates each as it comes."""
    tmp = tmp_path_factory.mktemp("docs")
    box, two = FIXTURES / "box_on_box.pcd", FIXTURES / "two_touching_boxes.pcd"
    runs = [
        ("segment", "--json", box),
        ("predicates", "--json", box),
        ("plan", "--json", box),
        ("info", "--json", box),
        ("info", "--json", FIXTURES / "session.mcap"),
        ("robots", "--json"),
        ("robots", "panda", "--json"),
        ("replay", "--json", FIXTURES / "session.mcap"),
        ("plan", "--json", box, two, tmp / "missing.pcd"),  # documents, an error, a summary
        ("evaluate", "dataset", "--json", box, two),
        ("segment", box, "-o", tmp / "labels.pcd"),
        ("evaluate", "segmentation", "--json", tmp / "labels.pcd", box),
        ("simulate", tmp / "sim.mcap", "--scene", "box_on_box", "--max-actions", "2", "--json"),
        ("schema", "--json"),
    ]
    found: dict[str, list[dict[str, Any]]] = {}
    for args in runs:
        done = run_clear(*args, timeout=600)
        assert done.returncode in (0, 5, 10, 11), f"clear {args}: {done.returncode} {done.stderr[-500:]}"
        for doc in _docs(done.stdout):
            found.setdefault(doc["schema"].removeprefix("clear."), []).append(doc)
            if "document" in doc:
                inner = doc["document"]
                found.setdefault(inner["schema"].removeprefix("clear."), []).append(inner)
    return found


@pytest.mark.parametrize("name", NAMES)
def test_each_schema_validates_a_document_clear_wrote(name: str, documents: dict[str, list[dict[str, Any]]]) -> None:
    docs = documents.get(name, [])
    assert docs, f"no clear.{name} document was made"
    for doc in docs:
        validate_document(doc, f"clear.{name}")


def test_both_kinds_of_line_of_replay_and_batch_are_met(documents: dict[str, list[dict[str, Any]]]) -> None:
    assert {d["type"] for d in documents["replay"]} == {"frame", "summary"}
    batch = documents["batch"]
    assert {d["type"] for d in batch} == {"frame", "summary"}
    assert any("error" in d for d in batch) and any("document" in d for d in batch)
    assert any("evaluation" in d for d in batch if d["type"] == "summary")
    assert {"profiles", "profile"} <= {k for d in documents["robots"] for k in d}
    assert {d["format"] for d in documents["info"]} == {"pcd", "mcap"}


# ----------------------------------------------------------------------------- able to fail


def _refused(name: str, doc: dict[str, Any]) -> bool:
    return not validator(name).is_valid(doc)


@pytest.mark.parametrize("name", NAMES)
def test_a_broken_document_fails(name: str, documents: dict[str, list[dict[str, Any]]]) -> None:
    doc = documents[name][0]
    assert not _refused(name, doc)
    payload = [k for k in doc if k not in ("schema", "version", "clear")]
    required = set(schemas.load(name)["required"])
    for key in ["clear", *payload]:
        broken = copy.deepcopy(doc)
        del broken[key]
        if key in required or name in ("replay", "batch", "robots", "info"):  # a variant's keys
            assert _refused(name, broken), f"clear.{name} without {key!r} passed"
    for key in payload:
        wrong = copy.deepcopy(doc)
        wrong[key] = {"a wrong": "type"} if not isinstance(doc[key], dict) else "a wrong type"
        assert _refused(name, wrong), f"clear.{name} with {key!r} of a wrong type passed"
    typo = copy.deepcopy(doc)
    typo[payload[-1] + "_"] = typo.pop(payload[-1])  # a typo'd key
    assert _refused(name, typo)
    assert _refused(name, {**doc, "version": doc["version"] + 1})
    assert _refused(name, {**doc, "clear": {**doc["clear"], "source": "somewhere"}})


def test_nested_breaks_fail(documents: dict[str, list[dict[str, Any]]]) -> None:
    plan = copy.deepcopy(documents["plan"][0])
    assert plan["steps"], "the fixture's plan has steps"
    del plan["steps"][0]["kind"]
    assert _refused("plan", plan)
    plan = copy.deepcopy(documents["plan"][0])
    plan["status"] = "finished"  # not one of the closed set
    assert _refused("plan", plan)
    plan = copy.deepcopy(documents["plan"][0])
    plan["T_base_camera"] = plan["T_base_camera"][:3]  # a 3x4 "pose"
    assert _refused("plan", plan)
    seg = copy.deepcopy(documents["segmentation"][0])
    seg["objects"][0]["centroid"] = [0.0, 0.0]
    assert _refused("segmentation", seg)
    frame = copy.deepcopy(next(d for d in documents["replay"] if d["type"] == "frame"))
    frame["frames_read"] = 3  # a summary's key on a frame line
    assert _refused("replay", frame)
    line = copy.deepcopy(next(d for d in documents["batch"] if "error" in d))
    line["document"] = documents["plan"][0]  # both an error and a document
    assert _refused("batch", line)


def test_a_batch_lines_document_is_checked_under_its_own_schema(documents: dict[str, list[dict[str, Any]]]) -> None:
    line = copy.deepcopy(next(d for d in documents["batch"] if "document" in d))
    assert not _refused("batch", line)
    del line["document"]["steps"]  # the batch schema alone would not see it
    with pytest.raises(SchemaMismatch, match="clear.plan"):
        validate_document(line, "a batch line")


def test_an_unknown_or_missing_schema_name_is_a_failure() -> None:
    with pytest.raises(SchemaMismatch, match="no schema in clearcli/schemas"):
        validate_document({"schema": "clear.nonsense", "version": 1}, "made up")
    with pytest.raises(SchemaMismatch, match="no clear schema"):
        validate_document({"version": 1, "objects": []}, "made up")
    with pytest.raises(SchemaMismatch, match="not an object"):
        validate_document([1, 2], "made up")


def test_the_in_process_hook_sees_what_print_line_writes(capsys: pytest.CaptureFixture[str]) -> None:
    before = len(FAILURES)
    provenance.print_line(json.dumps({"schema": "clear.plan", "version": 5}))
    try:
        assert len(FAILURES) == before + 1 and "clear.plan" in FAILURES[-1]
    finally:
        del FAILURES[before:]  # this test's own, on purpose
    assert capsys.readouterr().out.startswith('{"schema"')  # still written


def test_the_schemas_load_from_a_zipped_package(tmp_path: Path) -> None:
    """importlib.resources, not paths beside the source: a zip stands in for a wheel
    that is not unpacked in a folder."""
    import subprocess
    import sys
    import zipfile

    import clearcli

    root = Path(clearcli.__file__).parent
    archive = tmp_path / "clear.zip"
    with zipfile.ZipFile(archive, "w") as z:
        for rel in ["__init__.py", "errors.py", "schemas/__init__.py", *(f"schemas/{n}.json" for n in NAMES)]:
            z.write(root / rel, f"clearcli/{rel}")
    code = "from clearcli import schemas; print(schemas.__file__); print(len(schemas.names()), schemas.load('plan')['title'])"
    done = subprocess.run(
        [sys.executable, "-I", "-c", f"import sys; sys.path.insert(0, {str(archive)!r}); {code}"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    where, listing = done.stdout.splitlines()
    assert str(archive) in where
    assert listing == f"{len(NAMES)} clear.plan version 5"
