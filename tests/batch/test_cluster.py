"""Tests of clearcli/batch/cluster.py."""

from __future__ import annotations

import os

import pytest
from helpers.batch import FRAMES, clear, comparable, lines_of


def _need_ray() -> None:
    try:
        import ray  # noqa: F401
    except ImportError:
        if os.environ.get("CLEAR_REQUIRE_SHARED") == "1":
            pytest.fail("Ray is not installed, and CI must run this test: pip install 'clear-table[ray]'")
        pytest.skip("Ray is not installed (pip install 'clear-table[ray]')")


def test_local_ray_run_equals_the_pool() -> None:
    _need_ray()
    pool = clear("plan", *FRAMES[:3], "--json", "--jobs", "2")
    ray = clear("plan", *FRAMES[:3], "--json", "--ray")
    assert pool.returncode == ray.returncode == 0, ray.stderr
    rows_p, _ = lines_of(pool.stdout)
    rows_r, summary = lines_of(ray.stdout)
    assert summary["backend"] == "ray (local)" and summary["ray_init_s"] is not None
    assert [comparable(r["document"]) for r in rows_r] == [comparable(r["document"]) for r in rows_p]


def test_ray_address_that_cannot_be_reached() -> None:
    _need_ray()
    res = clear("plan", *FRAMES[:2], "--ray", "127.0.0.1:1", timeout=120)
    assert res.returncode == 3 and "127.0.0.1:1" in res.stderr and "Traceback" not in res.stderr
    assert res.stdout == ""  # before any work


@pytest.mark.parametrize(
    ("address", "says"),
    [
        ("127.0.0.1:99999999999999999999", "the port must be 1 to 65535"),  # once an OverflowError
        ("127.0.0.1:0", "the port must be 1 to 65535"),
        ("127.0.0.1:\u00b2", "expected HOST:PORT"),  # "²": a digit to isdigit, not to int()
        ("127.0.0.1", "expected HOST:PORT"),
    ],
)
def test_a_bad_ray_address_is_one_line(address: str, says: str) -> None:
    _need_ray()
    res = clear("plan", *FRAMES[:1], "--ray", address, timeout=120)
    assert res.returncode == 3 and says in res.stderr and "Traceback" not in res.stderr, res.stderr
    assert res.stderr.count("\n") == 1 and res.stdout == ""
