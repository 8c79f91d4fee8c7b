"""The versions of the planning layer's JSON schemas, in a module that imports nothing:
`clear plan --help` names the version the documents carry without loading the planner.
A key removed, renamed or changed in meaning raises its schema's version."""

from __future__ import annotations

# version 1 had no grasp kinds beyond the pinch (objects' "grasp_kinds", "not_offered")
PREDICATES_SCHEMA, PREDICATES_VERSION = "predicates", 2
# version 1 had no status/left, and its optimal and steps meant less; version 2 had no
# robot block and no gripper poses per step; version 3 no grasp kind per step; version 4 no
# "assumes" (a plan found only as light as a cracker box, the cup's own hold: tasks/plan.py)
PLAN_SCHEMA, PLAN_VERSION = "plan", 5
