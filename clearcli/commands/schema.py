"""`clear schema [NAME]`: the JSON Schemas (draft 2020-12) of the documents `clear` writes.

`clear schema NAME` prints the schema of documents whose ``schema`` key is ``clear.NAME``
(``NAME`` may carry the prefix) exactly as shipped in the package (clearcli/schemas/);
`clear schema` lists the names, and with --json prints one document, schema
``clear.schemas`` version 1: {"schemas": [{"name", "schema", "version", "title",
"description"}]}. An unknown NAME is one line naming the valid ones, exit 3.
"""

from __future__ import annotations

from typing import Annotated, Any

import typer

from clearcli.commands.common import print_json


def schema_cmd(
    name: Annotated[
        str | None,
        typer.Argument(
            help="A schema (plan, segmentation, batch, ...): print it. Without one: list them.", metavar="[NAME]"
        ),
    ] = None,
    json_out: Annotated[
        bool, typer.Option("--json", help="The list as a document (schema clear.schemas, version 1).")
    ] = False,
) -> None:
    """Print the JSON Schema (draft 2020-12) of a document `clear` writes with --json, or
    list them. A document's "schema" key names its schema: "clear.plan" is `clear schema
    plan`."""
    # the schemas and the printer that holds Ctrl-C until a line is whole: neither is
    # needed by `clear --help`
    from clearcli import schemas  # noqa: PLC0415  (~1 ms, but not for `clear --help`)
    from clearcli.provenance import print_line  # noqa: PLC0415  (~50 ms: the settings tree)

    if name is not None:
        print_line(schemas.text(name).rstrip("\n"))
        return
    rows = [_row(n, schemas.load(n)) for n in schemas.names()]
    if json_out:
        print_json("schemas", 1, {"schemas": rows}, None, "schema")
        return
    width = max(len(r["name"]) for r in rows)
    for r in rows:
        typer.echo(f"{r['name']:{width}s}  version {r['version']}  {r['description'].split(':', 1)[0]}")


def _row(name: str, schema: dict[str, Any]) -> dict[str, Any]:
    return {
        "name": name,
        "schema": schema["properties"]["schema"]["const"],
        "version": schema["properties"]["version"]["const"],
        "title": schema["title"],
        "description": schema["description"],
    }
