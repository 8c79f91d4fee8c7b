"""MkDocs hook: the settings page's tables, generated from the settings tree when the
site is built (every section, key, default and accepted range, as `clear settings
--ranges` prints them), so the page can never disagree with the code."""

from __future__ import annotations

import dataclasses
from typing import Any

from clearcli.settings.fields import range_of
from clearcli.settings.tree import SECTIONS, Settings

MARKER = "<!-- settings-tables -->"


def _value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"' if value else '""'
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    return repr(value)


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def settings_tables() -> str:
    """Markdown: one table per section of the tree, in `clear settings`'s order."""
    defaults = Settings()
    out: list[str] = []
    for name, cls in SECTIONS.items():
        doc = (cls.__doc__ or "").strip()
        if doc.startswith(f"{cls.__name__}("):  # no docstring: the dataclass's signature
            doc = ""
        out += [f"### [{name}]", ""]
        if doc:
            out += [_cell(doc.split("\n\n")[0]), ""]
        out += ["| key | default | accepted |", "|---|---|---|"]
        section = getattr(defaults, name)
        for f in dataclasses.fields(cls):
            value = getattr(section, f.name)
            accepted = "true or false" if isinstance(value, bool) else range_of(cls, f.name).describe()
            out.append(f"| `{f.name}` | `{_cell(_value(value))}` | {_cell(accepted)} |")
        out.append("")
    return "\n".join(out)


def on_page_markdown(markdown: str, page: Any, **kwargs: Any) -> str:
    if MARKER in markdown:
        return markdown.replace(MARKER, settings_tables())
    return markdown
