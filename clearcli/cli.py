"""The `clear` command line: parse, call one function, print. Nothing else.

Subcommands live in `clearcli/commands/<name>.py`, each a plain function registered here
(clearcli/commands/registry.py lists them; `main` imports and registers only the one it
runs); heavy libraries are imported inside those functions so that `clear --help` is fast.

This module's top-level imports run before `main` holds Ctrl-C/SIGTERM
(clearcli/interrupts.py), so they are kept to a few light ones: typer and the command
modules (which import typer) are imported after the hold, inside the functions below.
"""

from __future__ import annotations

import functools
import os
import shutil
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

from clearcli import interrupts, startup
from clearcli.commands import registry, root_help
from clearcli.errors import (
    EXIT_BROKEN_PIPE,
    EXIT_CODES,
    EXIT_INTERNAL,
    EXIT_INTERRUPTED,
    EXIT_MEMORY,
    EXIT_OUTPUT,
    EXIT_TERMINATED,
    ClearError,
    Terminated,
)
from clearcli.startup import DEFERRED_MODULES as DEFERRED_MODULES
from clearcli.startup import SINGLE_THREADED as SINGLE_THREADED

if TYPE_CHECKING:
    import typer

_EXIT_HELP = "\n\n".join(f"{code}: {text}" for code, text in EXIT_CODES.items())


def make_app(only: str | None = None) -> typer.Typer:
    """The `clear` app with every subcommand registered, or only the one named ``only``.

    `main` registers only the subcommand it runs: importing the other command modules
    and building their click commands is start-up time spent on nothing. `app` (this
    module's attribute, built on first use) has them all, for tests and embedding.
    """
    # typer is imported here, not at the top: `main` holds Ctrl-C/SIGTERM first
    # (clearcli/interrupts.py), so a signal during its ~85 ms of imports is held
    import typer  # noqa: PLC0415  (~85 ms, after interrupts.hold())

    from clearcli.commands import coercion  # noqa: PLC0415  (with typer)

    coercion.install()  # options converted without pydantic where typer's result is certain

    def _version(value: bool) -> None:
        if value:
            from clearcli.provenance import version_line  # noqa: PLC0415  (--version only)

            typer.echo(version_line())
            raise typer.Exit(0)

    def _root(version: bool | None = None) -> None:
        pass

    # real objects, not this module's postponed strings: typer resolves them in the
    # module's globals, where typer is not (see above)
    _root.__annotations__ = {
        "version": Annotated[
            bool | None,
            typer.Option("--version", callback=_version, is_eager=True, help="Print the version and exit."),
        ],
        "return": None,
    }

    app = typer.Typer(
        name="clear",
        help=(
            "Plan how a robot arm clears a cluttered table, from recorded point clouds and RGB-D images.\n\n"
            "Results go to stdout (--json: one stable, versioned schema); logs and progress "
            "to stderr.\n\nExit codes:\n\n" + _EXIT_HELP
        ),
        no_args_is_help=True,
        add_completion=True,  # --install-completion, --show-completion (bash, zsh, fish, PowerShell)
        pretty_exceptions_enable=False,
        rich_markup_mode=None,
    )
    app.callback()(_root)
    for name, target, kwargs in registry.COMMANDS:
        if only is None or name == only:
            app.command(name, **kwargs)(_releasing(registry.load(target)))
    for name, target in registry.GROUPS:
        if only is None or name == only:
            group = registry.load(target)
            for info in group.registered_commands:
                info.callback = _releasing(info.callback)
            app.add_typer(group, name=name)
    return app


def _releasing(fn: Any) -> Any:
    """``fn``, releasing held signals on entry (clearcli/interrupts.py), unless it does so
    itself at a better point (a command with batch options: inside the batch's run, so a
    signal at start-up still gets a batch's summary)."""
    if fn is None or getattr(fn, "releases_interrupts", False) or getattr(fn, "_clear_releasing", False):
        return fn

    @functools.wraps(fn)
    def command(*args: Any, **kwargs: Any) -> Any:
        interrupts.release()
        return fn(*args, **kwargs)

    command._clear_releasing = True  # type: ignore[attr-defined]  # a function attribute: mypy does not model them
    return command


_full_app: typer.Typer | None = None


def __getattr__(name: str) -> typer.Typer:
    if name == "app":
        global _full_app
        if _full_app is None:
            _full_app = make_app()
        return _full_app
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def render_root_help(prog_name: str = root_help.PROG_NAME) -> str:
    """What the app prints for `clear --help` on a terminal of 80 columns or more (click
    makes its help 78 columns wide there): the text clearcli/commands/root_help.py
    records (tests/cli/record_root_help.py)."""
    import typer.main  # noqa: PLC0415  (~85 ms; recording and its test only)

    command = typer.main.get_command(make_app())
    with command.make_context(prog_name, [], resilient_parsing=True) as ctx:
        ctx.terminal_width = root_help.MIN_COLUMNS - 2
        return command.get_help(ctx) + "\n"  # click's echo adds the newline


def _recorded_root_help(args: list[str], prog_name: str) -> str | None:
    """`clear --help`'s text as recorded (clearcli/commands/root_help.py) where click would
    print exactly that, else None (the app prints it): the root's --help alone, under the
    name it was recorded with, no shell completion asked (click's check, on the same name),
    and a terminal as wide as click's help at its widest (shutil's size, as click takes it:
    a pipe counts as 80 columns unless $COLUMNS says otherwise)."""
    if args != ["--help"] or prog_name != root_help.PROG_NAME:
        return None
    if f"_{prog_name}_COMPLETE".replace("-", "_").upper() in os.environ:
        return None
    if shutil.get_terminal_size().columns < root_help.MIN_COLUMNS:
        return None
    return root_help.TEXT


def _command_named(args: list[str]) -> str | None:
    """The subcommand ``args`` (argv without the program) runs when it is the first word,
    else None: every command is registered then, for `--help`'s listing or click's error.
    (The root's only options, --help and --version, print and exit.)"""
    return args[0] if args and args[0] in registry.NAMES else None


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


def _stdout_pacified() -> bool:
    """Whether click (typer's) met a closed stdout and wrapped it to keep quiet."""
    return type(sys.stdout).__name__ in ("PacifyFlushWrapper", "_PacifyFlushWrapper")


def _quiet_stdout() -> None:
    """Point stdout at /dev/null, so that the interpreter's last flush does not fail too."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass


# What a process does before it imports NumPy (clearcli/startup.py; a batch's workers do
# the same); the names are kept here too, where the tests and benchmarks/startup.py read them.
_single_threaded_numerics = startup.single_threaded_numerics
_lighten_imports = startup.lighten_imports
# The frame commands whose start-up runs without the garbage collector until they read
# their frame (clearcli/startup.py `pause_collection`).
COLLECTION_PAUSED = frozenset({"segment", "predicates", "plan"})


def main() -> None:
    """Entry point of `clear` and `clearcli`: maps ClearError to its exit code."""
    from clearcli.limits import too_little_memory  # noqa: PLC0415  (first: before NumPy can hang)

    reason = too_little_memory()
    if reason is not None:
        sys.stderr.write(f"clear: error: {reason}\n")
        sys.exit(EXIT_MEMORY)
    _single_threaded_numerics()  # first: before any import of NumPy
    _lighten_imports()  # before anything imports NumPy or SciPy
    if _command_named(sys.argv[1:]) in COLLECTION_PAUSED:
        startup.pause_collection()  # until the frame is read (clearcli/startup.py)
    if len(sys.argv) == 1 and Path(sys.argv[0]).name == "clear" and sys.stdout.isatty() and sys.stdin.isatty():
        _run_terminal_clear()
        return
    # a new `clear` process (`clear`, `clearcli`, `python -m clearcli.cli`), not a test or a
    # program calling main with the libraries loaded, which may go on after it
    fresh = "numpy" not in sys.modules and _is_entry_point()
    interrupts.hold()  # until the command can answer a signal properly (clearcli/interrupts.py)
    code: int | None = None  # the exit code, when the command ended with one
    try:
        try:
            _main()
            code = 0
        except SystemExit as exc:
            code = 0 if exc.code is None else exc.code if isinstance(exc.code, int) else None
            raise
    finally:
        startup.resume_collection(freeze=False)  # no frame read (--help, an error): as it was
        interrupts.finish()  # a signal during the interpreter's exit: 130/143 at once, no traceback
        if fresh and code is not None:
            interrupts.end_process(code)  # at once: no teardown of every module


def _is_entry_point() -> bool:
    """Whether the program is `clear` itself: its console scripts, ``-m clearcli`` or
    ``-m clearcli.cli``."""
    top = sys.modules.get("__main__")
    spec = getattr(top, "__spec__", None)
    if spec is not None:
        return spec.name in ("clearcli.cli", "clearcli.__main__")
    return Path(getattr(top, "__file__", None) or "").stem in ("clear", "clearcli")


def _main() -> None:
    try:
        try:
            if "--ray" in sys.argv:
                # imports typer (~85 ms): after interrupts.hold(), as in make_app
                from clearcli.commands.options import ray_argv  # noqa: PLC0415  (typer, after hold())

                sys.argv = ray_argv(sys.argv)
            # `python -m clearcli` shows its argv[0] as .../__main__.py: named as the script
            prog_name = Path(sys.argv[0]).name
            prog_name = "clear" if prog_name in ("", "__main__.py") else prog_name
            recorded = _recorded_root_help(sys.argv[1:], prog_name)
            if recorded is not None:
                # as click's echo: written and flushed (a closed stdout shows here)
                sys.stdout.write(recorded)
                sys.stdout.flush()
            else:
                app = make_app(_command_named(sys.argv[1:]))
                app(prog_name=prog_name)
        finally:
            if not _stdout_pacified():
                sys.stdout.flush()  # a full disk shows here, not at the interpreter's exit
            interrupts.release()  # a signal no command released (--help, a usage error): exit 130/143
    except SystemExit as exc:
        # Typer turns Ctrl-C (and SIGTERM, raised as Terminated) into exit 130, and a
        # closed stdout into exit 1 after quieting it: say which really happened.
        if _stdout_pacified():
            _quiet_stdout()
            sys.exit(EXIT_BROKEN_PIPE)
        if exc.code == EXIT_INTERRUPTED and interrupts.untold():
            terminated = interrupts.terminated()
            sys.stderr.write("clear: terminated\n" if terminated else "clear: interrupted\n")
            sys.exit(EXIT_TERMINATED if terminated else EXIT_INTERRUPTED)
        raise
    except ClearError as exc:
        sys.stderr.write(f"clear: error: {_one_line(str(exc))}\n")
        sys.exit(exc.exit_code)
    except Terminated:
        sys.stderr.write("clear: terminated\n")
        sys.exit(EXIT_TERMINATED)
    except KeyboardInterrupt:
        sys.stderr.write("clear: interrupted\n")
        sys.exit(EXIT_INTERRUPTED)
    except BrokenPipeError:
        _quiet_stdout()
        sys.exit(EXIT_BROKEN_PIPE)
    except OSError as exc:
        # loaded by every command by now; at the top it would add ~10 ms (tempfile, random)
        # before interrupts.hold()
        from clearcli.files import WRITE_ERRNOS  # noqa: PLC0415  (~10 ms before hold())

        if exc.errno not in WRITE_ERRNOS:
            _internal(exc)
        _quiet_stdout()
        sys.stderr.write(f"clear: error: cannot write the results to stdout ({exc.strerror or exc})\n")
        sys.exit(EXIT_OUTPUT)
    except MemoryError:
        sys.stderr.write(
            "clear: error: out of memory: an allocation failed (a frame larger than the memory the process may "
            "use: free memory, raise its limit, or use a smaller frame)\n"
        )
        sys.exit(EXIT_MEMORY)
    except Exception as exc:  # a bug: one line unless the user asks for the traceback
        _internal(exc)


def _one_line(message: str) -> str:
    """``message`` on one line: a file name the user gave may hold a newline or another
    control character, which a script reading stderr line by line would split on."""
    if message.isprintable():
        return message
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in message)


def _internal(exc: BaseException) -> None:
    if os.environ.get("CLEAR_DEBUG"):
        raise exc
    sys.stderr.write(
        f"clear: internal error: {type(exc).__name__}: {_one_line(str(exc))} "
        "(rerun with CLEAR_DEBUG=1 for the traceback and report it)\n"
    )
    sys.exit(EXIT_INTERNAL)


if __name__ == "__main__":
    main()
