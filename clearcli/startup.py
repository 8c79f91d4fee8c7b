"""What every `clear` process does before it imports NumPy: a single `clear` call
(clearcli/cli.py `main`) and each worker of a batch (clearcli/batch/pool.py), which is a
fresh interpreter (spawned) that does not run `main`.

`single_threaded_numerics` sets the numeric libraries' thread pools to one thread;
`lighten_imports` defers NumPy's and SciPy's modules clear never uses, runs SciPy's
subpackages' (and numpy.ma's, and SciPy's utilities') own code only where a name of theirs
is used, keeps SciPy from parsing docstrings, and has dataclasses run the code it compiled
for a class in an earlier process, kept in the user's cache directory (issue 39). Both only change what a
process loads and how fast, never a result. Standard library only: this runs before
anything heavy is imported.
"""

from __future__ import annotations

import _thread
import atexit
import gc
import importlib
import importlib.machinery
import importlib.util
import marshal
import os
import sys
from collections.abc import Callable
from types import ModuleType
from typing import Any

# Numeric libraries' thread pools: one thread each in a single `clear` call. NumPy's
# OpenBLAS starts a worker per core when it loads, and on clear's small products the
# workers spin for nothing: the same wall time for more CPU (issue 39: mOSD test48's
# segment 0.26 s of CPU for 0.15 s of wall with them, 0.15 s without). The batch's
# workers (clearcli/batch/pool.py) set the same and inherit these. The libraries read
# them when they load, so they are set before anything imports NumPy; a value the user
# set is kept.
SINGLE_THREADED = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def single_threaded_numerics() -> None:
    for var in SINGLE_THREADED:
        os.environ.setdefault(var, "1")


# NumPy subpackages clear never uses: its test and build tooling, and polynomials.
# SciPy's array-API layer (scipy._lib.array_api_compat.numpy, imported by every SciPy
# subpackage through scipy._lib._util) copies NumPy's namespace with `from numpy import *`
# and a getattr of every name, and NumPy's lazy attributes then import them all:
# numpy.f2py (the Fortran wrapper generator) and numpy.testing (unittest, difflib) were
# 57 ms of a cold `clear plan` on a quiet machine (issue 39), numpy.polynomial some 6 ms
# more (numpy.ma is left alone: SciPy's functions touch it on their first call). Here
# importing one of them only creates the module; its code runs at the first use of one
# of its attributes (the standard library's importlib.util.LazyLoader), so code that does
# use them gets them whole. scipy.spatial imports its rotations (scipy.spatial.transform,
# ~20 ms on a quiet machine) with `from . import transform`; clear uses its trees and
# hulls only. SciPy's docstring parser (scipy._lib._docscrape, imported by its array-API
# layer) imports pydoc at its top and uses it only inside functions clear does not reach:
# pydoc was 30-40 ms of a cold `clear plan` here (issue 39).
DEFERRED_MODULES = frozenset({"numpy.f2py", "numpy.testing", "numpy.polynomial", "scipy.spatial.transform", "pydoc"})


# SciPy subpackages whose own code (their __init__) runs at the first use of a name they
# define, not when they are imported: their modules import without it (the package's
# __path__ is set), so `from scipy.spatial import cKDTree` needs only the tree's module.
# Importing scipy.spatial ran its whole namespace: scipy.sparse (for cKDTree's
# sparse_distance_matrix, which clear never calls), scipy.linalg (the hull's module
# loads LAPACK's table from scipy.linalg.cython_lapack, a module of that package),
# scipy.special and scipy.spatial.distance (for geometric_slerp), its Voronoi and
# Procrustes, none of it used: SciPy's imports in a cold `clear plan` went from ~66 to
# ~25 ms with this (issue 39; sums of -X importtime minima over 8-10 runs; callgrind:
# 8 % fewer instructions for the whole plan). A package whose code ran is the very
# module it would have been (the same objects; only when its code runs differs).
# scipy.ndimage's code (its array-API wrappers and all of its modules, ~15 ms of a cold
# `clear plan` on a loaded machine) runs only where a name of it is used:
# clearcli/perception/raster.py imports the two C modules it calls without it.
DEFERRED_PACKAGES = frozenset(
    {"numpy.ma", "scipy.linalg", "scipy.ndimage", "scipy.sparse", "scipy.spatial", "scipy.special"}
)
# Names a deferred package gives from the module that defines them, its own code not run
# (the same object its code would give: it imports them from there); any other name
# runs the package's code. clear uses only these of scipy.spatial.
PACKAGE_SHORTCUTS: dict[str, dict[str, str]] = {
    "scipy.spatial": {"cKDTree": "_ckdtree", "ConvexHull": "_qhull", "Delaunay": "_qhull", "QhullError": "_qhull"},
}


def _is_masked(x: Any) -> bool:
    """numpy.ma.is_masked without numpy.ma's code: ``getmask(x)`` is ``x._mask``, or
    ``nomask`` (so False) for what has none, as every array but a masked one; a masked
    one (or anything with a ``_mask``) gets numpy.ma's own answer."""
    if not hasattr(x, "_mask"):
        return False
    answer: bool = importlib.import_module("numpy.ma.core").is_masked(x)
    return answer


def _is_masked_array(x: Any) -> bool:
    """numpy.ma.isMaskedArray without numpy.ma's code: ``isinstance(x, MaskedArray)``,
    and no masked array exists before numpy.ma.core has run (it defines the class)."""
    core = sys.modules.get("numpy.ma.core")
    return core is not None and bool(core.isMaskedArray(x))


# numpy.ma (masked arrays) is a deferred package too: clear makes no masked array, but
# NumPy asks numpy.ma of every array np.unique is given (is_masked) and of np.median's
# NaN check (isMaskedArray), and numpy.ma's code (its core module: ~6 ms of a cold
# `clear plan` on a loaded machine) ran for that alone. Names a deferred package answers
# with a function of clear's while its code has not run, giving that function's answer
# exactly (not bound: once its code ran, the name is the package's own); any other name
# runs the package's code.
STAND_INS: dict[str, dict[str, Callable[..., Any]]] = {
    "numpy.ma": {"is_masked": _is_masked, "isMaskedArray": _is_masked_array}
}


def _copy_if_needed() -> Any:
    """scipy._lib._util.copy_if_needed without its module's code: None on a NumPy whose
    version is 2.0.0 or later, as that code decides it (by the same comparison); on an
    older NumPy (a test of np.array's keywords there) `_MISSING`: its code runs."""
    import numpy as np  # noqa: PLC0415  (imported by now: SciPy's modules import it first)

    return None if np.lib.NumpyVersion(np.__version__) >= "2.0.0" else _MISSING


# Modules, not packages, whose own code is deferred as a package's is (DEFERRED_PACKAGES):
# it runs at the first use of a name it defines that VALUE_STAND_INS does not give.
# scipy.spatial's tree (scipy.spatial._ckdtree, a Cython module) imports one name of
# SciPy's utilities at its import, `copy_if_needed` (None on NumPy 2); those utilities'
# module imports SciPy's whole array-API layer (scipy._lib._array_api: array_api_compat's
# copy of NumPy's namespace, array_api_extra, the docstring parser), ~20-30 ms of CPU of a
# cold `clear plan` that no function clear calls uses (issue 39).
DEFERRED_CODE_MODULES = frozenset({"scipy._lib._util"})
# Names such a module (or a deferred package) gives while its code has not run: the value
# its code would bind (the same object), from a function of clear's that computes it,
# or `_MISSING` when only its code can tell (then it runs).
VALUE_STAND_INS: dict[str, dict[str, Callable[[], Any]]] = {"scipy._lib._util": {"copy_if_needed": _copy_if_needed}}
_PACKAGE_LOCK = _thread.RLock()  # one thread runs a package's code; the others wait for it


class _DeferredPackage(ModuleType):
    """A package of DEFERRED_PACKAGES whose own code has not run yet. Python calls
    __getattr__ only for names the module does not hold: its spec, __path__ and the
    submodules imported so far are there without it."""

    def __getattr__(self, name: str) -> Any:
        with _PACKAGE_LOCK:
            if type(self) is _DeferredPackage:
                loader = getattr(self.__spec__, "loader", None)
                if not isinstance(loader, _DeferredLoader) or loader.running:
                    # its code is running (in this thread: the lock is held) and has not
                    # defined the name yet, as any module part-way through its code
                    raise AttributeError(f"partially initialised module {self.__name__!r} has no attribute {name!r}")
                if name == "__path__":
                    # a module, not a package (DEFERRED_CODE_MODULES): it has none, with its
                    # code run or not (the import system asks, for `from module import name`)
                    raise AttributeError(f"module {self.__name__!r} has no attribute '__path__'")
                stand_in = STAND_INS.get(self.__name__, {}).get(name)
                if stand_in is not None:
                    return stand_in
                value_of = VALUE_STAND_INS.get(self.__name__, {}).get(name)
                if value_of is not None:
                    value = value_of()
                    if value is not _MISSING:
                        setattr(self, name, value)  # kept: its code, when it runs, binds the same value
                        return value
                module = PACKAGE_SHORTCUTS.get(self.__name__, {}).get(name)
                if module is not None:
                    try:
                        value = getattr(importlib.import_module(f"{self.__name__}.{module}"), name, _MISSING)
                    except ImportError:  # a SciPy that moved it: its package's code gives it
                        value = _MISSING
                    if value is not _MISSING:
                        setattr(self, name, value)  # kept: its code, when it runs, binds the same object
                        return value
                loader.run(self)
        return getattr(self, name)


_MISSING = object()


class _DeferredLoader:
    """A package's own loader, its code run by `run` (at the first use of a name its code
    defines) instead of at the import; anything else asked of the loader goes to its own."""

    def __init__(self, loader: Any) -> None:
        self._loader = loader
        self.running = False

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType | None:
        module: ModuleType | None = self._loader.create_module(spec)
        return module

    def exec_module(self, module: ModuleType) -> None:
        module.__class__ = _DeferredPackage

    def run(self, module: ModuleType) -> None:
        self.running = True
        try:
            # the module's loader is its own from here, as if imported without this
            module.__loader__ = self._loader
            if module.__spec__ is not None:
                module.__spec__.loader = self._loader
            self._loader.exec_module(module)
        finally:
            module.__class__ = ModuleType
            self.running = False

    def __getattr__(self, name: str) -> Any:
        return getattr(self._loader, name)


class _DocstringKept:
    """Stands for numpydoc's FunctionDoc in SciPy's xp_capabilities decorator: the
    function's docstring as it is, no section parsed, the note appended to nothing.

    That decorator (scipy._lib._array_api, SciPy >= 1.15) wraps the public functions of
    scipy.linalg, special, ndimage, spatial ... as they are defined, and parses each
    docstring to render it again with a note on array-API support: 229 docstrings, 0.16
    of the 0.40 s of CPU the SciPy subpackages of a `clear plan` took to import (issue 39,
    minima of 6 runs on a loaded machine). No `clear` command shows a SciPy docstring;
    the decorator's other work (its table of capabilities) is left as it is, and so is
    every other use of FunctionDoc in SciPy. The decorator does
    ``str(FunctionDoc(f)).split("\\n", 1)[1].lstrip(" \\n")`` (the first line is the
    signature): so str() is a blank first line, then the docstring."""

    def __init__(self, func: Any) -> None:
        self._doc = getattr(func, "__doc__", None) or ""

    def __getitem__(self, section: str) -> list[str]:
        return []  # a section to append to; what is appended is dropped

    def __setitem__(self, section: str, value: Any) -> None:
        pass

    def __str__(self) -> str:
        return "\n" + self._doc


def _keep_scipy_docstrings(module: ModuleType) -> None:
    if hasattr(module, "xp_capabilities") and hasattr(module, "FunctionDoc"):
        setattr(module, "FunctionDoc", _DocstringKept)  # noqa: B010  (a module mypy does not know)


class _PatchedAfterExec:
    """A module's own loader, then ``patch`` on the module it ran; anything else asked of
    the loader (get_source, resource readers ...) goes to its own."""

    def __init__(self, loader: Any, patch: Callable[[ModuleType], None]) -> None:
        self._loader = loader
        self._patch = patch

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType | None:
        module: ModuleType | None = self._loader.create_module(spec)
        return module

    def exec_module(self, module: ModuleType) -> None:
        self._loader.exec_module(module)
        self._patch(module)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._loader, name)


class _LighterImports:
    """Finds `DEFERRED_MODULES`, `DEFERRED_PACKAGES` and `PATCHED_MODULES` as the path
    finder does, with a lazy loader, a deferred package's or a patch after its code around
    their own loader. (A meta-path finder by its method alone: importlib.abc costs ~10 ms
    to import.)"""

    def find_spec(self, fullname: str, path: Any = None, target: Any = None) -> importlib.machinery.ModuleSpec | None:
        if (
            fullname not in DEFERRED_MODULES
            and fullname not in DEFERRED_PACKAGES
            and fullname not in DEFERRED_CODE_MODULES
            and fullname not in PATCHED_MODULES
        ):
            return None
        spec = importlib.machinery.PathFinder.find_spec(fullname, path)
        if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
            return spec
        if fullname in DEFERRED_MODULES:
            spec.loader = importlib.util.LazyLoader(spec.loader)
        elif fullname in DEFERRED_CODE_MODULES:
            spec.loader = _DeferredLoader(spec.loader)  # type: ignore[assignment]  # a Loader by its methods
        elif fullname in DEFERRED_PACKAGES:
            if spec.submodule_search_locations is None:
                return spec  # not a package: nothing to import without its code
            spec.loader = _DeferredLoader(spec.loader)  # type: ignore[assignment]  # a Loader by its methods
        else:
            # a Loader by its methods (importlib.abc costs ~10 ms to import)
            spec.loader = _PatchedAfterExec(spec.loader, PATCHED_MODULES[fullname])  # type: ignore[assignment]
        return spec


def lighten_imports() -> None:
    if not any(isinstance(finder, _LighterImports) for finder in sys.meta_path):
        sys.meta_path.insert(0, _LighterImports())


# Dataclasses' generated methods, compiled once per user (issue 39). The dataclass
# decorator writes each class's __init__, __repr__, __eq__, __hash__, __setattr__ ... as
# source text and compiles it with `exec` when the class is defined: ~500 texts in a
# `clear plan`, and compiling them was ~90 % of the ~100 ms its dataclasses took on a
# loaded machine. `_cache_dataclass_code` gives the dataclasses module an `exec` (its
# globals' name shadows the builtin) that runs, for a text it compiled before, the code
# compiled then: the same text compiled the same way (file "<string>", no future
# features inherited: as dataclasses' own exec compiles it) is the same code, so the
# classes are the very ones they were. The code is kept in one file under the user's
# cache directory, by a digest of its text, for this Python's bytecode (cache_tag and
# marshal's version in its name); written whole to a temporary file and renamed (a
# reader sees the old file or the new one), rewritten at exit only when some text was
# new; a file that cannot be read or decoded is as none (recompiled, then replaced).
# As with .pyc files, none is written when Python is told not to (PYTHONDONTWRITEBYTECODE).
_CODE_CACHE_FORMAT = 1
_CODE_CACHE_MAX = 2000  # texts kept at most (~1 ms to read 500): past it, a rewrite keeps this process's only


def _code_cache_path() -> str | None:
    # a relative XDG_CACHE_HOME is ignored, as the XDG spec says: it would put the file in
    # whatever folder clear runs in
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    base = xdg if os.path.isabs(xdg) else os.path.join(os.path.expanduser("~"), ".cache")
    tag = sys.implementation.cache_tag
    if not os.path.isabs(base) or tag is None:  # no home ("~" unexpanded): no cache
        return None
    # the bytecode's magic number too: it can change between releases of one minor version
    magic = importlib.util.MAGIC_NUMBER.hex()
    name = f"dataclass-code.{tag}.{magic}.m{marshal.version}.v{_CODE_CACHE_FORMAT}"
    return os.path.join(base, "clear", name)


class _CachedExec:
    """dataclasses' `exec`: source text it compiled before runs as the code compiled
    then; anything else is the builtin's."""

    def __init__(self, path: str) -> None:
        self.path = path
        self.codes: dict[bytes, Any] = {}
        self.used: set[bytes] = set()
        self.new = 0
        self._builtin_exec = exec
        try:
            # read whole, then decoded: marshal.load(f) reads the file piece by piece, one
            # call per object (~10 ms for a plan's ~500 texts; this ~1 ms, the same objects)
            with open(path, "rb") as f:
                loaded = marshal.loads(f.read())
            if isinstance(loaded, dict):
                self.codes = {k: v for k, v in loaded.items() if isinstance(k, bytes) and _is_code(v)}
        except Exception:  # none yet, unreadable, truncated, not marshal's: as none
            self.codes = {}

    def __call__(self, source: Any, globals: Any = None, locals: Any = None, /) -> None:  # noqa: A002
        if not isinstance(source, str):
            self._builtin_exec(source, globals, locals)
            return
        import _blake2  # noqa: PLC0415  (an extension module: only where a dataclass is made)

        key = _blake2.blake2b(source.encode("utf-8"), digest_size=20).digest()
        code = self.codes.get(key)
        if code is None:
            # as exec compiles a string in dataclasses' frame: no future feature of ours
            code = compile(source, "<string>", "exec", dont_inherit=True)
            self.codes[key] = code
            self.new += 1
        self.used.add(key)
        self._builtin_exec(code, globals, locals)

    def save(self) -> None:
        if not self.new or sys.dont_write_bytecode:
            return
        keep = self.codes
        if len(keep) > _CODE_CACHE_MAX:
            keep = {k: v for k, v in keep.items() if k in self.used}
        tmp = f"{self.path}.{os.getpid()}.tmp"
        try:
            os.makedirs(os.path.dirname(self.path), exist_ok=True)
            with open(tmp, "wb") as f:
                marshal.dump(keep, f)
            os.replace(tmp, self.path)
        except OSError:  # a read-only or full disk: the next process compiles them again
            try:
                os.unlink(tmp)
            except OSError:
                pass


def _is_code(value: Any) -> bool:
    return type(value).__name__ == "code"


def _cache_dataclass_code(module: ModuleType) -> None:
    path = _code_cache_path()
    if path is None or isinstance(getattr(module, "exec", None), _CachedExec):
        return
    cached = _CachedExec(path)
    setattr(module, "exec", cached)  # noqa: B010  (shadows the builtin in its module)
    atexit.register(cached.save)


def cache_dataclass_code() -> None:
    """The dataclass code cache in a process whose `dataclasses` module was imported
    before `lighten_imports` could patch it: a batch's worker, where multiprocessing and
    the pool's own module import it first. Without this each worker compiled again the
    ~500 texts of the classes its first frame defines (issue 39). Nothing when the module
    is not imported yet (`lighten_imports` patches it then) or is patched already."""
    module = sys.modules.get("dataclasses")
    if module is not None:
        _cache_dataclass_code(module)


# Modules patched right after their own code ran, before anything uses them.
PATCHED_MODULES: dict[str, Callable[[ModuleType], None]] = {
    "scipy._lib._array_api": _keep_scipy_docstrings,
    "dataclasses": _cache_dataclass_code,
}


# Python's cyclic garbage collector while a frame command loads its libraries (issue 39).
# Loading typer, NumPy, SciPy and clear's modules makes ~100 000 objects (modules,
# classes, functions), all kept to the end; the collector ran ~80 times over them in a
# cold `clear plan` (~14 ms of CPU on a loaded machine), finding nothing to free (a whole
# plan leaves no cyclic garbage at all). `pause_collection` stops it until the command
# reads its frame (`resume_collection`, from clearcli/pipeline.py `read`, or a batch's
# parent before its run): what was made until then is moved out of the collector's sight
# (gc.freeze: never scanned again, as objects that live as long as the process), and the
# collector runs as before on what the work makes. Only in a process that has not loaded
# NumPy yet (a fresh `clear`): a test or a program calling `main` again is left alone.
_collection_paused = False


def pause_collection() -> None:
    global _collection_paused
    if gc.isenabled() and "numpy" not in sys.modules:
        gc.disable()
        _collection_paused = True


def resume_collection(freeze: bool = True) -> None:
    """The collector back on after `pause_collection` (else nothing): with ``freeze``, what
    exists now is never scanned again."""
    global _collection_paused
    if _collection_paused:
        _collection_paused = False
        if freeze:
            gc.freeze()
        gc.enable()
