"""Tests of clearcli/perception/clock.py."""

from __future__ import annotations

import time

import pytest

from clearcli.perception.clock import Clock


def test_a_clock_adds_up_each_named_step() -> None:
    clock = Clock(("a", "b", "never"))
    assert clock.timings == {"a": 0.0, "b": 0.0, "never": 0.0}  # in order, 0 until timed
    with clock("b"):
        time.sleep(0.01)
    with clock("a"):
        time.sleep(0.01)
    with clock("b"):  # a name timed twice adds up
        time.sleep(0.01)
    with pytest.raises(ValueError), clock("late"):  # a step that fails is timed too
        raise ValueError
    assert list(clock.timings) == ["a", "b", "never", "late"]
    assert clock.timings["a"] >= 0.01 and clock.timings["b"] >= 0.02 and clock.timings["never"] == 0.0
    assert clock.timings["late"] >= 0.0
    clock.total("a+b", ("a", "b", "missing"))
    assert clock.timings["a+b"] == clock.timings["a"] + clock.timings["b"]
    assert clock.elapsed() >= clock.timings["a"] + clock.timings["b"]
