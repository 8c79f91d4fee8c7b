"""One root exception for everything a user can get wrong, each kind with its exit code.

The CLI prints ``str(error)`` as one line on stderr and exits with ``error.exit_code``;
the codes are documented in ``clear --help`` and the README. Messages say what was wrong
(naming the file) and what to do about it.
"""

from __future__ import annotations

from typing import Any

# Exit codes, documented in the README and in `clear --help`.
EXIT_OK = 0  # for `plan`: the plan removes every object (an empty table included)
EXIT_INTERNAL = 1  # a bug in clear: please report it
EXIT_USAGE = 2  # Typer/Click: unknown option, missing argument
EXIT_INPUT = 3  # input file missing, empty, corrupt, not a point cloud, bad settings file
EXIT_SCENE = 4  # the frame holds no usable table (no plane, seen from below, all NaN)
EXIT_NO_PLAN = 5  # nothing can be done: no object can be removed (the reasons are printed)
EXIT_PLANNER = 6  # the planner failed: time-out, crash, binary missing
EXIT_NOT_YET = 7  # subcommand not implemented yet
EXIT_OUTPUT = 8  # an output could not be written (exists without --force, not writable)
EXIT_PARTIAL = 9  # a log was read only in part (truncated/corrupt after complete frames)
EXIT_PARTIAL_PLAN = 10  # the plan removes some objects; the others are left, with reasons
EXIT_BATCH_FAILED = 11  # a batch ran, and some of its frames failed (their codes in their lines)
EXIT_MEMORY = 12  # out of memory: an allocation failed, or the memory limit is below what clear needs
EXIT_INTERRUPTED = 130  # Ctrl-C (128 + SIGINT, as shells report it)
EXIT_BROKEN_PIPE = 141  # stdout closed by its reader (`clear ... | head`): 128 + SIGPIPE
EXIT_TERMINATED = 143  # SIGTERM (what Slurm, Kubernetes and `timeout` send): 128 + 15

EXIT_CODES: dict[int, str] = {
    EXIT_OK: "success (plan: every object removed, an empty table included)",
    EXIT_INTERNAL: "internal error (a bug in clear; rerun with CLEAR_DEBUG=1 and report it)",
    EXIT_USAGE: "usage error (unknown option, missing argument)",
    EXIT_INPUT: "bad input: file missing, empty, corrupt, not a point cloud, bad settings",
    EXIT_SCENE: "no usable table in the frame (no plane, seen from below, no finite points)",
    EXIT_NO_PLAN: "no plan: no object can be removed (reasons printed; plan --json still prints its document)",
    EXIT_PLANNER: "planner failure: time-out, crash or Fast Downward missing",
    EXIT_NOT_YET: "subcommand not implemented yet",
    EXIT_OUTPUT: "output not written: exists (use --force) or not writable",
    EXIT_PARTIAL: "log read only in part: truncated or corrupt after the frames reported",
    EXIT_PARTIAL_PLAN: "partial plan: it removes some objects; the others are left, each with its reason",
    EXIT_BATCH_FAILED: "batch (several frames): some frames failed; each one's code and message are in its line",
    EXIT_MEMORY: "out of memory: an allocation failed, or the memory limit (ulimit -v / -d) is below what clear needs",
    EXIT_INTERRUPTED: "interrupted (Ctrl-C); a batch still prints the summary of what finished",
    EXIT_BROKEN_PIPE: "stdout was closed by its reader (e.g. `| head`): ended quietly",
    EXIT_TERMINATED: "terminated (SIGTERM); a batch still prints the summary of what finished",
}


class ClearError(Exception):
    """Root of every error a user can cause; carries the process exit code."""

    exit_code: int = EXIT_INTERNAL

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.message = message

    def __str__(self) -> str:
        return self.message


class InputError(ClearError):
    """A file cannot be read as what it should be."""

    exit_code = EXIT_INPUT


class SettingsError(InputError):
    """A settings file or flag value is invalid."""


class SceneError(ClearError):
    """The frame was read but holds no usable table scene."""

    exit_code = EXIT_SCENE


class NoPlanError(ClearError):
    """Planning finished and proved the table cannot be cleared."""

    exit_code = EXIT_NO_PLAN
    # the plan stage attaches what it found (a `clearcli.planning.types.Plan`, which this
    # bottom layer does not import); None when nothing is attached
    plan: Any = None


class PlannerError(ClearError):
    """The planner itself failed (time-out, crash, missing binary)."""

    exit_code = EXIT_PLANNER


class NotYetError(ClearError):
    exit_code = EXIT_NOT_YET


class OutputError(ClearError):
    """An output file could not be written; nothing was changed. ``errno`` says why when
    the system did (ENOSPC: the disk is full, and a batch stops starting frames)."""

    exit_code = EXIT_OUTPUT

    def __init__(self, message: str, errno_: int | None = None) -> None:
        super().__init__(message)
        self.errno = errno_


class MemoryLimitError(ClearError):
    """Not enough memory: the process's address-space or data limit is below what clear
    needs to start, or an allocation failed (Python's MemoryError)."""

    exit_code = EXIT_MEMORY


class PartialLogError(ClearError):
    """A log ended early or was corrupt after some complete frames."""

    exit_code = EXIT_PARTIAL


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the program is (the CLI installs the handler): it stops work
    the way Ctrl-C does (writes clean up, a batch prints its summary), exit 143."""
