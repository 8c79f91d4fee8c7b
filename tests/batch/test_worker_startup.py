"""A batch's workers start as a single call does (clearcli/startup.py): one BLAS thread,
NumPy's and SciPy's unused modules and SciPy's subpackages' code deferred, SciPy's
array-API layer not imported. A
worker is a fresh interpreter that never runs the CLI's main (issue 39: without this a
worker's first frame paid ~1 s of SciPy imports on a loaded machine)."""

from __future__ import annotations

import json
from pathlib import Path

from helpers import FIXTURES
from helpers.batch import clear, hooked_env, lines_of

from clearcli.startup import DEFERRED_CODE_MODULES, DEFERRED_MODULES, DEFERRED_PACKAGES, SINGLE_THREADED

# In every child: at exit, a report named by its pid (a worker: a multiprocessing child
# running the pool's worker module).
_HOOK = """
import atexit, importlib.util, json, multiprocessing, os, sys

def _report():
    state = {"worker": multiprocessing.parent_process() is not None and "clearcli.batch.pool" in sys.modules, "scipy": "scipy" in sys.modules}
    for name in DEFERRED:
        module = sys.modules.get(name)
        # type(), not module.__class__: any attribute access would load a lazy module
        lazy = type(module) is importlib.util._LazyModule or type(module).__name__ == "_DeferredPackage"
        state[name] = "absent" if module is None else "deferred" if lazy else "loaded"
    state["scipy_array_api"] = "scipy._lib._array_api" in sys.modules
    state["env"] = {var: os.environ.get(var) for var in THREADS}
    with open(os.path.join(os.environ["CLEAR_TEST_REPORTS"], f"{os.getpid()}.json"), "w") as out:
        json.dump(state, out)

atexit.register(_report)
""".replace("DEFERRED", repr(sorted(DEFERRED_MODULES | DEFERRED_PACKAGES | DEFERRED_CODE_MODULES))).replace(
    "THREADS", repr(SINGLE_THREADED)
)


def test_batch_workers_start_light(tmp_path: Path) -> None:
    reports = tmp_path / "reports"
    reports.mkdir()
    env = hooked_env(tmp_path, _HOOK)
    env["CLEAR_TEST_REPORTS"] = str(reports)
    for var in SINGLE_THREADED:
        env.pop(var, None)
    frames = [FIXTURES / "isolated_box.pcd", FIXTURES / "two_touching_boxes.pcd"]
    res = clear("segment", *frames, "--json", "--jobs", "2", env=env)
    assert res.returncode == 0, res.stderr
    rows, summary = lines_of(res.stdout)
    assert [r["exit_code"] for r in rows] == [0, 0] and summary["failed"] == 0
    workers = [s for s in (json.loads(p.read_text()) for p in reports.glob("*.json")) if s.pop("worker")]
    assert workers, "no worker reported: nothing was checked"
    for state in workers:
        assert state.pop("scipy") is True, "the worker did not import SciPy: nothing was checked"
        assert state.pop("scipy_array_api") is False  # scipy._lib._util's code not run
        assert state.pop("env") == dict.fromkeys(SINGLE_THREADED, "1")
        # scipy.spatial.transform: not imported, scipy.spatial's code (which imports it) not
        # run; nor scipy.special, which scipy.ndimage's code imported (clearcli/perception/
        # raster.py calls its C functions without it); nor NumPy's tooling and pydoc, which
        # SciPy's array-API layer imported (scipy._lib._util's code imports that layer)
        assert state == {
            **dict.fromkeys(DEFERRED_PACKAGES | DEFERRED_CODE_MODULES, "deferred"),
            **dict.fromkeys(DEFERRED_MODULES, "absent"),
            "scipy.spatial.transform": "absent",
            "scipy.special": "absent",
        }
