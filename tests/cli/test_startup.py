"""Start-up: `clear` does not run NumPy's test and build tooling that SciPy's array-API
layer imports (clearcli/cli.py DEFERRED_MODULES), nor the code of SciPy's subpackages
whose names it does not use (clearcli/startup.py DEFERRED_PACKAGES), and code that uses
them still gets them; `clear --help` is printed from its recording, identical to the app's."""

from __future__ import annotations

import importlib.util
import json
import marshal
import os
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import FIXTURES, REPO, run_clear
from helpers.batch import hooked_env

from clearcli.cli import DEFERRED_MODULES, render_root_help
from clearcli.commands import registry, root_help
from clearcli.startup import DEFERRED_CODE_MODULES, DEFERRED_PACKAGES

# In the child before clear's main: at exit, which deferred modules ran their code.
_HOOK = """
import atexit, importlib.util, json, os, sys

def _report():
    state = {}
    for name in DEFERRED:
        module = sys.modules.get(name)
        # type(), not module.__class__: any attribute access would load a lazy module
        lazy = type(module) is importlib.util._LazyModule or type(module).__name__ == "_DeferredPackage"
        state[name] = "absent" if module is None else "deferred" if lazy else "loaded"
    state["scipy"] = "scipy" in sys.modules
    state["scipy_array_api"] = "scipy._lib._array_api" in sys.modules
    with open(os.environ["CLEAR_TEST_REPORT"], "w") as out:
        json.dump(state, out)

atexit.register(_report)
""".replace("DEFERRED", repr(sorted(DEFERRED_MODULES | DEFERRED_PACKAGES | DEFERRED_CODE_MODULES)))

# what a command leaves unrun: numpy.ma, SciPy's subpackages and SciPy's utilities
# (scipy._lib._util, whose one name the tree imports is given without its code) imported
# and not run; SciPy's array-API layer, which imported NumPy's tooling and pydoc, not
# imported at all (scipy._lib._util's code imports it), nor scipy.spatial.transform
# (scipy.spatial's code imports it) or scipy.special (scipy.ndimage's code imported it)
_UNRUN = {
    **dict.fromkeys(DEFERRED_PACKAGES | DEFERRED_CODE_MODULES, "deferred"),
    **dict.fromkeys(DEFERRED_MODULES, "absent"),
    "scipy.spatial.transform": "absent",
    "scipy.special": "absent",
}


def test_segment_leaves_numpy_tooling_unrun(tmp_path: Path) -> None:
    report = tmp_path / "report.json"
    env = hooked_env(tmp_path, _HOOK)
    env["CLEAR_TEST_REPORT"] = str(report)
    res = run_clear("segment", FIXTURES / "isolated_box.pcd", "--json", timeout=120, env=env)
    assert res.returncode == 0, res.stderr
    assert json.loads(res.stdout)["schema"] == "clear.segmentation"
    state = json.loads(report.read_text())
    assert state.pop("scipy") is True, "segment did not import SciPy: nothing was checked"
    assert state.pop("scipy_array_api") is False  # issue 39: ~20-30 ms of CPU of a cold plan
    assert state == _UNRUN


def test_deferred_modules_load_whole_on_use() -> None:
    code = """
import importlib.util, sys
from clearcli.cli import _lighten_imports
_lighten_imports()
import scipy.sparse
scipy.sparse.coo_matrix  # a name that runs its code (clearcli/startup.py DEFERRED_PACKAGES)
assert type(sys.modules["numpy.testing"]) is importlib.util._LazyModule
import numpy as np
from numpy.testing import assert_allclose
assert_allclose(np.polynomial.Polynomial([1.0, 2.0])(3.0), 7.0)
assert type(sys.modules["numpy.testing"]) is not importlib.util._LazyModule
assert "unittest" in sys.modules
import scipy.spatial
scipy.spatial.distance  # a name that runs scipy.spatial's code (clearcli/startup.py DEFERRED_PACKAGES)
assert type(sys.modules["scipy.spatial.transform"]) is importlib.util._LazyModule
from scipy.spatial.transform import Rotation
assert abs(Rotation.from_euler("z", 90, degrees=True).as_matrix()[1, 0] - 1.0) < 1e-12
assert type(sys.modules["pydoc"]) is importlib.util._LazyModule  # SciPy's docscrape imported it
import pydoc
assert pydoc.getdoc(Rotation).startswith("Rotation in 3 dimensions")
print("ok")
"""
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "ok"


def test_scipy_keeps_its_docstrings_unparsed_and_works() -> None:
    """SciPy's array-API decorator leaves each docstring as it is (clearcli/cli.py
    _DocstringKept): the text whole, its capability table filled, the functions the same."""
    code = """
import json, sys
from clearcli.cli import _lighten_imports
_lighten_imports()
import numpy as np
import scipy.linalg, scipy.ndimage, scipy.spatial, scipy.spatial.transform, scipy.special
scipy.linalg.norm, scipy.spatial.distance, scipy.spatial.transform.Rotation  # run their code (DEFERRED_PACKAGES)
from scipy._lib import _array_api
labels, n = scipy.ndimage.label(np.array([[1, 0, 1], [1, 0, 0]]))
hull = scipy.spatial.ConvexHull(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.2, 0.2]]))
print(json.dumps({
    "kept": _array_api.FunctionDoc.__name__,
    "table": len(_array_api.xp_capabilities_table),
    "doc": scipy.ndimage.label.__doc__,
    "results": [labels.tolist(), n, sorted(hull.vertices.tolist()), float(scipy.special.gamma(5.0))],
}))
"""
    kept = json.loads(_run_python(code))
    plain = json.loads(_run_python(code.replace("_lighten_imports()", "")))
    assert (kept["kept"], plain["kept"]) == ("_DocstringKept", "FunctionDoc")
    assert kept["results"] == plain["results"] == [[[1, 0, 2], [1, 0, 0]], 2, [0, 1, 2], 24.0]
    assert kept["table"] == plain["table"] > 100
    assert kept["doc"].startswith("Label features in an array.") and "Parameters\n    ----------" in kept["doc"]
    # what is dropped: numpydoc's re-rendering and its note on array-API support
    assert "Array API Standard Support" in plain["doc"] and "Array API Standard Support" not in kept["doc"]


def _run_python(code: str) -> str:
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, timeout=120)
    assert res.returncode == 0, res.stderr
    return res.stdout


# `clear --help` printed from its recording (clearcli/commands/root_help.py) without
# importing typer or any command module: identical to what the app prints, wherever used.

_APP_HELP = """
import sys
from clearcli.cli import make_app
make_app()(prog_name=sys.argv[1], args=["--help"])
"""


def _app_help(prog_name: str, columns: int) -> str:
    """What the app itself prints for --help (the recording bypassed), in a child."""
    env = dict(os.environ, COLUMNS=str(columns))
    res = subprocess.run(
        [sys.executable, "-c", _APP_HELP, prog_name], capture_output=True, text=True, cwd=REPO, env=env, timeout=120
    )
    assert res.returncode == 0, res.stderr
    return res.stdout


def test_the_recorded_help_is_what_the_app_prints() -> None:
    assert root_help.TEXT == _app_help("clear", 80) == _app_help("clear", 200), (
        "the root help changed: re-record it with `python tests/cli/record_root_help.py`"
    )
    assert render_root_help() == root_help.TEXT
    assert "Commands:" in root_help.TEXT and all(name in root_help.TEXT for name in registry.NAMES)


def _help_hooked(tmp_path: Path, *args: str, **env: str) -> tuple[subprocess.CompletedProcess[str], dict]:
    report = tmp_path / "report.json"
    child_env = hooked_env(tmp_path, _MODULES_HOOK)
    child_env.pop("COLUMNS", None)
    child_env.update(env, CLEAR_TEST_REPORT=str(report))
    res = run_clear(*args, timeout=120, env=child_env)
    return res, json.loads(report.read_text())


_MODULES_HOOK = """
import atexit, json, os, sys
atexit.register(lambda: json.dump(
    {"typer": "typer" in sys.modules, "commands": sorted(m for m in sys.modules if m.startswith("clearcli.commands."))},
    open(os.environ["CLEAR_TEST_REPORT"], "w")))
"""


@pytest.mark.parametrize("columns", [None, "80", "200"])
def test_help_is_printed_from_the_recording(tmp_path: Path, columns: str | None) -> None:
    res, loaded = _help_hooked(tmp_path, "--help", **({"COLUMNS": columns} if columns else {}))
    assert (res.returncode, res.stdout, res.stderr) == (0, root_help.TEXT, "")
    assert loaded == {"typer": False, "commands": ["clearcli.commands.registry", "clearcli.commands.root_help"]}


def test_a_narrow_terminal_gets_the_apps_own_help(tmp_path: Path) -> None:
    res, loaded = _help_hooked(tmp_path, "--help", COLUMNS="60")
    assert res.returncode == 0 and res.stdout == _app_help("clear", 60) != root_help.TEXT
    assert max(len(line) for line in res.stdout.splitlines()) <= 58  # click's width there: 60 - 2
    assert loaded["typer"] is True


def test_help_of_a_command_or_a_completion_request_goes_through_the_app(tmp_path: Path) -> None:
    res, loaded = _help_hooked(tmp_path, "plan", "--help")
    assert res.returncode == 0 and res.stdout.startswith("Usage: clear plan [OPTIONS]")
    assert loaded["typer"] is True and "clearcli.commands.plan" in loaded["commands"]
    (tmp_path / "completion").mkdir()
    res, loaded = _help_hooked(
        tmp_path / "completion", "--help", _CLEAR_COMPLETE="complete_bash", COMP_WORDS="clear pl", COMP_CWORD="1"
    )
    assert res.returncode == 0 and res.stdout.split() == ["plan"]
    assert loaded["typer"] is True


_ALL_MODULES_HOOK = """
import atexit, json, os, sys

def _report():
    with open(os.environ["CLEAR_TEST_REPORT"], "w") as out:
        json.dump(sorted(sys.modules), out)

atexit.register(_report)
"""


@pytest.mark.parametrize("command", ["segment", "plan"])
def test_a_command_imports_only_what_it_runs(tmp_path: Path, command: str) -> None:
    """Issue 39: reading a PCD needs neither pypcd4 nor pydantic (its header is parsed by
    clearcli/io/pcd.py), a plan on the default arm (the WAM) not Pinocchio (its
    kinematics are NumPy's), and `segment` none of the predicates' or planner's modules."""
    report = tmp_path / "modules.json"
    env = hooked_env(tmp_path, _ALL_MODULES_HOOK)
    env["CLEAR_TEST_REPORT"] = str(report)
    res = run_clear(command, FIXTURES / "isolated_box.pcd", "--json", timeout=180, env=env)
    assert res.returncode in (0, 10), res.stderr
    modules = set(json.loads(report.read_text()))
    assert "clearcli.perception.segment" in modules and "clearcli.io.pcd" in modules  # it did run
    heavy = {"pypcd4", "pydantic", "pinocchio", "coal"}
    assert not {m.split(".")[0] for m in modules} & heavy
    # logging only where a segment is left out (clearcli/predicates/state_builder.py),
    # importlib.resources only where package data is read (the PDDL domain's text for
    # --domain/--problem, the learned join's model: off by default)
    assert "logging" not in modules and "importlib.resources" not in modules
    stages = {m for m in modules if m.startswith(("clearcli.planning", "clearcli.predicates", "clearcli.robot"))}
    if command == "segment":
        assert stages == set()
    else:
        assert {"clearcli.planning.backtrack", "clearcli.robot.wam_kinematics"} <= stages
        # the suction kind is registered, its model only imported for a tool with a cup
        assert "clearcli.predicates.grasps.suction" in modules and "clearcli.geometry.suction" not in modules
    # SciPy: the tree's and the hull's modules (and the LAPACK table the hull loads), the
    # two C modules of scipy.ndimage clearcli/perception/raster.py calls, no more of
    # scipy.spatial, scipy.sparse, scipy.linalg, scipy.ndimage (its array-API layer) or
    # scipy.special (clearcli/startup.py DEFERRED_PACKAGES: ~35 ms of a cold plan on a
    # quiet machine); numpy.ma imported, its code (numpy.ma.core) not run
    # nor SciPy's array-API layer (scipy._lib._util's code imports it, and the tree takes
    # one name of that module: clearcli/startup.py DEFERRED_CODE_MODULES)
    assert "scipy._lib._util" in modules and "scipy._lib._array_api" not in modules
    deferred = {m for m in modules if any(m == p or m.startswith(p + ".") for p in DEFERRED_PACKAGES)}
    assert deferred == (DEFERRED_PACKAGES - {"scipy.special"}) | {
        "scipy.spatial._ckdtree",
        "scipy.spatial._qhull",
        "scipy.linalg.cython_lapack",
        "scipy.ndimage._ni_label",
        "scipy.ndimage._nd_image",
    }


@pytest.mark.parametrize("command", ["segment", "plan"])
def test_text_to_a_pipe_does_not_import_rich(tmp_path: Path, command: str) -> None:
    """Issue 39: `clear segment` and `clear plan` print their text to a pipe without rich
    (clearcli/console.py writes what rich would); rich was ~40-60 ms of their cold start."""
    report = tmp_path / "modules.json"
    env = hooked_env(tmp_path, _ALL_MODULES_HOOK)
    env["CLEAR_TEST_REPORT"] = str(report)
    for name in ("FORCE_COLOR", "TTY_COMPATIBLE", "JUPYTER_COLUMNS", "JUPYTER_LINES"):
        env.pop(name, None)
    res = run_clear(command, FIXTURES / "isolated_box.pcd", timeout=180, env=env)
    assert res.returncode in (0, 10), res.stderr
    assert res.stdout.strip()  # it printed its text
    if command == "segment":
        assert "┏━" in res.stdout and "isolated_box.pcd: table normal" in res.stdout  # the table, the bold line
    modules = set(json.loads(report.read_text()))
    assert "clearcli.console" in modules
    assert not {m for m in modules if m == "rich" or m.startswith("rich.")}


_COMPILED_HOOK = """
import atexit, json, os, sys

def _report():
    cached = getattr(sys.modules.get("dataclasses"), "exec", None)
    with open(os.environ["CLEAR_TEST_REPORT"], "w") as out:
        json.dump(None if cached is None else [cached.new, len(cached.used)], out)

atexit.register(_report)
"""


def test_plan_keeps_its_dataclasses_code_for_the_next_call(tmp_path: Path) -> None:
    """Issue 39: the methods dataclasses generate (~500 in a plan, most of their cost to
    compile) are compiled by the first `clear plan` of a user and kept in their cache
    (clearcli/startup.py `_cache_dataclass_code`); the next call compiles none, and prints
    the same."""
    report = tmp_path / "compiled.json"
    env = hooked_env(tmp_path, _COMPILED_HOOK)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env.update(XDG_CACHE_HOME=str(tmp_path / "cache"), CLEAR_TEST_REPORT=str(report))
    runs = []
    for _ in range(2):
        res = run_clear("plan", FIXTURES / "isolated_box.pcd", "--json", timeout=180, env=env)
        assert res.returncode in (0, 10), res.stderr
        doc = json.loads(res.stdout)
        doc.pop("timings_s")
        runs.append((doc, json.loads(report.read_text())))
    (first, (new_1, used_1)), (again, (new_2, used_2)) = runs
    assert first == again
    assert new_1 == used_1 > 300 and (new_2, used_2) == (0, used_1)
    assert [p.name for p in (tmp_path / "cache" / "clear").iterdir()] == [
        f"dataclass-code.{sys.implementation.cache_tag}.{importlib.util.MAGIC_NUMBER.hex()}.m{marshal.version}.v1"
    ]


_COLLECTOR_HOOK = """
import atexit, gc, json, os, sys
runs = []
# per collection: after main's start (typer is imported after it), after the frame's read
# (the PCD reader's module loads then)
gc.callbacks.append(
    lambda phase, info: phase == "stop" and runs.append(("typer" in sys.modules, "clearcli.io.pcd" in sys.modules))
)
atexit.register(lambda: json.dump(
    {"enabled": gc.isenabled(), "frozen": gc.get_freeze_count(), "numpy_frozen": "numpy" in sys.modules,
     "before_read": runs.count((True, False)), "after_read": runs.count((True, True))},
    open(os.environ["CLEAR_TEST_REPORT"], "w")))
"""


@pytest.mark.parametrize(
    ("args", "frozen"),
    [
        (("plan", FIXTURES / "isolated_box.pcd"), True),
        (("segment", FIXTURES / "isolated_box.pcd", "--json"), True),
        (("plan", "--help"), False),  # no frame read: the collector back on as it was
        (("info", FIXTURES / "isolated_box.pcd"), False),  # not a frame command of issue 39's
    ],
)
def test_a_frame_command_loads_its_libraries_without_the_collector(
    tmp_path: Path, args: tuple[object, ...], frozen: bool
) -> None:
    """Issue 39: the collector scanned start-up's ~100 000 objects ~80 times in a cold
    `clear plan` (~14 ms), freeing nothing; a frame command pauses it until it reads its
    frame (clearcli/startup.py pause_collection), then freezes what it loaded."""
    report = tmp_path / "gc.json"
    env = hooked_env(tmp_path, _COLLECTOR_HOOK)
    env["CLEAR_TEST_REPORT"] = str(report)
    res = run_clear(*args, timeout=180, env=env)
    assert res.returncode in (0, 10), res.stderr
    state = json.loads(report.read_text())
    assert state["enabled"] is True
    if frozen:
        # no collection from main's start until the frame was read
        assert state["before_read"] == 0 and state["after_read"] > 0
        assert state["frozen"] > 10_000 and state["numpy_frozen"] is True
    else:
        assert state["frozen"] == 0 and state["before_read"] > 0


def test_a_batchs_parent_turns_the_collector_back_on(tmp_path: Path) -> None:
    report = tmp_path / "gc.json"
    env = hooked_env(tmp_path, _COLLECTOR_HOOK)
    env["CLEAR_TEST_REPORT"] = str(report)
    frames = [FIXTURES / "isolated_box.pcd", FIXTURES / "two_touching_boxes.pcd"]
    res = run_clear("segment", *frames, "--json", "--jobs", "1", timeout=180, env=env)
    assert res.returncode == 0, res.stderr
    state = json.loads(report.read_text())
    assert state["enabled"] is True and state["frozen"] > 10_000  # resumed before its run
