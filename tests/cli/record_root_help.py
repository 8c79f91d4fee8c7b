"""Re-record clearcli/commands/root_help.py, the text `clear --help` prints without
building the app (clearcli/cli.py), from the app itself:

    .venv/bin/python tests/cli/record_root_help.py

Run it after changing what the root help shows (a command's docstring, the app's help,
the exit codes); tests/cli/test_startup.py fails until then.
"""

from __future__ import annotations

from pathlib import Path

from clearcli.cli import render_root_help
from clearcli.commands import root_help

TARGET = Path(root_help.__file__)


def module_text(text: str) -> str:
    """root_help.py's source holding ``text`` (what click prints, its final newline included)."""
    if '"""' in text or "\\" in text or not text.endswith("\n"):
        raise SystemExit("record_root_help.py: the help text needs escaping this script does not do")
    head, _, _ = TARGET.read_text().partition('TEXT = """\\\n')
    return head + 'TEXT = """\\\n' + text + '"""\n'


def main() -> None:
    new = module_text(render_root_help())
    if new == TARGET.read_text():
        print(f"{TARGET}: unchanged")
        return
    TARGET.write_text(new)
    print(f"{TARGET}: recorded")


if __name__ == "__main__":
    main()
