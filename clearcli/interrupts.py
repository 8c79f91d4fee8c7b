"""Ctrl-C and SIGTERM at any moment, start-up included.

Python raises KeyboardInterrupt wherever the program is when SIGINT arrives: during
start-up that is inside an import (a traceback, or "Exception ignored" noise) or before
a batch has anything to summarise. So `clear` *holds* both signals from its first line
until the command knows what it is doing: a signal that arrives meanwhile is remembered,
and *released* (raised) at the first point that can answer it properly, i.e. inside a
batch's run (which then prints the summary of the frames that finished, none) or on
entry to a single-frame command. A second signal while held is raised at once, so a
start-up that hangs still stops on the second Ctrl-C.

SIGTERM raises `Terminated` (a KeyboardInterrupt: every clean-up that Ctrl-C runs, runs),
and the CLI maps it to exit 143.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from clearcli.errors import Terminated

_pending: int | None = None  # the signal received while held, if any
_held = False
_terminated = False  # SIGTERM was received (the CLI's exit code is 143, not 130)
_raised = False  # a signal was raised as an exception
_told = False  # someone (a batch's summary) already told the user on stderr


def _raise_for(signum: int) -> None:
    global _terminated, _raised
    _raised = True
    if signum == signal.SIGTERM:
        _terminated = True
        raise Terminated()
    raise KeyboardInterrupt()


def _on_signal_held(signum: int, frame: Any) -> None:
    global _pending
    if _pending is not None:  # the second one: the user means it
        _raise_for(signum)
    _pending = signum


def _on_signal(signum: int, frame: Any) -> None:
    _raise_for(signum)


def hold() -> None:
    """From now on remember SIGINT and SIGTERM instead of raising them (see the module)."""
    global _held
    _held = True
    signal.signal(signal.SIGINT, _on_signal_held)
    signal.signal(signal.SIGTERM, _on_signal_held)


def release() -> None:
    """Raise SIGINT/SIGTERM where they arrive from now on, and at once if one came while
    held. Without `hold` first (clear embedded in another program) it does nothing, so a
    host's own handlers are left alone."""
    global _held, _pending
    if not _held:
        return
    _held = False
    signal.signal(signal.SIGINT, _on_signal)
    signal.signal(signal.SIGTERM, _on_signal)
    if _pending is not None:
        signum, _pending = _pending, None
        _raise_for(signum)


def _flush_streams() -> bool:
    """Flush stdout and stderr (both, whatever the first does); whether both went out."""
    whole = True
    for stream in (sys.stdout, sys.stderr):
        try:
            if stream is not None:
                stream.flush()
        except BaseException:  # a closed or full pipe
            whole = False
    return whole


def _exit_now(signum: int, frame: Any) -> None:
    # the command's output is out; flush what is left of it, then go without unwinding
    # (a stream that cannot be flushed: the exit code below still tells)
    _flush_streams()
    os._exit(128 + signum)


def end_process(code: int) -> None:
    """End the process with ``code`` now that its work is over (a `clear` command, a
    batch worker with no more frames): the exit handlers run, stdout and stderr are
    flushed, and the interpreter's own teardown of every module (NumPy's, SciPy's,
    Pinocchio's: 5-30 ms of a cold call, ~40 ms a batch waited for each worker, issue 39)
    is skipped. What `clear` writes is written whole and closed before its work ends
    (files.py), so nothing waits for the teardown. Returns, and the usual exit follows,
    where the teardown may matter: a thread other than daemons still running (the usual
    exit waits for it), or a stream that cannot be flushed (the usual exit reports it)."""
    import atexit  # noqa: PLC0415  (loaded already: the interpreter imports it)

    main_thread = threading.main_thread()
    if any(t is not main_thread and not t.daemon and t.is_alive() for t in threading.enumerate()):
        return
    atexit._run_exitfuncs()  # it clears them: the usual exit, if it follows, runs none again
    if _flush_streams():
        os._exit(code & 0xFF)


def finish() -> None:
    """The command is over: a SIGINT/SIGTERM from now on ends the process at once with
    130/143, raising nothing. Without this, a signal during the interpreter's own exit
    (atexit callbacks, thread joins, module teardown) raised `Terminated` where nothing
    can catch it: "Exception ignored in ..." and a traceback on stderr."""
    signal.signal(signal.SIGINT, _exit_now)
    signal.signal(signal.SIGTERM, _exit_now)


def terminated() -> bool:
    """Whether SIGTERM (not Ctrl-C) stopped the program."""
    return _terminated


def told() -> None:
    """Record that the stop was already reported on stderr (a batch's last line)."""
    global _told
    _told = True


def untold() -> bool:
    """Whether a signal stopped the program and nobody has said so yet."""
    return _raised and not _told


@contextmanager
def deferred() -> Iterator[None]:
    """Hold SIGINT/SIGTERM for the ``with`` block (something that must not be cut in
    half, such as starting a worker process) and raise one that came, after it. Blocking
    the signal with the OS mask does not do: with several threads (BLAS's), the signal
    goes to a thread that does not block it, and Python raises it in the main one."""
    if threading.current_thread() is not threading.main_thread():
        yield  # signals are only ever raised in the main thread
        return
    global _pending
    old_int, old_term = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    outer_pending = _pending
    _pending = None
    signal.signal(signal.SIGINT, _on_signal_held)
    signal.signal(signal.SIGTERM, _on_signal_held)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old_int)
        signal.signal(signal.SIGTERM, old_term)
        came, _pending = _pending, outer_pending
        if came is not None:
            handler = old_term if came == signal.SIGTERM else old_int
            if callable(handler):
                handler(came, None)
            elif handler == signal.SIG_DFL:
                signal.raise_signal(came)
