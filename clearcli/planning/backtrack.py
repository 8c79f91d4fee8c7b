"""Planning with backtracking on IK (thesis Algorithm 1).

    repeat
        plan <- Fast Downward(state + ik facts, goal)
        check the first action: IK for every gripper pose of it, arm clear of the table
        and of the other objects
        if infeasible: add ik_unfeasible_grasp(o) / ik_unfeasible_dir(o, d)
            and when every action of o is IK-infeasible, drop o from the goal (unreachable)
    until the first action is feasible, or the goal is empty / unreachable

Two additions to the thesis's loop, both exact because the model is monotone (no action
ever makes a blocking or IK fact true, see compile.py):

* objects that no sequence of actions can free any more (say, blocked only by an
  unreachable object) are dropped from the goal as ``stuck`` instead of making the
  whole problem unsolvable; a frame where nothing can be removed is "no plan";
* objects whose width the gripper cannot take (``ungraspable``) are never in the goal,
  but can still be pushed out of the way.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Iterable, Mapping, Sequence

import numpy as np

from clearcli.errors import NoPlanError, PlannerError, SettingsError
from clearcli.planning import downward
from clearcli.planning.compile import compile_strips, removable_objects
from clearcli.planning.types import Action, BacktrackStep, CheckedAction, Plan
from clearcli.predicates.state import DIRECTIONS, Fact, SymbolicState

# check(action) -> (CheckedAction or None, reason when None)
Checker = Callable[[Action], tuple[CheckedAction | None, str]]


@dataclass(frozen=True)
class Solved:
    actions: tuple[Action, ...]
    cost: int
    optimal: bool
    config: str
    time_s: float


def solve(
    objects: Sequence[str],
    facts: Iterable[Fact],
    goal: Sequence[str],
    push_costs: Mapping[tuple[str, str], int] | None,
    *,
    time_limit_s: float = 30.0,
    optimal_max_objects: int = 40,
    optimal_time_s: float = 10.0,
    anytime_time_s: float = 5.0,
    formulation: str = "positive",
) -> Solved | None:
    """One Fast Downward plan for removing ``goal`` (None when proven impossible).

    Optimal A* + LM-cut up to ``optimal_max_objects`` goal objects, for at most
    ``optimal_time_s``; beyond that, or when the optimal search runs out of time, LAMA
    (anytime) within ``anytime_time_s``. Both capped by ``time_limit_s``.
    """
    if formulation not in ("positive", "negative"):
        raise SettingsError(f"settings: [plan] formulation must be \"positive\" or \"negative\", got {formulation!r}")
    if not goal:
        return Solved((), 0, True, "", 0.0)
    task = compile_strips(objects, facts, goal, push_costs, positive=formulation == "positive")
    result = None
    if len(goal) <= optimal_max_objects:
        try:
            result = downward.run_downward(
                task.domain,
                task.problem,
                search=downward.OPTIMAL,
                time_limit_s=min(optimal_time_s, time_limit_s),
            )
        except PlannerError as exc:
            if "timed out" not in str(exc):
                raise
            result = None
    if result is None:
        result = downward.run_downward(
            task.domain,
            task.problem,
            alias=downward.ANYTIME_ALIAS,
            time_limit_s=min(anytime_time_s, time_limit_s),
        )
    if result.unsolvable:
        return None
    actions: list[Action] = []
    removed: set[str] = set()
    cost = result.cost
    costs = push_costs or {}
    for step in result.steps:
        if step[0] not in task.actions:
            raise PlannerError(f"Fast Downward returned an unknown action {step[0]!r}")
        action = task.actions[step[0]]
        if action.obj in removed:
            # The grounded form leaves out the lifted domain's (not (removed ?o)): acting
            # on a removed object changes nothing that matters, so an anytime plan that
            # does it is the same plan without that step.
            cost -= 1 if action.kind == "grasp" else int(costs.get((action.obj, str(action.direction)), 1))
            continue
        if action.kind == "grasp":
            removed.add(action.obj)
        actions.append(action)
    return Solved(tuple(actions), cost, result.optimal, result.config, result.time_s)


def action_space(state_facts: frozenset[Fact], obj: str, directions: Sequence[str] = DIRECTIONS) -> list[Action]:
    """The actions the model allows for ``obj`` at all (static facts excluded)."""
    out = []
    if ("ungraspable", obj) not in state_facts:
        out.append(Action("grasp", obj))
    for d in directions:
        if ("push_off_table", obj, d) not in state_facts:
            out.append(Action("push", obj, d))
    return out


def backtrack(
    state: SymbolicState,
    check: Checker,
    *,
    time_limit_s: float = 30.0,
    optimal_max_objects: int = 40,
    optimal_time_s: float = 10.0,
    anytime_time_s: float = 5.0,
    max_backtracks: int = 200,
    formulation: str = "positive",
    goal_objects: Sequence[str] | None = None,
    precheck: Callable[[Action], str] | None = None,
) -> Plan:
    """Algorithm 1 with ``check`` as HASIKSOLUTION. Raises NoPlanError when nothing can be
    removed (with the reason and the partial result in ``error.plan``)."""
    t_start = time.perf_counter()
    names = state.names()
    facts = frozenset(state.facts)
    ungraspable = tuple(o for o in names if ("ungraspable", o) in facts)
    goal = [o for o in (goal_objects if goal_objects is not None else names) if o not in ungraspable]
    ik_facts: set[Fact] = set()
    unreachable: list[str] = []
    stuck: list[str] = []
    steps: list[BacktrackStep] = []
    timings = {"planner_s": 0.0, "ik_s": 0.0}
    reasons: dict[str, str] = {}

    def refresh_goal() -> None:
        # Objects whose every allowed action is IK-infeasible are unreachable.
        for o in list(goal):
            space = action_space(facts, o)
            if all(a.ik_fact() in ik_facts for a in space):
                goal.remove(o)
                unreachable.append(o)
        # Objects no plan can remove any more (exact: the model is monotone).
        removable = removable_objects(names, facts | ik_facts, state.push_costs)
        for o in list(goal):
            if o not in removable:
                goal.remove(o)
                stuck.append(o)

    def partial(actions: tuple[Action, ...], cost: int, optimal: bool, first: CheckedAction | None, config: str) -> Plan:
        timings["total_s"] = time.perf_counter() - t_start
        return Plan(
            actions=actions,
            cost=cost,
            optimal=optimal,
            first=first,
            ik_facts=frozenset(ik_facts),
            unreachable=tuple(unreachable),
            replans=len(steps),
            timings_s=dict(timings),
            goal=tuple(goal),
            ungraspable=ungraspable,
            stuck=tuple(stuck),
            search=config,
            steps=tuple(steps),
        )

    if precheck is not None:
        # Cheap necessary conditions (reach) for every action, before any search: an
        # object far away is dropped without planning around it first.
        t0 = time.perf_counter()
        for o in names:
            for a in action_space(facts, o):
                why = precheck(a)
                if why:
                    ik_facts.add(a.ik_fact())
                    reasons.setdefault(o, why)
        timings["precheck_s"] = time.perf_counter() - t0
    refresh_goal()
    while True:
        if not goal:
            plan = partial((), 0, True, None, "")
            if not names:
                return plan  # an empty table is clear already
            why = _no_plan_reason(names, unreachable, stuck, ungraspable, reasons)
            err = NoPlanError(f"no plan: {why}")
            err.plan = plan  # type: ignore[attr-defined]
            raise err
        if len(steps) >= max_backtracks:
            raise PlannerError(
                f"backtracking gave up after {len(steps)} replans; raise [plan] max_backtracks"
            )
        t0 = time.perf_counter()
        solved = solve(
            names,
            facts | ik_facts,
            goal,
            state.push_costs,
            time_limit_s=time_limit_s,
            optimal_max_objects=optimal_max_objects,
            optimal_time_s=optimal_time_s,
            anytime_time_s=anytime_time_s,
            formulation=formulation,
        )
        timings["planner_s"] += time.perf_counter() - t0
        if solved is None:
            # Cannot happen after refresh_goal (the fixpoint is exact); guard anyway.
            raise PlannerError("Fast Downward proved the goal unsolvable although it is reachable")
        first_action = solved.actions[0]
        t0 = time.perf_counter()
        checked, reason = check(first_action)
        timings["ik_s"] += time.perf_counter() - t0
        steps.append(BacktrackStep(solved.actions, solved.cost, solved.optimal, checked is not None, reason))
        if checked is not None:
            return partial(solved.actions, solved.cost, solved.optimal, checked, solved.config)
        ik_facts.add(first_action.ik_fact())
        reasons[first_action.obj] = reason
        refresh_goal()


def _no_plan_reason(
    names: Sequence[str],
    unreachable: Sequence[str],
    stuck: Sequence[str],
    ungraspable: Sequence[str],
    reasons: Mapping[str, str],
) -> str:
    parts = []
    if unreachable:
        detail = "; ".join(f"{o}: {reasons[o]}" for o in unreachable if o in reasons)
        parts.append(f"out of the robot's reach: {', '.join(unreachable)}" + (f" ({detail})" if detail else ""))
    if stuck:
        parts.append(f"blocked by objects that cannot be moved: {', '.join(stuck)}")
    if ungraspable:
        parts.append(f"too wide or narrow for the gripper: {', '.join(ungraspable)}")
    if not parts:
        parts.append(f"none of {', '.join(names)} can be removed")
    return "; ".join(parts)


@dataclass
class IKActionChecker:
    """HASIKSOLUTION: every pose of some half-turn candidate of the action has an IK
    solution with the arm clear of the table and of the other objects."""

    state: SymbolicState
    T_base_camera: np.ndarray
    kin: object
    obstacles: object
    per_action_s: list[float] = field(default_factory=list)
    # check that a pushed object can be grasped where the push leaves it
    push_lookahead: bool = False

    def poses(self, action: Action) -> tuple[tuple[np.ndarray, ...], ...]:
        from clearcli.robot.kinematics import half_turn

        obj = self.state.by_name(action.obj)
        if action.kind == "grasp":
            cands = tuple(obj.grasp_candidates)
        else:
            push = obj.pushes.get(str(action.direction))
            cands = tuple(push.candidates) if push is not None else ()
        if len(cands) == 1:  # the gripper is symmetric: its half-turn is as good
            cands = (cands[0], tuple(half_turn(T) for T in cands[0]))
        return tuple(tuple(self.T_base_camera @ np.asarray(T, dtype=float) for T in c) for c in cands)

    def beyond_reach(self, action: Action) -> str:
        """Non-empty when every candidate has a pose beyond the arm's reach."""
        cands = self.poses(action)
        if not cands:
            return "no gripper poses for this action"
        if all(any(not self.kin.reachable(T) for T in c) for c in cands):  # type: ignore[attr-defined]
            return "beyond the arm's reach"
        return ""

    def __call__(self, action: Action) -> tuple[CheckedAction | None, str]:
        from clearcli.robot.kinematics import SequenceChecker

        t0 = time.perf_counter()
        try:
            cands = self.poses(action)
            if not cands:
                return None, "no gripper poses for this action"
            checker = SequenceChecker(self.kin, self.obstacles)  # type: ignore[arg-type]
            reasons = []
            for i, poses in enumerate(cands):
                res = checker.check(poses, action.obj)
                if res.ok:
                    if action.kind == "push" and self.push_lookahead:
                        why = self.grasp_after_push(action, checker)
                        if why:
                            return None, why
                    return CheckedAction(action, poses, res.joints, i), ""
                reasons.append(res.reason)
            return None, min(reasons, key=_reason_rank)
        finally:
            self.per_action_s.append(time.perf_counter() - t0)

    def grasp_after_push(self, action: Action, checker: object) -> str:
        """Empty when some grasp candidate, moved by the push, has IK solutions clear of
        the other objects (as they stand now); else why not."""
        obj = self.state.by_name(action.obj)
        push = obj.pushes.get(str(action.direction))
        if push is None or not push.object_path or not obj.grasp_candidates:
            return ""
        shift = np.asarray(push.object_path[-1], dtype=float)
        reasons = []
        for cand in obj.grasp_candidates:
            moved = []
            for T in cand:
                T2 = np.array(T, dtype=float)
                T2[:3, 3] += shift
                moved.append(self.T_base_camera @ T2)
            res = checker.check(moved, action.obj)  # type: ignore[attr-defined]
            if res.ok:
                return ""
            reasons.append(res.reason)
        return f"the push leaves {action.obj} where it cannot be grasped ({min(reasons, key=_reason_rank)})"


def _reason_rank(reason: str) -> int:
    # Report the most telling failure among the half-turns.
    for rank, key in enumerate(("collides", "no IK", "beyond")):
        if key in reason:
            return rank
    return 3


def make_plan(state: SymbolicState, settings: object, T_base_camera: np.ndarray | None = None) -> Plan:
    """Plan for ``state`` (SymbolicState) with the WAM at ``T_base_camera`` (else from
    ``[robot] camera_pose`` or derived from the table, see clearcli/robot/placement.py)."""
    from clearcli.robot.kinematics import WamKinematics, make_obstacles
    from clearcli.robot.placement import placement_from_settings

    robot = settings.robot  # type: ignore[attr-defined]
    plan_s = settings.plan  # type: ignore[attr-defined]
    if T_base_camera is None:
        T_base_camera, _ = placement_from_settings(robot, state)
    T_base_camera = np.asarray(T_base_camera, dtype=float)
    kin = WamKinematics(
        damping=robot.ik_damping,
        max_iterations=robot.ik_max_iterations,
        tolerance_m=robot.ik_tolerance_m,
        tolerance_rad=robot.ik_tolerance_rad,
        n_seeds=robot.ik_seeds,
    )
    obstacles = make_obstacles(state, T_base_camera, robot.collision_margin_m)
    checker = IKActionChecker(state, T_base_camera, kin, obstacles, push_lookahead=plan_s.push_lookahead)
    try:
        plan = backtrack(
            state,
            checker,
            time_limit_s=plan_s.time_limit_s,
            optimal_max_objects=plan_s.optimal_max_objects,
            optimal_time_s=plan_s.optimal_time_s,
            anytime_time_s=plan_s.anytime_time_s,
            max_backtracks=plan_s.max_backtracks,
            formulation=plan_s.formulation,
            precheck=checker.beyond_reach if plan_s.reach_precheck else None,
        )
    except NoPlanError as err:
        if getattr(err, "plan", None) is not None:
            err.plan = _with_pose(err.plan, T_base_camera)  # type: ignore[attr-defined]
        raise
    return _with_pose(plan, T_base_camera)


def _with_pose(plan: Plan, T_base_camera: np.ndarray) -> Plan:
    import dataclasses

    return dataclasses.replace(plan, T_base_camera=T_base_camera)
