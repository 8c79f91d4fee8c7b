"""Plans checked by an independent tool: unified-planning's validator reads the domain,
problem and plan files `clear` wrote with its own PDDL readers."""

from __future__ import annotations

from pathlib import Path


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
