"""Run the real Fast Downward (the one the up-fast-downward wheel ships) on PDDL text.

Each call works in its own temporary directory (the translator writes ``output.sas`` and
the search ``sas_plan*`` into the working directory; batch scripts run many `clear`
processes at once), under a time limit, in its own process group so a time-out kills the
translator and the search binary together.
"""

from __future__ import annotations

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


def find_fast_downward() -> Path:
    """Path of the wheel's ``fast-downward.py`` driver, or PlannerError with a hint."""
    try:
        import importlib.util

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
    return driver


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
    heuristic, false for aliases). Raises PlannerError on time-out without a plan, on a
    crash, or when Fast Downward is missing; an unsolvable task is a normal result.
    """
    driver = find_fast_downward()
    if optimal is None:
        optimal = alias is None and search is not None and search.startswith("astar(")
    config = alias or search or ""
    # The driver takes whole seconds of CPU time and gives each component what is left
    # after its own start-up, rounded down: below 2 s the translator would get 0 s.
    limit = max(2, int(math.ceil(time_limit_s)))
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="clear-fd-") as tmp:
        tmpdir = Path(tmp)
        (tmpdir / "domain.pddl").write_text(domain, encoding="utf-8")
        (tmpdir / "problem.pddl").write_text(problem, encoding="utf-8")
        cmd = [sys.executable, str(driver), "--overall-time-limit", f"{limit}s", "--plan-file", "sas_plan"]
        if alias:
            cmd += ["--alias", alias, "domain.pddl", "problem.pddl"]
        else:
            cmd += ["domain.pddl", "problem.pddl", "--search", str(search)]
        env = dict(os.environ)
        env.pop("PYTHONPATH", None)
        try:
            proc = subprocess.Popen(
                cmd,
                cwd=tmpdir,
                stdout=subprocess.PIPE,
                stderr=subprocess.STDOUT,
                text=True,
                env=env,
                start_new_session=True,  # its own process group: killable as a whole
            )
        except OSError as exc:
            raise PlannerError(f"cannot start Fast Downward ({exc}); {INSTALL_HINT}") from None
        try:
            # The driver enforces the limit itself (CPU time); the wall-clock backstop
            # catches a stuck translator on a loaded machine.
            out, _ = proc.communicate(timeout=limit * 2 + 10)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
            raise PlannerError(
                f"Fast Downward ({config}) did not finish within {time_limit_s:g} s; "
                "raise --time-limit or [plan] time_limit_s"
            ) from None
        elapsed = time.perf_counter() - t0
        code = proc.returncode
        plans = sorted(
            tmpdir.glob("sas_plan*"),
            key=lambda p: int(p.suffix[1:]) if p.suffix[1:].isdigit() else 0,
        )
        # An anytime search stopped by the time limit leaves its best plan so far; a plan
        # file is whole once its closing cost line is written.
        plans = [p for p in plans if "cost =" in p.read_text(encoding="utf-8")]
        # A component killed by its CPU limit (SIGXCPU) leaves the driver with 256 - 24.
        cpu_killed = code in (-24, 232) or "exit code: -24" in out
        if code == _SUCCESS or (plans and (code in _PLAN_AND_OUT or code in _OUT_OF_TIME or cpu_killed)):
            if not plans:
                raise PlannerError(f"Fast Downward ({config}) reported success but wrote no plan")
            steps, cost = _parse_plan(plans[-1].read_text(encoding="utf-8"))
            return DownwardResult(
                solved=True,
                steps=steps,
                cost=len(steps) if cost is None else cost,
                optimal=bool(optimal and code == _SUCCESS and alias is None),
                unsolvable=False,
                time_s=elapsed,
                config=config,
                exit_code=code,
            )
        if code in _UNSOLVABLE:
            return DownwardResult(False, (), 0, False, True, elapsed, config, code)
        tail = " | ".join(line for line in out.strip().splitlines()[-3:])
        if code in _OUT_OF_TIME or cpu_killed or (code == _INCOMPLETE and elapsed >= limit):
            raise PlannerError(
                f"Fast Downward ({config}) timed out after {time_limit_s:g} s without a plan; "
                "raise --time-limit or [plan] time_limit_s"
            )
        if code in _OUT_OF_MEMORY:
            raise PlannerError(f"Fast Downward ({config}) ran out of memory")
        if code < 0:
            raise PlannerError(f"Fast Downward ({config}) was killed by signal {-code}: {tail}")
        raise PlannerError(f"Fast Downward ({config}) failed with exit code {code}: {tail}")
