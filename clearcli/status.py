"""Status values, one home each: what a replayed frame came to, and what a plan does.

String enums: they compare equal to their values and print as them in JSON, so the
schemas keep the words they always had."""

from __future__ import annotations

from enum import StrEnum


class FrameStatus(StrEnum):
    """One frame of a replay or simulation, in the order a replay reports them."""

    OK = "ok"  # planned: the plan's first action is what the robot would do next
    CLEARED = "cleared"  # the table holds no object: nothing left to do
    NO_TABLE = "no_table"  # no usable table in the frame: skipped
    NO_PLAN = "no_plan"  # objects remain but no action can be taken (reason in the error)
    FAILED = "failed"  # a stage failed on this frame (error says which and why)


class PlanStatus(StrEnum):
    COMPLETE = "complete"  # every object removed (an empty table included)
    PARTIAL = "partial"  # some removed; the others left, each with its reason
    NO_PLAN = "no_plan"  # no object can be removed
