"""Run the real Fast Downward (the one the up-fast-downward wheel ships).

`run_downward` takes PDDL text and runs the whole planner through its Python driver
(translator + search); `run_sas` takes a SAS+ task we wrote ourselves (`planning.sas`)
and runs only the search binary, which saves the translator's start-up and re-grounding
(>= 0.1 s per call).

Each call works in its own temporary directory (the translator writes ``output.sas`` and
the search ``sas_plan*`` into the working directory; batch scripts run many `clear`
processes at once), under a wall-clock time limit, in its own process group so a
time-out kills the driver, the translator and the search binary together. An anytime
search stopped by the limit returns the best plan it has written (``timed_out=True``).
"""

from __future__ import annotations

import importlib.util
import math
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from clearcli.errors import PlannerError

try:
    import resource
except ImportError:  # not on every system (Windows): a search there has no CPU backstop
    _HAS_RESOURCE = False
else:
    _HAS_RESOURCE = True

# Search configurations (Fast Downward option strings), chosen by benchmarks/plan.py.
OPTIMAL = "astar(lmcut())"  # admissible: the plan is proven optimal
BLIND = "astar(blind())"
HMAX = "astar(hmax())"
ANYTIME_ALIAS = "seq-sat-lama-2011"  # LAMA: anytime, improves the plan until time runs out
FIRST_ALIAS = "lama-first"

INSTALL_HINT = (
    "Fast Downward not found: install it into clear's environment with "
    "`pip install up-fast-downward` (it ships the planner binary)"
)

# Driver exit codes (driver/returncodes.py).
_SUCCESS = 0
_PLAN_AND_OUT = (1, 2, 3)  # a plan was found, then memory/time ran out (anytime search)
_UNSOLVABLE = (10, 11)  # proved: no plan exists
_INCOMPLETE = 12  # search ended without a plan and without a proof
_OUT_OF_TIME = (21, 23, 24)
_OUT_OF_MEMORY = (20, 22)


@dataclass(frozen=True)
class DownwardResult:
    solved: bool
    steps: tuple[tuple[str, ...], ...]  # each step: (action name, args...) lower case
    cost: int
    optimal: bool  # proven optimal (admissible search finished)
    unsolvable: bool  # proven: no plan
    time_s: float
    config: str
    exit_code: int
    timed_out: bool = False  # stopped by the time limit (then the plan is the best so far)


def _downward_root() -> Path:
    """The wheel's ``downward`` directory (driver and binaries), or PlannerError."""
    try:
        spec = importlib.util.find_spec("up_fast_downward")
    except (ImportError, ValueError):
        spec = None
    if spec is None or not spec.origin:
        raise PlannerError(INSTALL_HINT)
    root = Path(spec.origin).parent / "downward"
    driver = root / "fast-downward.py"
    binary = root / "builds" / "release" / "bin" / "downward"
    if not driver.is_file() or not binary.is_file():
        raise PlannerError(INSTALL_HINT + f" (looked in {root})")
    return root


def find_fast_downward() -> Path:
    """Path of the wheel's ``fast-downward.py`` driver, or PlannerError with a hint."""
    return _downward_root() / "fast-downward.py"


def find_search_binary() -> Path:
    """Path of the wheel's search component (``builds/release/bin/downward``)."""
    return _downward_root() / "builds" / "release" / "bin" / "downward"


def _parse_plan(text: str) -> tuple[tuple[tuple[str, ...], ...], int | None]:
    steps: list[tuple[str, ...]] = []
    cost: int | None = None
    for line in text.splitlines():
        line = line.strip()
        if line.startswith("("):
            steps.append(tuple(line.strip("()").lower().split()))
        elif line.startswith(";"):
            m = re.search(r"cost\s*=\s*(\d+)", line)
            if m:
                cost = int(m.group(1))
    return tuple(steps), cost


def _default_optimal(search: str | None, alias: str | None) -> bool:
    return alias is None and search is not None and search.startswith("astar(")


def _clean_env() -> dict[str, str]:
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)
    return env


def _backstop_cpu_s(time_limit_s: float) -> int:
    """CPU seconds a run may use: well above the wall-clock limit (the single-threaded
    search uses at most as much CPU as wall time), so never the binding limit; it only
    ends processes whose parent died before it could kill them."""
    return int(math.ceil(time_limit_s)) + 5


def _cpu_backstop(pid: int, time_limit_s: float) -> None:
    """`_backstop_cpu_s` as RLIMIT_CPU of a directly started search."""
    if not _HAS_RESOURCE:
        return  # not a POSIX system
    try:
        soft = _backstop_cpu_s(time_limit_s)
        resource.prlimit(pid, resource.RLIMIT_CPU, (soft, soft + 5))
    except (AttributeError, OSError, ValueError):
        pass  # not Linux, or the process is gone already


def _kill_group(proc: subprocess.Popen[bytes]) -> None:
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass


def _execute(
    cmd: list[str],
    tmpdir: Path,
    *,
    stdin_path: Path | None,
    time_limit_s: float,
    config: str,
    optimal: bool,
    env: dict[str, str] | None = None,
    backstop: bool = False,
) -> DownwardResult:
    """Run ``cmd`` in ``tmpdir`` (own process group) under a wall-clock limit and read
    the plan files ``sas_plan*`` it leaves."""
    t0 = time.perf_counter()
    with open(stdin_path, "rb") if stdin_path is not None else open(os.devnull, "rb") as stdin:
        try:
            proc = subprocess.Popen(
                cmd,
                cwd=tmpdir,
                stdin=stdin,
                stdout=subprocess.PIPE,  # its end (EOF) wakes us at once, unlike wait()'s polling
                stderr=subprocess.STDOUT,
                env=env,
                start_new_session=True,  # its own process group: killable as a whole
            )
        except OSError as exc:
            raise PlannerError(f"cannot start Fast Downward ({exc}); {INSTALL_HINT}") from None
    if backstop:
        _cpu_backstop(proc.pid, time_limit_s)
    timed_out = False
    try:
        raw, _ = proc.communicate(timeout=max(0.0, time_limit_s - (time.perf_counter() - t0)))
    except subprocess.TimeoutExpired:
        timed_out = True
        _kill_group(proc)
        raw, _ = proc.communicate()
    except BaseException:  # KeyboardInterrupt and the like: leave nothing running
        _kill_group(proc)
        proc.communicate()
        raise
    elapsed = time.perf_counter() - t0
    code = proc.returncode
    out = (raw or b"").decode("utf-8", errors="replace")
    plans = sorted(
        tmpdir.glob("sas_plan*"),
        key=lambda p: int(p.suffix[1:]) if p.suffix[1:].isdigit() else 0,
    )
    # An anytime search stopped by the time limit leaves its best plan so far; a plan
    # file is whole once its closing cost line is written.
    plans = [p for p in plans if "; cost =" in p.read_text(encoding="utf-8")]
    # A component killed by its CPU limit (SIGXCPU) leaves the driver with 256 - 24.
    cpu_killed = code in (-24, 232) or "exit code: -24" in out
    out_of_time = timed_out or cpu_killed or code in _OUT_OF_TIME or code in (2, 3)
    if code == _SUCCESS or (plans and (out_of_time or code in _PLAN_AND_OUT)):
        if not plans:
            raise PlannerError(f"Fast Downward ({config}) reported success but wrote no plan")
        steps, cost = _parse_plan(plans[-1].read_text(encoding="utf-8"))
        return DownwardResult(
            solved=True,
            steps=steps,
            cost=len(steps) if cost is None else cost,
            optimal=bool(optimal and code == _SUCCESS and not timed_out),
            unsolvable=False,
            time_s=elapsed,
            config=config,
            exit_code=code,
            timed_out=timed_out or (code != _SUCCESS and out_of_time),
        )
    if code in _UNSOLVABLE and not timed_out:
        return DownwardResult(False, (), 0, False, True, elapsed, config, code)
    tail = " | ".join(line for line in out.strip().splitlines()[-3:])
    if out_of_time or (code == _INCOMPLETE and elapsed >= time_limit_s):
        raise PlannerError(
            f"Fast Downward ({config}) timed out after {time_limit_s:g} s without a plan; "
            "raise --time-limit or [plan] time_limit_s"
        )
    if code in _OUT_OF_MEMORY:
        raise PlannerError(f"Fast Downward ({config}) ran out of memory")
    if code < 0:
        raise PlannerError(f"Fast Downward ({config}) was killed by signal {-code}: {tail}")
    raise PlannerError(f"Fast Downward ({config}) failed with exit code {code}: {tail}")


def run_downward(
    domain: str,
    problem: str,
    *,
    search: str | None = OPTIMAL,
    alias: str | None = None,
    time_limit_s: float = 30.0,
    optimal: bool | None = None,
) -> DownwardResult:
    """Translate + search ``domain``/``problem`` (PDDL text).

    ``search`` is a Fast Downward search option (e.g. ``astar(lmcut())``); or give
    ``alias`` (e.g. ``seq-sat-lama-2011``) instead. ``optimal`` says whether a finished
    search proves optimality (default: true for ``astar(...)`` with an admissible
    heuristic, false for aliases). ``time_limit_s`` is wall-clock time for translation
    and search together; when it runs out, an anytime search's best plan so far is
    returned (``timed_out=True``, not optimal). Raises PlannerError on time-out without a
    plan, on a crash, or when Fast Downward is missing; an unsolvable task is a normal
    result.
    """
    driver = find_fast_downward()
    if optimal is None:
        optimal = _default_optimal(search, alias)
    config = alias or search or ""
    # The driver's own limit is CPU time in whole seconds (and each component gets what
    # is left after the ones before it, rounded down): only a backstop here.
    with tempfile.TemporaryDirectory(prefix="clear-fd-") as tmp:
        tmpdir = Path(tmp)
        (tmpdir / "domain.pddl").write_text(domain, encoding="utf-8")
        (tmpdir / "problem.pddl").write_text(problem, encoding="utf-8")
        return _run_driver(
            driver,
            ["domain.pddl", "problem.pddl"],
            tmpdir,
            alias=alias,
            search=search,
            time_limit_s=time_limit_s,
            config=config,
            optimal=bool(optimal and alias is None),
        )


def _run_driver(
    driver: Path,
    inputs: list[str],
    tmpdir: Path,
    *,
    alias: str | None,
    search: str | None,
    time_limit_s: float,
    config: str,
    optimal: bool,
) -> DownwardResult:
    """The driver on ``inputs`` (PDDL files, or one .sas file: then it only searches)."""
    cpu_limit = _backstop_cpu_s(time_limit_s)
    cmd = [sys.executable, str(driver), "--overall-time-limit", f"{cpu_limit}s", "--plan-file", "sas_plan"]
    if alias:
        cmd += ["--alias", alias, *inputs]
    else:
        cmd += [*inputs, "--search", str(search)]
    return _execute(
        cmd, tmpdir, stdin_path=None, time_limit_s=time_limit_s, config=config, optimal=optimal, env=_clean_env()
    )


def run_sas(
    sas_text: str,
    *,
    search: str | None = OPTIMAL,
    alias: str | None = None,
    time_limit_s: float = 30.0,
    optimal: bool | None = None,
) -> DownwardResult:
    """Search a SAS+ task (translator-output format, e.g. `sas.compile_sas(...).text`).

    With ``search`` (a search option string) the search binary runs directly, the task
    on its stdin: no Python driver, no translator. With ``alias`` (e.g.
    ``seq-sat-lama-2011``, whose option string the driver expands) the driver runs with
    the ``.sas`` file as its only input, which makes it skip translation.
    ``time_limit_s`` is wall-clock time (may be fractional); on expiry the process group
    is killed and an anytime search's best complete plan is returned (``timed_out=True``,
    ``optimal=False``); without one PlannerError "timed out". Other outcomes as
    `run_downward`: unsolvable proved -> ``unsolvable=True``; out of memory, crash or
    missing Fast Downward -> PlannerError.
    """
    if optimal is None:
        optimal = _default_optimal(search, alias)
    config = alias or search or ""
    if not alias and not search:
        raise ValueError("run_sas needs a search option or an alias")
    with tempfile.TemporaryDirectory(prefix="clear-fd-") as tmp:
        tmpdir = Path(tmp)
        sas_path = tmpdir / "output.sas"
        sas_path.write_text(sas_text, encoding="utf-8")
        if alias:
            return _run_driver(
                find_fast_downward(),
                ["output.sas"],
                tmpdir,
                alias=alias,
                search=None,
                time_limit_s=time_limit_s,
                config=config,
                optimal=False,
            )
        binary = find_search_binary()
        cmd = [str(binary), "--search", str(search), "--internal-plan-file", "sas_plan"]
        return _execute(
            cmd,
            tmpdir,
            stdin_path=sas_path,
            time_limit_s=time_limit_s,
            config=config,
            optimal=bool(optimal),
            backstop=True,
        )
