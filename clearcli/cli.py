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
import importlib.machinery
import importlib.util
import os
import shutil
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Annotated, Any

from clearcli import interrupts
from clearcli.commands import registry, root_help
from clearcli.errors import (
    EXIT_BROKEN_PIPE,
    EXIT_CODES,
    EXIT_INTERNAL,
    EXIT_INTERRUPTED,
    EXIT_OUTPUT,
    EXIT_TERMINATED,
    ClearError,
    Terminated,
)

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


# Numeric libraries' thread pools: one thread each in a single `clear` call. NumPy's
# OpenBLAS starts a worker per core when it loads, and on clear's small products the
# workers spin for nothing: the same wall time for more CPU (issue 39: mOSD test48's
# segment 0.26 s of CPU for 0.15 s of wall with them, 0.15 s without). The batch's
# workers (clearcli/batch/pool.py) set the same and inherit these. The libraries read
# them when they load, so they are set before anything imports NumPy; a value the user
# set is kept.
SINGLE_THREADED = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def _single_threaded_numerics() -> None:
    for var in SINGLE_THREADED:
        os.environ.setdefault(var, "1")


# NumPy subpackages clear never uses: its test and build tooling, and polynomials.
# SciPy's array-API layer (scipy._lib.array_api_compat.numpy, imported by every SciPy
# subpackage through scipy._lib._util) copies NumPy's namespace with `from numpy import *`
# and a getattr of every name, and NumPy's lazy attributes then import them all:
# numpy.f2py (the Fortran wrapper generator) and numpy.testing (unittest, difflib) were
# 57 ms of a cold `clear plan` on a quiet machine (issue 39), numpy.polynomial some 6 ms
# more (numpy.ma is left alone: SciPy's functions touch it on their first call). Here
# importing one of them only creates the module; its code runs at the first use of one
# of its attributes (the standard library's importlib.util.LazyLoader), so code that does
# use them gets them whole. scipy.spatial imports its rotations (scipy.spatial.transform,
# ~20 ms on a quiet machine) with `from . import transform`; clear uses its trees and
# hulls only. SciPy's docstring parser (scipy._lib._docscrape, imported by its array-API
# layer) imports pydoc at its top and uses it only inside functions clear does not reach:
# pydoc was 30-40 ms of a cold `clear plan` here (issue 39).
DEFERRED_MODULES = frozenset({"numpy.f2py", "numpy.testing", "numpy.polynomial", "scipy.spatial.transform", "pydoc"})


class _DocstringKept:
    """Stands for numpydoc's FunctionDoc in SciPy's xp_capabilities decorator: the
    function's docstring as it is, no section parsed, the note appended to nothing.

    That decorator (scipy._lib._array_api, SciPy >= 1.15) wraps the public functions of
    scipy.linalg, special, ndimage, spatial ... as they are defined, and parses each
    docstring to render it again with a note on array-API support: 229 docstrings, 0.16
    of the 0.40 s of CPU the SciPy subpackages of a `clear plan` took to import (issue 39,
    minima of 6 runs on a loaded machine). No `clear` command shows a SciPy docstring;
    the decorator's other work (its table of capabilities) is left as it is, and so is
    every other use of FunctionDoc in SciPy. The decorator does
    ``str(FunctionDoc(f)).split("\\n", 1)[1].lstrip(" \\n")`` (the first line is the
    signature): so str() is a blank first line, then the docstring."""

    def __init__(self, func: Any) -> None:
        self._doc = getattr(func, "__doc__", None) or ""

    def __getitem__(self, section: str) -> list[str]:
        return []  # a section to append to; what is appended is dropped

    def __setitem__(self, section: str, value: Any) -> None:
        pass

    def __str__(self) -> str:
        return "\n" + self._doc


def _keep_scipy_docstrings(module: ModuleType) -> None:
    if hasattr(module, "xp_capabilities") and hasattr(module, "FunctionDoc"):
        setattr(module, "FunctionDoc", _DocstringKept)  # noqa: B010  (a module mypy does not know)


# Modules patched right after their own code ran, before anything uses them.
PATCHED_MODULES: dict[str, Callable[[ModuleType], None]] = {"scipy._lib._array_api": _keep_scipy_docstrings}


class _PatchedAfterExec:
    """A module's own loader, then ``patch`` on the module it ran; anything else asked of
    the loader (get_source, resource readers ...) goes to its own."""

    def __init__(self, loader: Any, patch: Callable[[ModuleType], None]) -> None:
        self._loader = loader
        self._patch = patch

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType | None:
        module: ModuleType | None = self._loader.create_module(spec)
        return module

    def exec_module(self, module: ModuleType) -> None:
        self._loader.exec_module(module)
        self._patch(module)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._loader, name)


class _LighterImports:
    """Finds `DEFERRED_MODULES` and `PATCHED_MODULES` as the path finder does, with a
    lazy loader or a patch after its code around their own loader. (A meta-path finder
    by its method alone: importlib.abc costs ~10 ms to import.)"""

    def find_spec(self, fullname: str, path: Any = None, target: Any = None) -> importlib.machinery.ModuleSpec | None:
        if fullname not in DEFERRED_MODULES and fullname not in PATCHED_MODULES:
            return None
        spec = importlib.machinery.PathFinder.find_spec(fullname, path)
        if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
            return spec
        if fullname in DEFERRED_MODULES:
            spec.loader = importlib.util.LazyLoader(spec.loader)
        else:
            # a Loader by its methods (importlib.abc costs ~10 ms to import)
            spec.loader = _PatchedAfterExec(spec.loader, PATCHED_MODULES[fullname])  # type: ignore[assignment]
        return spec


def _lighten_imports() -> None:
    if not any(isinstance(finder, _LighterImports) for finder in sys.meta_path):
        sys.meta_path.insert(0, _LighterImports())


def main() -> None:
    """Entry point of `clear` and `clearcli`: maps ClearError to its exit code."""
    _single_threaded_numerics()  # first: before any import of NumPy
    _lighten_imports()  # before anything imports NumPy or SciPy
    if len(sys.argv) == 1 and Path(sys.argv[0]).name == "clear" and sys.stdout.isatty() and sys.stdin.isatty():
        _run_terminal_clear()
        return
    interrupts.hold()  # until the command can answer a signal properly (clearcli/interrupts.py)
    try:
        _main()
    finally:
        interrupts.finish()  # a signal during the interpreter's exit: 130/143 at once, no traceback


def _main() -> None:
    try:
        try:
            if "--ray" in sys.argv:
                # imports typer (~85 ms): after interrupts.hold(), as in make_app
                from clearcli.commands.options import ray_argv  # noqa: PLC0415  (typer, after hold())

                sys.argv = ray_argv(sys.argv)
            prog_name = Path(sys.argv[0]).name or "clear"
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
        sys.stderr.write(f"clear: error: {exc}\n")
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
    except Exception as exc:  # a bug: one line unless the user asks for the traceback
        _internal(exc)


def _internal(exc: BaseException) -> None:
    if os.environ.get("CLEAR_DEBUG"):
        raise exc
    sys.stderr.write(
        f"clear: internal error: {type(exc).__name__}: {exc} "
        "(rerun with CLEAR_DEBUG=1 for the traceback and report it)\n"
    )
    sys.exit(EXIT_INTERNAL)


if __name__ == "__main__":
    main()
