"""What every `clear` process does before it imports NumPy: a single `clear` call
(clearcli/cli.py `main`) and each worker of a batch (clearcli/batch/pool.py), which is a
fresh interpreter (spawned) that does not run `main`.

`single_threaded_numerics` sets the numeric libraries' thread pools to one thread;
`lighten_imports` defers NumPy's and SciPy's modules clear never uses and keeps SciPy
from parsing docstrings (issue 39). Both only change what a process loads and how fast,
never a result. Standard library only: this runs before anything heavy is imported.
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
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


# Modules patched right after their own code ran, before anything uses them.
PATCHED_MODULES: dict[str, Callable[[ModuleType], None]] = {"scipy._lib._array_api": _keep_scipy_docstrings}


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
    """Finds `DEFERRED_MODULES` and `PATCHED_MODULES` as the path finder does, with a
    lazy loader or a patch after its code around their own loader. (A meta-path finder
    by its method alone: importlib.abc costs ~10 ms to import.)"""

    def find_spec(self, fullname: str, path: Any = None, target: Any = None) -> importlib.machinery.ModuleSpec | None:
        if fullname not in DEFERRED_MODULES and fullname not in PATCHED_MODULES:
            return None
        spec = importlib.machinery.PathFinder.find_spec(fullname, path)
        if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
            return spec
        if fullname in DEFERRED_MODULES:
            spec.loader = importlib.util.LazyLoader(spec.loader)
        else:
            # a Loader by its methods (importlib.abc costs ~10 ms to import)
            spec.loader = _PatchedAfterExec(spec.loader, PATCHED_MODULES[fullname])  # type: ignore[assignment]
        return spec


def lighten_imports() -> None:
    if not any(isinstance(finder, _LighterImports) for finder in sys.meta_path):
        sys.meta_path.insert(0, _LighterImports())
