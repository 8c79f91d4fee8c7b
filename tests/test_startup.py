"""clearcli/startup.py's deferred packages (DEFERRED_PACKAGES): a SciPy subpackage's own
code runs at the first use of a name it defines, not at its import; the names clear
uses of scipy.spatial (PACKAGE_SHORTCUTS) come from their own modules without it; and
what the package gives, before and after its code ran, is what a plain import gives.
Each case in a fresh interpreter (the hook changes how that process imports)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import REPO

from clearcli.startup import DEFERRED_PACKAGES, PACKAGE_SHORTCUTS

# the same computation with and without the hook: a 3-4-5 triangle and a unit square
_USE = """
import json, sys
import numpy as np
from scipy.spatial import ConvexHull, QhullError, cKDTree
tree_then = cKDTree
square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5]])
dist, idx = cKDTree(square).query([[0.9, 0.8]], k=2)
hull = ConvexHull(square)
try:
    ConvexHull(np.zeros((3, 2)))
    flat = "no error"
except QhullError:
    flat = "QhullError"
unrun = sorted(n for n in DEFERRED if type(sys.modules.get(n)).__name__ == "_DeferredPackage")
import scipy.spatial
d = scipy.spatial.distance.euclidean([0.0, 0.0], [3.0, 4.0])  # not a shortcut: runs its code
print(json.dumps({
    "unrun_before": unrun,
    "unrun_after": sorted(n for n in DEFERRED if type(sys.modules.get(n)).__name__ == "_DeferredPackage"),
    "query": [dist.round(12).tolist(), idx.tolist()],
    "hull": sorted(hull.vertices.tolist()),
    "flat": flat,
    "euclidean": d,
    "same_tree": scipy.spatial.cKDTree is tree_then is sys.modules["scipy.spatial._ckdtree"].cKDTree,
    "names": sorted(vars(scipy.spatial)),
    "linalg": float(scipy.linalg.norm([3.0, 4.0])),
}))
""".replace("DEFERRED", repr(sorted(DEFERRED_PACKAGES)))


def _run(code: str) -> dict:
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, timeout=120)
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout)


def test_scipy_spatial_gives_its_tree_and_hull_without_running_its_code() -> None:
    hooked = _run("from clearcli.startup import lighten_imports\nlighten_imports()\n" + _USE)
    plain = _run(_USE)
    # with the hook, none of the packages' own code ran for the tree and the hull (the
    # hull's module imports scipy.linalg's LAPACK table; scipy.special is not imported;
    # numpy.ma is, by NumPy, which asks it whether an array is masked)
    unrun = ["numpy.ma", "scipy.linalg", "scipy.sparse", "scipy.spatial"]
    assert hooked.pop("unrun_before") == unrun and plain.pop("unrun_before") == []
    # a name that is not a shortcut ran scipy.spatial's code (and, through it, the
    # others': scipy.spatial.distance imports scipy.linalg and scipy.special; numpy.ma's
    # code runs at the first name of it that is not a stand-in)
    assert hooked.pop("unrun_after") == ["numpy.ma", "scipy.sparse"] and plain.pop("unrun_after") == []
    # the same results and the same namespace as a plain import
    assert hooked == plain
    assert hooked["query"] == [[[0.223606797750, 0.5]], [[2, 4]]]  # (1,1): sqrt(0.1^2+0.2^2); centre: sqrt(0.4^2+0.3^2)
    assert hooked["hull"] == [0, 1, 2, 3] and hooked["flat"] == "QhullError" and hooked["euclidean"] == 5.0
    assert hooked["same_tree"] is True and hooked["linalg"] == 5.0


def test_a_package_without_shortcuts_runs_its_code_at_its_first_name() -> None:
    code = """
import sys
from clearcli.startup import lighten_imports
lighten_imports()
import scipy.sparse
m = sys.modules["scipy.sparse"]
assert type(m).__name__ == "_DeferredPackage" and hasattr(m, "__path__")
assert "coo_matrix" not in vars(m)
a = scipy.sparse.coo_matrix(([1.0, 2.0], ([0, 1], [1, 0])), shape=(2, 2)).toarray().tolist()
assert type(m) is type(sys) and a == [[0.0, 1.0], [2.0, 0.0]]
assert m.__spec__.loader is m.__loader__ and type(m.__loader__).__name__ == "SourceFileLoader"
print("ok")
"""
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "ok"


def test_shortcuts_name_modules_of_their_package_that_define_them() -> None:
    import importlib

    for package, names in PACKAGE_SHORTCUTS.items():
        assert package in DEFERRED_PACKAGES
        for name, module in names.items():
            assert hasattr(importlib.import_module(f"{package}.{module}"), name), (package, name, module)


def test_a_shortcut_to_a_module_scipy_moved_falls_back_to_the_package() -> None:
    # a later SciPy may rename its private modules: the name then comes from the
    # package's own code, as a plain import gives it, instead of an ImportError
    code = """
import sys
from clearcli import startup
startup.PACKAGE_SHORTCUTS["scipy.spatial"]["cKDTree"] = "_no_such_module"
startup.lighten_imports()
from scipy.spatial import cKDTree
import scipy.spatial
assert cKDTree is scipy.spatial.cKDTree and type(sys.modules["scipy.spatial"]) is type(sys)
print(int(cKDTree([[0.0], [2.0]]).query([[1.4]])[1][0]))
"""
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "1"


_MASKED = """
import json, sys
import numpy as np
class Masked:  # not a masked array, but what numpy.ma.getmask reads
    def __init__(self, mask):
        self._mask = mask
a = np.array([3.0, 1.0, np.nan, 1.0])
before = [np.unique(a[[0, 1, 3]]).tolist(), float(np.median([4.0, 1.0, 2.0])), bool(np.isnan(np.median(a)))]
ran_before = "numpy.ma.core" in sys.modules
asks = [np.ma.is_masked(x) for x in (a, [1, 2], "a string", 5, Masked(np.array([False, True])), Masked(np.array([False])))]
asks.append(np.ma.isMaskedArray(a))
m = np.ma.masked_array([1.0, 2.0], mask=[False, True])  # a name not a stand-in: numpy.ma's code runs
asks += [np.ma.is_masked(m), np.ma.isMaskedArray(m), np.ma.is_masked(a), np.ma.isMaskedArray(a)]
print(json.dumps({"before": before, "ran_before": ran_before, "asks": asks, "type": type(sys.modules["numpy.ma"]).__name__}))
"""


def test_numpy_ma_answers_without_its_code_what_it_answers_with_it() -> None:
    hooked = _run("from clearcli.startup import lighten_imports\nlighten_imports()\n" + _MASKED)
    plain = _run(_MASKED)
    # NumPy's np.unique and np.median asked numpy.ma, and its code did not run for that
    assert (hooked.pop("ran_before"), plain.pop("ran_before")) == (False, True)
    assert hooked == plain
    assert hooked["before"] == [[1.0, 3.0], 2.0, True]
    assert hooked["asks"] == [False, False, False, False, True, False, False, True, True, False, False]
    assert hooked["type"] == "module"  # its code ran at masked_array


# clearcli/startup.py's cache of dataclasses' generated methods: the classes made with it
# (from source compiled now, or from code the cache file kept) are the classes made
# without it, down to their methods' code and annotations.
_DATACLASSES = """
import json, sys
HOOK
import dataclasses
from dataclasses import dataclass, field

@dataclass(frozen=True)
class Pose:
    x_m: float
    name: str = "o1"
    tags: tuple[str, ...] = field(default_factory=tuple)

@dataclass(order=True)
class Count:
    n: int = 0

def code(f):
    c = f.__code__
    return [c.co_code.hex(), repr(c.co_consts), c.co_names, c.co_varnames, c.co_filename, c.co_flags]

p = Pose(1.5)
try:
    p.x_m = 2.0
    frozen = "no"
except dataclasses.FrozenInstanceError:
    frozen = "FrozenInstanceError"
cached = getattr(dataclasses, "exec", None)
print(json.dumps({
    "values": [repr(p), p == Pose(1.5, "o1", ()), hash(p) == hash(Pose(1.5)), frozen, Count(1) < Count(2), repr(Count())],
    "annotations": [repr(Pose.__init__.__annotations__), repr(Count.__init__.__annotations__)],
    "code": [code(getattr(c, m)) for c in (Pose, Count) for m in ("__init__", "__repr__", "__eq__", "__setattr__", "__lt__")
             if m in vars(c)],
    "compiled": None if cached is None else [cached.new, len(cached.used)],
}))
"""
_HOOKED = "from clearcli.startup import lighten_imports; lighten_imports()"


def _dataclasses_run(tmp_path: Path, hooked: bool, **env: str) -> dict:
    code = _DATACLASSES.replace("HOOK", _HOOKED if hooked else "")
    child = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    child.update(XDG_CACHE_HOME=str(tmp_path), **env)
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, env=child, timeout=120)
    assert res.returncode == 0, res.stderr
    out: dict = json.loads(res.stdout)
    return out


def _cache_file(tmp_path: Path) -> Path:
    files = list((tmp_path / "clear").glob("dataclass-code.*"))
    assert len(files) == 1, files
    return files[0]


def test_dataclasses_made_from_cached_code_are_the_same(tmp_path: Path) -> None:
    plain = _dataclasses_run(tmp_path, hooked=False)
    assert plain.pop("compiled") is None and not (tmp_path / "clear").exists()
    first = _dataclasses_run(tmp_path, hooked=True)
    # every generated method compiled once, then kept: Pose's __init__, __repr__, __eq__,
    # __hash__, __setattr__, __delattr__; Count's __init__, __repr__, __eq__ and 4 orderings
    assert first.pop("compiled") == [13, 13]
    assert _cache_file(tmp_path).stat().st_size > 0
    again = _dataclasses_run(tmp_path, hooked=True)
    assert again.pop("compiled") == [0, 13]  # nothing compiled: all from the cache file
    assert first == again == plain
    assert plain["values"] == [
        "Pose(x_m=1.5, name='o1', tags=())",
        True,
        True,
        "FrozenInstanceError",
        True,
        "Count(n=0)",
    ]
    assert "'x_m': 'float'" not in plain["annotations"][0]  # the types themselves: no future feature of startup.py's


def test_a_corrupt_cache_file_is_as_none_and_replaced(tmp_path: Path) -> None:
    _dataclasses_run(tmp_path, hooked=True)
    path = _cache_file(tmp_path)
    good = path.read_bytes()
    path.write_bytes(good[: len(good) // 2])  # cut short, as by a crash mid-write of another writer
    plain = _dataclasses_run(tmp_path / "plain", hooked=False)
    plain.pop("compiled")
    hooked = _dataclasses_run(tmp_path, hooked=True)
    assert hooked.pop("compiled") == [13, 13] and hooked == plain
    assert path.read_bytes() == good  # rewritten whole
    path.write_bytes(b"not marshal at all")
    assert _dataclasses_run(tmp_path, hooked=True).pop("compiled") == [13, 13]


def test_no_cache_file_when_python_writes_no_bytecode(tmp_path: Path) -> None:
    out = _dataclasses_run(tmp_path, hooked=True, PYTHONDONTWRITEBYTECODE="1")
    assert out.pop("compiled") == [13, 13]
    assert not (tmp_path / "clear").exists()


def test_the_cache_lives_under_an_absolute_cache_home_only(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    # a relative XDG_CACHE_HOME would put the file in the folder clear runs in: ignored
    from clearcli import startup

    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert str(startup._code_cache_path()).startswith(str(tmp_path / "xdg" / "clear" / "dataclass-code."))
    monkeypatch.setenv("XDG_CACHE_HOME", "cache")
    assert str(startup._code_cache_path()).startswith(str(tmp_path / "home" / ".cache" / "clear" / "dataclass-code."))
    monkeypatch.delenv("XDG_CACHE_HOME")
    assert str(startup._code_cache_path()).startswith(str(tmp_path / "home" / ".cache" / "clear"))


# scipy._lib._util (clearcli/startup.py DEFERRED_CODE_MODULES): the tree's module takes
# `copy_if_needed` from it at its import; the value is given without the module's code
# (and SciPy's array-API layer it imports), any other name runs that code.
_UTIL = """
import json, sys
PATCH
import numpy as np
from scipy.spatial import cKDTree
util = sys.modules["scipy._lib._util"]
before = [type(util).__name__, "scipy._lib._array_api" in sys.modules, hasattr(util, "__path__")]
from scipy._lib._util import copy_if_needed
dist, idx = cKDTree([[0.0, 0.0], [3.0, 4.0]]).query([[3.0, 3.0]])
given = [type(util).__name__, copy_if_needed]
rng = util.check_random_state(7)  # not a stand-in: its code runs
print(json.dumps({
    "before": before,
    "given": given,
    "after": [type(util).__name__, util.copy_if_needed, "scipy._lib._array_api" in sys.modules, type(rng).__name__],
    "query": [dist.tolist(), idx.tolist()],
}))
"""


def test_scipy_util_gives_the_trees_one_name_without_its_code() -> None:
    hook = "from clearcli.startup import lighten_imports\nlighten_imports()"
    hooked = _run(_UTIL.replace("PATCH", hook))
    plain = _run(_UTIL.replace("PATCH", ""))
    assert hooked["before"] == ["_DeferredPackage", False, False] and plain["before"] == ["module", True, False]
    assert hooked["given"] == ["_DeferredPackage", None] and plain["given"] == ["module", None]  # NumPy 2: None
    assert hooked["after"] == plain["after"] == ["module", None, True, "RandomState"]
    assert hooked["query"] == plain["query"] == [[1.0], [1]]  # (3,3) to (3,4): 1


def test_scipy_util_runs_its_code_where_clear_cannot_tell_its_value() -> None:
    # an older NumPy: only the module's own code can tell copy_if_needed (stand-in says _MISSING)
    code = _UTIL.replace(
        "PATCH",
        "from clearcli import startup\n"
        "startup.VALUE_STAND_INS['scipy._lib._util']['copy_if_needed'] = lambda: startup._MISSING\n"
        "startup.lighten_imports()",
    )
    out = _run(code)
    assert out["before"] == ["module", True, False]  # the tree's import ran it
    assert out["given"] == ["module", None] and out["after"] == ["module", None, True, "RandomState"]


# The garbage collector while a frame command loads its libraries (clearcli/startup.py
# pause_collection): off, then on again with what was made until then frozen.
def gc_threshold_0() -> int:
    import gc

    return gc.get_threshold()[0]


_COLLECTION = """
import gc, json, sys
from clearcli import startup
startup.pause_collection()
paused = [gc.isenabled(), startup._collection_paused]
junk = [[] for _ in range(1000)]
for a in junk:
    a.append(a)  # cycles, not freed while the collector is off
made = gc.get_count()[0]
startup.resume_collection(freeze=FREEZE)
resumed = [gc.isenabled(), gc.get_freeze_count() > 1000, startup._collection_paused]
del junk
import numpy  # a process with NumPy loaded (a test, a program): left alone
startup.pause_collection()
again = [gc.isenabled(), startup._collection_paused]
startup.resume_collection()
print(json.dumps({"paused": paused, "made": made, "resumed": resumed, "again": again, "frozen": gc.get_freeze_count() > 1000}))
"""


@pytest.mark.parametrize("freeze", [True, False])
def test_collection_is_paused_until_resumed_and_then_frozen(freeze: bool) -> None:
    out = _run(_COLLECTION.replace("FREEZE", str(freeze)))
    assert out["paused"] == [False, True]
    # the 1000 lists counted since the pause: a running collector would have reset the
    # count at its threshold (700) and collected
    assert out["made"] >= 1000 > gc_threshold_0()
    assert out["resumed"] == [True, freeze, False]
    assert out["again"] == [True, False]  # NumPy loaded: not paused
    assert out["frozen"] is freeze


def test_the_cache_file_is_read_whole_in_one_call(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # marshal.load(file) reads a file one small piece per object: ~10 ms for a plan's ~500
    # texts, against ~1 ms for one read then marshal.loads (issue 39); the same codes
    import builtins
    import marshal

    from clearcli import startup

    texts = [f"def f{k}(self):\n    return self.x + {k}\n" for k in range(50)]
    codes = {str(k).encode(): compile(t, "<string>", "exec", dont_inherit=True) for k, t in enumerate(texts)}
    path = tmp_path / "cache"
    path.write_bytes(marshal.dumps(codes))
    reads: list[str] = []
    real_open = builtins.open

    class Counted:
        def __init__(self, f):  # type: ignore[no-untyped-def]
            self._f = f

        def __enter__(self):  # type: ignore[no-untyped-def]
            return self

        def __exit__(self, *exc):  # type: ignore[no-untyped-def]
            self._f.close()

        def __getattr__(self, name):  # type: ignore[no-untyped-def]
            if name in ("read", "readinto", "readline", "peek"):
                reads.append(name)
            return getattr(self._f, name)

    monkeypatch.setattr(builtins, "open", lambda *a, **k: Counted(real_open(*a, **k)))
    cached = startup._CachedExec(str(path))
    monkeypatch.setattr(builtins, "open", real_open)
    assert reads == ["read"]
    assert sorted(cached.codes) == sorted(codes) and all(cached.codes[k] == codes[k] for k in codes)
