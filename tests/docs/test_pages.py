"""The documentation: the README is the front page (at most 200 lines, the two commands
first), the site's navigation names every page and every page is in it, the settings
page's tables cover every key of the tree, and the measurements moved from the README
are on their page."""

from __future__ import annotations

import dataclasses
import importlib.util
import re

from tests.helpers import REPO

DOCS = REPO / "docs"
TWO_COMMANDS = "./setup.sh && .venv/bin/clear plan fixtures/clutter10.pcd\n.venv/bin/python -m pytest -q tests\n"


def test_the_readme_is_a_front_page_with_the_two_commands_first() -> None:
    text = (REPO / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 200
    first_block = text.split("```sh\n", 1)[1].split("```", 1)[0]
    assert first_block == TWO_COMMANDS
    assert text.index("```sh") < text.index("\n## ")  # before any section
    for link in re.findall(r"\]\((docs/[^)#]+)", text):
        assert (REPO / link).is_file(), link


def test_every_page_is_in_the_navigation_and_every_entry_is_a_page() -> None:
    config = (REPO / "mkdocs.yml").read_text(encoding="utf-8")
    nav = set(re.findall(r":\s+([\w-]+\.md)\s*$", config, flags=re.M))
    pages = {p.name for p in DOCS.glob("*.md")}
    assert nav == pages
    for page in ("getting-started.md", "inputs.md", "outputs.md", "exit-codes.md", "batches.md", "settings.md"):
        assert page in pages
    for page in ("robots.md", "grasp-kinds.md", "segmentation.md", "api.md", "architecture.md", "measurements.md"):
        assert page in pages


def test_the_settings_tables_cover_every_key_of_the_tree() -> None:
    spec = importlib.util.spec_from_file_location("settings_page", DOCS / "hooks" / "settings_page.py")
    assert spec is not None and spec.loader is not None
    hook = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hook)
    from clearcli.settings.tree import SECTIONS, Settings

    page = (DOCS / "settings.md").read_text(encoding="utf-8")
    built = hook.on_page_markdown(page, page=None)
    assert hook.MARKER not in built
    defaults = Settings()
    for name, cls in SECTIONS.items():
        assert f"### [{name}]" in built
        for f in dataclasses.fields(cls):
            row = next((x for x in built.splitlines() if x.startswith(f"| `{f.name}` |")), None)
            assert row is not None, f"[{name}] {f.name}"
    # a default as the tree has it, and a range as the checks word it
    assert "| `voxel_m` | `0.005` | >= 0.001 and <= 0.05 |" in built
    assert defaults.segment.voxel_m == 0.005


def test_the_measurements_moved_with_their_benchmarks() -> None:
    text = (DOCS / "measurements.md").read_text(encoding="utf-8")
    for figure in (
        "| **all 50** | 50 | **0.990** |",  # segmentation on mOSD
        "Measured (`benchmarks/suction.py`, 26 Nov 2026, commit b94d235)",
        "`clear plan --jobs 2` 7.4 frames/s",
        "3.34 frames/s end to end",
    ):
        assert figure in text
    assert text.count("*Recorded in the README") >= 6  # each block dated by its commit


def test_the_api_page_shows_the_example_the_tests_run() -> None:
    text = (DOCS / "api.md").read_text(encoding="utf-8")
    assert '--8<-- "docs/examples/first_plan.py"' in text and "::: clearcli.api" in text
