"""Shared test helpers: where the read-only reference data lives, and how to skip without it."""

from __future__ import annotations

import functools
import importlib.util
import os
import subprocess
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

REPO = Path(__file__).resolve().parents[2]
SHARED = Path(os.environ.get("CLEAR_SHARED", REPO.parent / "shared")).resolve()
SHARED_DATA = SHARED / "data"
FIXTURES = REPO / "fixtures"


@functools.cache
def load_script(relative: str) -> ModuleType:
    """A script of the repository that is no package (``benchmarks/foreign.py``,
    ``training/join.py``) as a module, loaded once by its path."""
    path = REPO / relative
    spec = importlib.util.spec_from_file_location(path.stem + "_script", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def shared_path(relative: str) -> Path:
    """Path under ../shared/data; skips the test when absent, fails under CLEAR_REQUIRE_SHARED=1."""
    path = SHARED_DATA / relative
    if not path.exists():
        message = f"shared data {path} is not here (../shared/data beside the checkout)"
        if os.environ.get("CLEAR_REQUIRE_SHARED") == "1":
            pytest.fail(message + " and CLEAR_REQUIRE_SHARED=1")
        pytest.skip(message)
    return path


def run_clear(
    *args: object, timeout: float = 600, cwd: Path | None = None, env: dict[str, str] | None = None
) -> subprocess.CompletedProcess[str]:
    """The installed `clear`, as a user or a script runs it (its own process; ``env``
    its whole environment, when given)."""
    exe = Path(sys.executable).with_name("clear")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "clearcli.cli"]
    return subprocess.run(
        [*cmd, *map(str, args)], capture_output=True, text=True, timeout=timeout, cwd=cwd or REPO, env=env
    )


def run_clear_as_user(*args: object, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    """`run_clear` as a user runs it, without CLEAR_DEBUG (under which an internal error
    prints its traceback on purpose): no traceback, and a documented exit code."""
    from clearcli.errors import EXIT_CODES

    env = {k: v for k, v in os.environ.items() if k != "CLEAR_DEBUG"}
    res = run_clear(*args, timeout=timeout, env=env)
    assert "Traceback" not in res.stderr, res.stderr
    assert res.returncode in EXIT_CODES, (res.returncode, res.stderr)
    return res


def start_clear(*args: object, **popen: Any) -> subprocess.Popen[Any]:
    """`python -m clearcli.cli ARGS` started and not waited for (to signal or kill it on
    the way): stdout and stderr piped unless ``popen`` (`subprocess.Popen`'s own keywords)
    says otherwise."""
    streams = {"stdout": subprocess.PIPE, "stderr": subprocess.PIPE}
    return subprocess.Popen([sys.executable, "-m", "clearcli.cli", *map(str, args)], **{**streams, **popen})
