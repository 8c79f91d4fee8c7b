"""Cold start of `clear`: wall time per command, each run a fresh process, and the
share of it spent importing.

    .venv/bin/python benchmarks/startup.py [--runs N] [--no-imports] [--top K] [--against DIR] [--frame F]

Commands timed (FRAME = --frame, by default mosd/test/test57.pcd of the shared data:
mOSD's most cluttered 640x480 frame, so the most work after the imports): `clear --help`,
`clear info FRAME`, `clear segment FRAME`, `clear predicates FRAME`, `clear plan FRAME`.
Every run is a new process of the venv's `clear` script (stdout and stderr discarded);
one untimed run per command first warms the page cache. The commands' runs are
interleaved; printed are the median and min wall time of N runs and the median CPU time
(user + system of the process and its children, helper threads included, so it can
exceed the wall time) and the median of CPU / wall per run (issue 39's target for a single
call: at most 1.05; a loaded machine lowers it, as the process waits for a core). Other work on the machine inflates both: the load average is
printed before and after.

Import share: the modules a command imports are taken from one `-X importtime` run of
it (the top-level entries after `site`, in import order); a fresh process that imports
only those modules (after what clear's main does first: one BLAS thread, NumPy's unused
tooling deferred) is timed the same way ("imports", median of N); "work" is the wall
median minus that. The heaviest top-level imports (cumulative ms from -X importtime,
which adds its own overhead) are listed per command. "python" is a bare
`python -c pass`, for scale.

A note is printed when some of clearcli's modules have no up-to-date bytecode (e.g.
PYTHONDONTWRITEBYTECODE set with an editable install whose sources were edited since):
every run then compiles those it imports from source.

--against DIR measures another version of clearcli back to back with this one: DIR is a
folder holding a `clearcli` package (an older checkout, or `git archive REV clearcli`
unpacked), put first on PYTHONPATH for its runs. Each run then starts both versions of
each command one after the other (which goes first alternates), so that the load of a
busy machine falls on both alike; its rows are marked with "*".

Shared data: $CLEAR_SHARED, else ../shared/data beside the repository.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path


def _shared() -> Path:
    env = os.environ.get("CLEAR_SHARED")
    return Path(env) if env else Path(__file__).resolve().parent.parent.parent / "shared" / "data"


def _clear_cmd() -> list[str]:
    """How to start `clear`: [python, script] for the venv's console script (what users
    run; started through this interpreter so -X importtime can be added), else
    [python, -m, clearcli.cli]."""
    script = Path(sys.executable).parent / "clear"
    if script.is_file():
        return [sys.executable, str(script)]
    return [sys.executable, "-m", "clearcli.cli"]


def _run(argv: list[str], env: dict[str, str] | None = None) -> tuple[float, float, int]:
    """(wall s, CPU s of the process and its children, exit code)."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return wall, cpu, proc.returncode


def _imports(
    clear: list[str], args: list[str], env: dict[str, str] | None = None
) -> tuple[list[str], list[tuple[float, str]]]:
    """The top-level modules a command imports after `site` (in order), and their
    cumulative ms."""
    proc = subprocess.run(
        [clear[0], "-X", "importtime", *clear[1:], *args],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    names: list[str] = []
    costs: list[tuple[float, str]] = []
    children: list[tuple[float, str]] = []  # level-1 entries of the next top-level one
    after_site = False
    for line in proc.stderr.splitlines():
        if not line.startswith("import time:") or "cumulative" in line:
            continue
        _, cum, name = line[len("import time:") :].split("|")
        level = (len(name) - len(name.lstrip(" ")) - 1) // 2
        ms = int(cum) / 1000.0
        name = name.strip()
        if level == 1:
            children.append((ms, name))
        if level != 0:
            continue
        if not after_site:  # site, and what it imports, run before any command anyway
            after_site = name == "site"
        else:
            names.append(name)
            # clearcli.cli holds typer and the command modules: list those instead
            costs.extend(children if name == "clearcli.cli" else [(ms, name)])
        children = []
    return names, costs


def _bytecode_note() -> str | None:
    """A warning when clearcli's modules are compiled from source on a start: a module
    without bytecode, or whose bytecode is older than its source (edited since, with
    PYTHONDONTWRITEBYTECODE set the cache is never refreshed: issue 39 measured 15 such
    modules adding ~0.1 s to a cold `clear plan`)."""
    import importlib.util

    spec = importlib.util.find_spec("clearcli")
    if spec is None or spec.origin is None:
        return None
    package = Path(spec.origin).parent
    sources = sorted(package.rglob("*.py"))
    stale = [p for p in sources if not _bytecode_fresh(p)]
    if not stale:
        return None
    why = " (PYTHONDONTWRITEBYTECODE is set)" if os.environ.get("PYTHONDONTWRITEBYTECODE") else ""
    return (
        f"note: {len(stale)} of clearcli's {len(sources)} modules have no up-to-date bytecode{why}: a run "
        f"compiles those it imports from source; `{Path(sys.executable).name} -m compileall -q {package}` "
        "would save that time"
    )


def _bytecode_fresh(source: Path) -> bool:
    """Whether ``source`` has bytecode its import would use (a timestamp-based .pyc whose
    recorded mtime and size are the source's, or a hash-based one)."""
    import importlib.util

    try:
        header = Path(importlib.util.cache_from_source(str(source))).read_bytes()[:16]
        st = source.stat()
    except OSError:
        return False
    if len(header) < 16 or header[:4] != importlib.util.MAGIC_NUMBER:
        return False
    if int.from_bytes(header[4:8], "little") != 0:
        return True  # hash-based: checked (or not) by its own rule
    mtime = int.from_bytes(header[8:12], "little")
    size = int.from_bytes(header[12:16], "little")
    return mtime == int(st.st_mtime) & 0xFFFFFFFF and size == st.st_size & 0xFFFFFFFF


def _import_only_argv(modules: list[str]) -> list[str]:
    # what `clear`'s main does before its first import (clearcli/cli.py): one BLAS
    # thread, the import hooks (_lighten_imports; _defer_numpy_tooling before issue 39's
    # rename, so that an older checkout is measured the same way); without them the
    # imports would cost more here than in the command
    code = (
        "import importlib\n"
        "try:\n"
        "    from clearcli import cli\n"
        "    cli._single_threaded_numerics()\n"
        "    (getattr(cli, '_lighten_imports', None) or getattr(cli, '_defer_numpy_tooling'))()\n"
        "except (ImportError, AttributeError):\n"
        "    pass\n"
        f"for m in {modules!r}:\n"
        "    try:\n"
        "        importlib.import_module(m)\n"
        "    except Exception:\n"
        "        pass\n"
    )
    return [sys.executable, "-c", code]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=7, help="fresh processes per command (default 7)")
    ap.add_argument("--no-imports", action="store_true", help="skip the import-share measurement")
    ap.add_argument("--top", type=int, default=6, help="heaviest top-level imports listed per command")
    ap.add_argument(
        "--against", type=Path, help="a folder holding another clearcli package: measured back to back, rows marked *"
    )
    ap.add_argument(
        "--frame",
        default="mosd/test/test57.pcd",
        help="the frame the frame commands read: a path, or one relative to the shared data "
        "(default mosd/test/test57.pcd, mOSD's most cluttered 640x480 frame: 16 objects)",
    )
    opts = ap.parse_args()
    runs = max(1, opts.runs)

    data = _shared()
    frame = Path(opts.frame) if Path(opts.frame).is_file() else data / opts.frame
    if not frame.is_file():
        sys.exit(
            f"startup.py: frame not found: {frame} is missing.\n"
            "Set CLEAR_SHARED to the shared data directory (the one holding mosd/test/test57.pcd), "
            "or give --frame an existing file."
        )
    # (mark, environment): this checkout as the environment has it, and --against's
    versions: list[tuple[str, dict[str, str] | None]] = [("", None)]
    if opts.against is not None:
        against = opts.against.resolve()
        if not (against / "clearcli" / "__init__.py").is_file():
            sys.exit(f"startup.py: --against {against}: no clearcli package in it")
        path = os.pathsep.join(p for p in (str(against), os.environ.get("PYTHONPATH", "")) if p)
        versions.append(("*", dict(os.environ, PYTHONPATH=path)))

    clear = _clear_cmd()
    commands: list[tuple[str, list[str]]] = [
        ("--help", ["--help"]),
        ("info", ["info", str(frame)]),
        ("segment", ["segment", str(frame)]),
        ("predicates", ["predicates", str(frame)]),
        ("plan", ["plan", str(frame)]),
    ]
    load0 = os.getloadavg()[0]
    print(f"clear: {' '.join(clear)}\nframe: {frame}\nruns: {runs}   cpus: {os.cpu_count()}")
    if opts.against is not None:
        print(f"*: clearcli from {opts.against.resolve()}")

    rows = [(label + mark, args, env) for label, args in commands for mark, env in versions]
    import_argv: dict[str, list[str]] = {}
    top: dict[str, list[tuple[float, str]]] = {}
    if not opts.no_imports:
        for key, args, env in rows:
            names, costs = _imports(clear, args, env)
            import_argv[key] = _import_only_argv(names)
            top[key] = sorted(costs, reverse=True)[: opts.top]

    walls: dict[str, list[float]] = {key: [] for key, _, _ in rows}
    cpus: dict[str, list[float]] = {key: [] for key, _, _ in rows}
    imps: dict[str, list[float]] = {key: [] for key, _, _ in rows}
    codes: dict[str, set[int]] = {key: set() for key, _, _ in rows}
    bare: list[float] = []
    for _, args, env in rows:  # warm-up: page cache
        _run(clear + args, env)
    for run in range(runs):
        bare.append(_run([sys.executable, "-c", "pass"])[0])
        for label, args in commands:
            # both versions of a command back to back, which goes first alternating
            for mark, env in versions if run % 2 == 0 else versions[::-1]:
                key = label + mark
                wall, cpu, rc = _run(clear + args, env)
                walls[key].append(wall)
                cpus[key].append(cpu)
                codes[key].add(rc)
                if key in import_argv:
                    imps[key].append(_run(import_argv[key], env)[0])
    load1 = os.getloadavg()[0]

    print(f"load average (1 min) before {load0:.2f}, after {load1:.2f}")
    note = _bytecode_note()
    if note:
        print(note)
    print()
    print(
        f"{'command':<12} {'wall med':>9} {'min':>7} {'cpu med':>8} {'cpu/wall':>8} {'imports':>8} {'share':>6} "
        f"{'work':>7}  exit"
    )
    print(f"{'python':<12} {statistics.median(bare):9.3f} {min(bare):7.3f}")
    for key, _, _ in rows:
        w = statistics.median(walls[key])
        ratio = statistics.median(c / max(wall, 1e-9) for c, wall in zip(cpus[key], walls[key]))
        line = f"{key:<12} {w:9.3f} {min(walls[key]):7.3f} {statistics.median(cpus[key]):8.3f} {ratio:8.2f}"
        if imps[key]:
            i = statistics.median(imps[key])
            line += f" {i:8.3f} {100 * i / w:5.0f}% {w - i:7.3f}"
        else:
            line += " " * 23
        line += "  " + ",".join(str(c) for c in sorted(codes[key]))
        print(line)
    print("(seconds; wall: a fresh `clear` process; imports: a fresh process importing only what it imports)")
    if top:
        print("\nheaviest top-level imports (-X importtime cumulative, ms):")
        for key, _, _ in rows:
            print(f"  {key:<11} " + ", ".join(f"{name} {ms:.0f}" for ms, name in top[key]))


if __name__ == "__main__":
    main()
