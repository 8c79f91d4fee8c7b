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
    state["batch_parent"] = multiprocessing.parent_process() is None and "clearcli.batch.run" in sys.modules
    state["dataclass_exec"] = type(getattr(sys.modules.get("dataclasses"), "exec", None)).__name__
    import gc
    state["gc"] = [gc.isenabled(), gc.get_freeze_count() > 0]
    state["rich"] = sorted(name for name in sys.modules if name == "rich" or name.startswith("rich."))
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
        state.pop("rich")
        state.pop("batch_parent")
        # the dataclass code cache (clearcli/startup.py), though multiprocessing imported
        # dataclasses before the worker could patch it at its import
        assert state.pop("dataclass_exec") == "_CachedExec"
        # the collector paused while the libraries loaded, on again (what they made frozen)
        assert state.pop("gc") == [True, True]
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


def test_json_batch_parent_loads_no_rich_and_workers_run_their_exit_handlers(tmp_path: Path) -> None:
    """A --json batch whose stderr is a pipe draws no progress bar and no table: its parent
    imports none of rich (rich.progress and rich.console were ~40 ms before the workers
    started, issue 39). The workers end by `os._exit` after their exit handlers: the
    hook's report, written by an atexit handler, comes from every worker."""
    reports = tmp_path / "reports"
    reports.mkdir()
    env = hooked_env(tmp_path, _HOOK)
    env["CLEAR_TEST_REPORTS"] = str(reports)
    for var in ("FORCE_COLOR", "TTY_COMPATIBLE", "JUPYTER_COLUMNS", "JUPYTER_LINES"):
        env.pop(var, None)
    frames = [FIXTURES / "isolated_box.pcd", FIXTURES / "two_touching_boxes.pcd"]
    res = clear("segment", *frames, "--json", "--jobs", "2", env=env)
    assert res.returncode == 0, res.stderr
    rows, summary = lines_of(res.stdout)
    assert summary["failed"] == 0 and summary["backend"] == "2 worker processes"
    states = [json.loads(p.read_text()) for p in reports.glob("*.json")]
    workers = [s for s in states if s["worker"]]
    parents = [s for s in states if s["batch_parent"]]
    assert len(workers) == 2, states
    assert len(parents) == 1, states
    assert parents[0]["rich"] == []


def test_workers_collect_again_after_jobs_that_read_no_frame(tmp_path: Path) -> None:
    """A worker pauses the cyclic collector until its first frame is read
    (clearcli/startup.py pause_collection): a batch of inputs that are no point cloud
    does not go on without it (the read turns it on before it fails, and the pool after
    every job in any case)."""
    reports = tmp_path / "reports"
    reports.mkdir()
    env = hooked_env(tmp_path, _HOOK)
    env["CLEAR_TEST_REPORTS"] = str(reports)
    broken = tmp_path / "broken.pcd"
    broken.write_text("not a point cloud")
    res = clear("segment", broken, broken, "--json", "--jobs", "2", env=env)
    rows, _ = lines_of(res.stdout)
    assert [r["exit_code"] for r in rows] == [3, 3], res.stderr
    workers = [s for s in (json.loads(p.read_text()) for p in reports.glob("*.json")) if s["worker"]]
    assert len(workers) == 2
    assert all(w["gc"] == [True, True] for w in workers)
