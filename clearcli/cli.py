"""The `clear` command line: parse, call one function, print. Nothing else.

Subcommands live in `clearcli/commands/<name>.py`, each a plain function registered here;
heavy libraries are imported inside those functions so that `clear --help` is fast.
"""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path
from typing import Annotated, Optional

import typer

from clearcli import __version__
from clearcli.errors import EXIT_CODES, EXIT_INTERNAL, ClearError

_EXIT_HELP = "\n\n".join(f"{code}: {text}" for code, text in EXIT_CODES.items())

app = typer.Typer(
    name="clear",
    help=(
        "Plan how a robot arm clears a cluttered table, from recorded point clouds.\n\n"
        "Results go to stdout (--json: one stable, versioned schema); logs and progress "
        "to stderr.\n\nExit codes:\n\n" + _EXIT_HELP
    ),
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"clear {__version__}")
        raise typer.Exit(0)


@app.callback()
def _root(
    version: Annotated[
        Optional[bool],
        typer.Option("--version", callback=_version, is_eager=True, help="Print the version and exit."),
    ] = None,
) -> None:
    pass


def _register() -> None:
    from clearcli.commands import registry

    for name, func, kwargs in registry.COMMANDS:
        app.command(name, **kwargs)(func)
    for name, sub in registry.GROUPS:
        app.add_typer(sub, name=name)


_register()


def _run_terminal_clear() -> None:
    """Inside a venv `clear` shadows the terminal's `clear`: do what that one does."""
    own_dir = Path(sys.argv[0]).resolve().parent
    search = os.pathsep.join(
        p for p in os.environ.get("PATH", "").split(os.pathsep) if p and Path(p).resolve() != own_dir
    )
    system_clear = shutil.which("clear", path=search)
    if system_clear:
        os.execv(system_clear, [system_clear])
    sys.stdout.write("\x1b[H\x1b[2J\x1b[3J")
    sys.stdout.flush()


def main() -> None:
    """Entry point of `clear` and `clearcli`: maps ClearError to its exit code."""
    if (
        len(sys.argv) == 1
        and Path(sys.argv[0]).name == "clear"
        and sys.stdout.isatty()
        and sys.stdin.isatty()
    ):
        _run_terminal_clear()
        return
    try:
        app(prog_name=Path(sys.argv[0]).name or "clear")
    except ClearError as exc:
        sys.stderr.write(f"clear: error: {exc}\n")
        sys.exit(exc.exit_code)
    except KeyboardInterrupt:
        sys.stderr.write("clear: interrupted\n")
        sys.exit(130)
    except Exception as exc:  # a bug: one line unless the user asks for the traceback
        if os.environ.get("CLEAR_DEBUG"):
            raise
        sys.stderr.write(
            f"clear: internal error: {type(exc).__name__}: {exc} "
            "(rerun with CLEAR_DEBUG=1 for the traceback and report it)\n"
        )
        sys.exit(EXIT_INTERNAL)


if __name__ == "__main__":
    main()
