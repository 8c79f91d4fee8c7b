"""`clear` does not run NumPy's test and build tooling that SciPy's array-API layer imports
(clearcli/cli.py DEFERRED_MODULES), and code that uses them still gets them."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from helpers import FIXTURES, REPO, run_clear
from helpers.batch import hooked_env

from clearcli.cli import DEFERRED_MODULES

# In the child before clear's main: at exit, which deferred modules ran their code.
_HOOK = """
import atexit, importlib.util, json, os, sys

def _report():
    state = {}
    for name in DEFERRED:
        module = sys.modules.get(name)
        # type(), not module.__class__: any attribute access would load a lazy module
        state[name] = "absent" if module is None else "deferred" if type(module) is importlib.util._LazyModule else "loaded"
    state["scipy"] = "scipy" in sys.modules
    with open(os.environ["CLEAR_TEST_REPORT"], "w") as out:
        json.dump(state, out)

atexit.register(_report)
""".replace("DEFERRED", repr(sorted(DEFERRED_MODULES)))


def test_segment_leaves_numpy_tooling_unrun(tmp_path: Path) -> None:
    report = tmp_path / "report.json"
    env = hooked_env(tmp_path, _HOOK)
    env["CLEAR_TEST_REPORT"] = str(report)
    res = run_clear("segment", FIXTURES / "isolated_box.pcd", "--json", timeout=120, env=env)
    assert res.returncode == 0, res.stderr
    assert json.loads(res.stdout)["schema"] == "clear.segmentation"
    state = json.loads(report.read_text())
    assert state.pop("scipy") is True, "segment did not import SciPy: nothing was checked"
    assert state == dict.fromkeys(DEFERRED_MODULES, "deferred")


def test_deferred_modules_load_whole_on_use() -> None:
    code = """
import importlib.util, sys
from clearcli.cli import _defer_numpy_tooling
_defer_numpy_tooling()
import scipy.sparse
assert type(sys.modules["numpy.testing"]) is importlib.util._LazyModule
import numpy as np
from numpy.testing import assert_allclose
assert_allclose(np.polynomial.Polynomial([1.0, 2.0])(3.0), 7.0)
assert type(sys.modules["numpy.testing"]) is not importlib.util._LazyModule
assert "unittest" in sys.modules
print("ok")
"""
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "ok"
