"""clearcli/interrupts.py: signals held during start-up and raised where they can be answered."""

from __future__ import annotations

import os
import signal
import time
from collections.abc import Iterator

import pytest

from clearcli import interrupts
from clearcli.errors import Terminated


@pytest.fixture(autouse=True)
def _own_handlers() -> Iterator[None]:
    """Leave pytest's handlers and the module's state as they were."""
    saved = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    state = interrupts._pending, interrupts._held, interrupts._terminated, interrupts._raised, interrupts._told
    yield
    signal.signal(signal.SIGINT, saved[0])
    signal.signal(signal.SIGTERM, saved[1])
    (interrupts._pending, interrupts._held, interrupts._terminated, interrupts._raised, interrupts._told) = state


def _send(signum: int) -> None:
    os.kill(os.getpid(), signum)
    time.sleep(0.05)  # Python runs the handler at the next instruction of the main thread


def test_a_held_sigterm_is_raised_at_release_as_terminated() -> None:
    interrupts.hold()
    _send(signal.SIGTERM)  # nothing raised while held
    with pytest.raises(Terminated):
        interrupts.release()
    assert interrupts.terminated() and interrupts.untold()
    interrupts.told()
    assert not interrupts.untold()


def test_a_held_ctrl_c_is_a_keyboard_interrupt_and_a_second_one_is_raised_at_once() -> None:
    interrupts.hold()
    _send(signal.SIGINT)
    with pytest.raises(KeyboardInterrupt) as caught:
        _send(signal.SIGINT)
    assert type(caught.value) is KeyboardInterrupt and not interrupts.terminated()


def test_release_without_a_signal_raises_nothing_and_signals_then_raise_where_they_arrive() -> None:
    interrupts.hold()
    interrupts.release()
    with pytest.raises(Terminated):
        _send(signal.SIGTERM)


def test_release_without_hold_leaves_a_host_programs_handlers_alone() -> None:
    seen: list[int] = []
    signal.signal(signal.SIGTERM, lambda signum, frame: seen.append(signum))
    interrupts._held = False
    interrupts.release()
    _send(signal.SIGTERM)
    assert seen == [signal.SIGTERM]


def test_deferred_holds_a_block_together_and_raises_after_it() -> None:
    # Python's own Ctrl-C handler outside the block, as in a command's process: in CI's
    # full run an earlier test in this process left SIGINT ignored (then nothing is to be
    # raised, rightly); the autouse fixture restores whatever was there after the test
    signal.signal(signal.SIGINT, signal.default_int_handler)
    done = []
    with pytest.raises(KeyboardInterrupt):
        with interrupts.deferred():
            _send(signal.SIGINT)
            done.append("the rest of the block")
    assert done == ["the rest of the block"]
    assert signal.getsignal(signal.SIGINT) is not interrupts._on_signal_held  # handlers restored


_EXIT_SIGNAL = """
import atexit, os, signal, sys
# the signal lands while the interpreter exits, after the command is over
atexit.register(lambda: os.kill(os.getpid(), signal.{sig}))
sys.argv = ["clear", "info", {frame!r}, {frame!r}, "--json", "--jobs", "1"]
from clearcli.cli import main
main()
"""


@pytest.mark.parametrize("sig, code", [("SIGTERM", 143), ("SIGINT", 130)])
def test_a_signal_while_the_interpreter_exits_is_its_code_without_a_traceback(sig: str, code: int) -> None:
    """Issue 34, fault 9: a SIGTERM at the end of a batch raised `Terminated` in the
    interpreter's teardown, where nothing catches it ("Exception ignored in atexit
    callback" and a traceback). After the command, a signal ends the process at once."""
    import subprocess
    import sys
    from pathlib import Path

    frame = str(Path(__file__).resolve().parents[1] / "fixtures" / "box_on_box.pcd")
    res = subprocess.run(
        [sys.executable, "-c", _EXIT_SIGNAL.format(sig=sig, frame=frame)], capture_output=True, text=True, timeout=120
    )
    assert res.returncode == code, res.stderr
    assert res.stderr == "", res.stderr  # not a word: the batch's lines were out already
    lines = res.stdout.splitlines()
    assert len(lines) == 3 and '"type":"summary"' in lines[-1]  # the output whole, flushed before the exit


def test_a_worker_ignores_a_second_sigterm_while_it_cleans_up() -> None:
    """A busy worker gets SIGTERM twice (the pool's terminate() and its parent-death
    signal): the first exits through the writers' clean-up, the second must not raise
    again inside that clean-up."""
    from clearcli.batch import pool

    with pytest.raises(SystemExit) as exc:
        pool._stop_worker(signal.SIGTERM, None)
    assert exc.value.code == 143 and signal.getsignal(signal.SIGTERM) == signal.SIG_IGN
