"""clearcli/interrupts.py: signals held during start-up and raised where they can be answered."""

from __future__ import annotations

import os
import signal
import time
from typing import Iterator

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
    done = []
    with pytest.raises(KeyboardInterrupt):
        with interrupts.deferred():
            _send(signal.SIGINT)
            done.append("the rest of the block")
    assert done == ["the rest of the block"]
    assert signal.getsignal(signal.SIGINT) is not interrupts._on_signal_held  # handlers restored
