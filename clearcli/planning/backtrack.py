"""Planning with backtracking on IK (thesis Algorithm 1), every action checked.

    repeat
        plan <- Fast Downward(state + learnt facts, goal)
        check the plan's actions in order, each in the scene as the earlier ones leave it
        (`feasibility.SceneContext`: grasped objects gone, pushed ones moved)
        if an action has no arm motion: learn why, and plan again
    until every action has joint solutions, or the goal is empty

The thesis checks only the first action (``check="first"``, `clear plan --first-only`,
and what `replay` and `simulate` use: the robot replans after every action anyway).
The loop is a `Search` object: its fields are the search's state (the base, the facts
learnt, the fixed prefix), its bounds the [plan] settings it is given.

**What is learnt, and where it holds.** The model's ``ik_unfeasible_*`` facts are
initial-state facts, and ``push o`` deletes ``ik_unfeasible_grasp o``: "the grasp of o
fails after o's push" cannot be said in the initial state. So a failure is learnt where
it is true:

* If the failing action's object still stands where it stood in the state the plan was
  made from (the *base*), the action is checked again in the base; when it fails there
  too, that failure's facts hold in the base and are added to it. A failure of the
  first action is a failure in the base by definition (the thesis's case).
* Otherwise (the object was pushed earlier in the plan, or only an object pushed
  earlier stands in the way) nothing can be said of the base: the checked actions
  before the failing one are *fixed*, the base becomes the state they leave (symbolic
  facts progressed by the domain's effects, geometry by the context), the failure is
  learnt there, and the rest is planned from it.

Either way every fact ever added is true in the state it is added to, so every plan
returned has actions that are all checked in the scene they act on, and a problem
written from the recorded scene plus the facts learnt in it (``Plan.ik_facts``) is
solved by the whole plan: the facts learnt after a fixed prefix only restrict the
rest (they appear in negative preconditions alone), so leaving them out keeps the plan
valid. The loop ends: each round adds a new fact to a finite set at the current base, or
fixes at least one more checked action; ``[plan] max_backtracks`` bounds it and the
time limit bounds it in seconds.

What a failure teaches (`feasibility.Infeasible.facts`): an arm that hits objects in
every candidate learns ``block_grasp x o`` / ``block_dir x o d`` for the objects x hit
(the arm is in x's way as the gripper would be: moving x frees it, as the model says of
blocking objects); no IK, beyond reach or the table learn ``ik_unfeasible_*``. Both keep
the compiled model delete-only for blocking and IK facts (compile.py), so
`removable_objects` stays exact: objects no sequence of actions can free are dropped
from the goal as ``stuck``, objects whose every action is IK-infeasible as
``unreachable``; objects the gripper cannot hold (``ungraspable``) are never in the goal
but can still be pushed out of the way.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from clearcli.errors import NoPlanError, PlannerError, SettingsError
from clearcli.planning.compile import removable_objects
from clearcli.planning.feasibility import EMPTY, IKActionChecker, Infeasible, SceneContext, gripper_opening_text
from clearcli.planning.solve import Solved, action_cost, action_space, deadline_error, progress, solve
from clearcli.planning.types import Action, BacktrackStep, CheckedAction, LeftObject, Plan
from clearcli.predicates.grasps import kind as grasp_kind
from clearcli.predicates.grasps import kinds as grasp_kinds
from clearcli.predicates.grasps import parse_kinds
from clearcli.predicates.state import Fact, SymbolicState
from clearcli.robot.arm import Arm, resolve_arm
from clearcli.robot.collision import make_obstacles
from clearcli.settings.plan import PlanSettings
from clearcli.settings.profiles import tools_of

if TYPE_CHECKING:
    from clearcli.settings import Settings

# check(action, context) -> CheckedAction, or Infeasible with the reason
Checker = Callable[[Action, SceneContext], "CheckedAction | Infeasible"]

CHECK_MODES = ("whole", "first")


def _label(action: Action) -> str:
    """The action as reasons name it: its grasp kind's label ("grasp", "rim grasp", ...)
    or "push dirN"."""
    return grasp_kind(action.grasp_kind).label if action.kind == "grasp" else f"push {action.direction}"


def with_grasp_kinds(state: SymbolicState, kinds: Sequence[str]) -> SymbolicState:
    """``state`` with the facts of the grasp kinds not in ``kinds`` left out (``[plan]
    grasps``): with "pinch" alone, exactly the thesis's facts, so exactly its plans."""
    drop = {n for k in grasp_kinds() if k.name not in kinds for n in (k.facts.offered, k.facts.block) if n}
    if not drop or not any(f[0] in drop for f in state.facts):
        return state
    return dataclasses.replace(state, facts=frozenset(f for f in state.facts if f[0] not in drop))


class Search:
    """One backtracking search (the module's docstring): its state is its fields, its
    bounds the [plan] settings it is given.

    The base is the state plans are made from: the recorded scene (``base_ctx`` empty,
    ``base_facts`` the state's) until a prefix of checked actions is fixed (``prefix``);
    ``learnt0`` holds what is learnt in the recorded scene, ``learnt_here`` what is learnt
    in the base after a prefix. Each round (`step`) plans from the base, checks the
    plan's actions and either returns the plan or learns from the first failure
    (`learn`), after which the goal is worked out again (`refresh_goal`)."""

    def __init__(
        self,
        state: SymbolicState,
        check: Checker,
        settings: PlanSettings,
        *,
        goal_objects: Sequence[str] | None = None,
        precheck: Callable[[Action], str] | None = None,
        mode: str | None = None,
        describe_width: Callable[[str], tuple[str, float | None]] | None = None,
    ) -> None:
        self.state = state
        self.check = check
        self.settings = settings
        self.mode = settings.check if mode is None else mode
        if self.mode not in CHECK_MODES:
            raise SettingsError(f"settings: [plan] check must be one of {', '.join(CHECK_MODES)}, got {self.mode!r}")
        self.precheck = precheck
        self.describe_width = describe_width
        self.t_start = time.perf_counter()
        self.deadline_at = self.t_start + settings.time_limit_s
        self.names = state.names()
        self.facts0 = frozenset(state.facts)
        # no grasp kind offered: too wide or narrow for the pinch, and no other kind
        self.ungraspable = tuple(
            o for o in self.names if not any(k.facts.offered_in(self.facts0, o) for k in grasp_kinds())
        )
        wanted = goal_objects if goal_objects is not None else self.names
        self.wanted = [o for o in wanted if o not in self.ungraspable]
        self.learnt0: set[Fact] = set()  # learnt, true in the recorded scene
        self.why: dict[str, dict[str, str]] = {}  # object -> action label -> why it has no arm motion
        self.steps: list[BacktrackStep] = []
        self.timings = {"planner_s": 0.0, "ik_s": 0.0}
        self.prefix: list[Action] = []
        self.prefix_checked: list[CheckedAction] = []
        self.base_ctx: SceneContext = EMPTY
        self.base_facts: frozenset[Fact] = self.facts0
        self.learnt_here: set[Fact] = set()  # learnt in the base after a prefix
        self.learnt_later: list[tuple[int, Fact]] = []
        self.goal: list[str] = list(self.wanted)
        self.unreachable: list[str] = []
        self.stuck: list[str] = []

    # -- the base ------------------------------------------------------------------------
    def known(self) -> frozenset[Fact]:
        """The facts of the base, with what is learnt there."""
        return self.base_facts | (self.learnt0 if not self.prefix else frozenset()) | self.learnt_here

    def gone(self) -> set[str]:
        return {a.obj for a in self.prefix if a.kind == "grasp"}

    def base_names(self) -> tuple[str, ...]:
        gone = self.gone()
        return tuple(o for o in self.names if o not in gone)

    def refresh_goal(self) -> None:
        """The goal in the base: the wanted objects still there, less those no action of
        which has an arm motion (``unreachable``) and those no sequence frees (``stuck``)."""
        gone = self.gone()
        self.goal = [o for o in self.wanted if o not in gone]
        self.unreachable = []
        self.stuck = []
        facts = self.known()
        for o in list(self.goal):  # every allowed action IK-infeasible
            space = action_space(facts, o)
            grasps = [a for a in space if a.kind == "grasp"]
            # or its only grasps are of kinds whose IK fact no push clears (a slide's,
            # made for where the object stands): a push of it does not make them known,
            # so no sequence frees them
            fixed = bool(grasps) and all(not grasp_kind(a.grasp_kind).push_clears_ik for a in grasps)
            if all(a.ik_fact() in facts for a in (grasps if fixed else space)):
                self.goal.remove(o)
                self.unreachable.append(o)
        removable = removable_objects(self.base_names(), facts, self.state.push_costs)
        for o in list(self.goal):  # exact: the model is monotone
            if o not in removable:
                self.goal.remove(o)
                self.stuck.append(o)

    # -- the search ----------------------------------------------------------------------
    def run(self) -> Plan:
        """Backtracking with ``check`` as HASIKSOLUTION, on every action (``mode="whole"``)
        or the first (``"first"``; default ``settings.check``), its bounds those of
        ``settings`` (the [plan] section of the settings tree the caller resolved). Raises
        NoPlanError when nothing can be removed (the reason in the message, the result in
        ``error.plan``), PlannerError when the search fails or ``settings.time_limit_s``
        (the whole planning) ends without a checked plan."""
        if self.precheck is not None:
            self.run_precheck()
        self.refresh_goal()
        while True:
            plan = self.step()
            if plan is not None:
                return plan

    def run_precheck(self) -> None:
        """Cheap necessary conditions (reach) for every action, before any search: an
        object far away is dropped without planning around it first."""
        assert self.precheck is not None
        t0 = time.perf_counter()
        for o in self.names:
            for a in action_space(self.facts0, o):
                reason = self.precheck(a)
                if reason:
                    self.learnt0.add(a.ik_fact())
                    self.why.setdefault(o, {})[_label(a)] = reason
        self.timings["precheck_s"] = time.perf_counter() - t0

    def step(self) -> Plan | None:
        """One round: the plan with every checked action, or None after learning."""
        s = self.settings
        if not self.goal:
            plan = self.result(Solved((), 0, True, "", 0.0), ())
            if not self.names or plan.actions:
                return plan  # an empty table is clear already; a fixed prefix is a plan
            err = NoPlanError(f"no plan: {_no_plan_reason(plan)}")
            err.plan = plan
            raise err
        if len(self.steps) >= s.max_backtracks:
            raise PlannerError(f"backtracking gave up after {len(self.steps)} replans; raise [plan] max_backtracks")
        if time.perf_counter() >= self.deadline_at:
            raise deadline_error(s.time_limit_s)
        t0 = time.perf_counter()
        solved = solve(
            self.base_names(),
            self.known(),
            self.goal,
            self.state.push_costs,
            time_limit_s=s.time_limit_s,
            optimal_max_objects=s.optimal_max_objects,
            optimal_time_s=s.optimal_time_s,
            anytime_time_s=s.anytime_time_s,
            formulation=s.formulation,
            deadline_at=self.deadline_at,
        )
        self.timings["planner_s"] += time.perf_counter() - t0
        if solved is None:
            # Cannot happen after refresh_goal (the fixpoint is exact); guard anyway.
            raise PlannerError("Fast Downward proved the goal unsolvable although it is reachable")

        t0 = time.perf_counter()
        ctx = self.base_ctx
        checked: list[CheckedAction] = []
        failure: tuple[int, Action, Infeasible, SceneContext] | None = None
        for i, action in enumerate(solved.actions if self.mode == "whole" else solved.actions[:1]):
            res = self.check(action, ctx)
            if isinstance(res, Infeasible):
                failure = (i, action, res, ctx)
                break
            checked.append(res)
            ctx = ctx.after(action, self.state)
        if failure is None:
            self.timings["ik_s"] += time.perf_counter() - t0
            self.steps.append(BacktrackStep(solved.actions, solved.cost, solved.optimal, True, prefix=len(self.prefix)))
            return self.result(solved, checked)
        self.learn(solved, checked, *failure, t0=t0)
        self.refresh_goal()
        return None

    def learn(
        self,
        solved: Solved,
        checked: Sequence[CheckedAction],
        i: int,
        action: Action,
        fail: Infeasible,
        ctx_i: SceneContext,
        t0: float,
    ) -> None:
        """What the failure of the plan's ``i``-th action teaches, where it holds (the
        module's docstring): facts of the base, or a fixed prefix and a new base."""

        def failed_round(learnt: Iterable[Fact]) -> BacktrackStep:
            """This round: its plan, failing at action ``i`` (after the prefix fixed so
            far), and the facts it taught."""
            return BacktrackStep(
                solved.actions,
                solved.cost,
                solved.optimal,
                False,
                fail.reason,
                i,
                tuple(sorted(learnt)),
                len(self.prefix),
            )

        new: set[Fact] = set()
        if i == 0:
            new = set(fail.facts(action)) - self.known()
            self.why.setdefault(action.obj, {})[_label(action)] = fail.reason
        else:
            pushes_before = [j for j, a in enumerate(solved.actions[:i]) if a.obj == action.obj]
            if not pushes_before:
                # The object stands where it stood in the base: does the action fail
                # there too? Then what that failure teaches holds in the base.
                at_base = self.check(action, self.base_ctx)
                if isinstance(at_base, Infeasible):
                    new = set(at_base.facts(action)) - self.known()
                    if new:
                        self.why.setdefault(action.obj, {})[_label(action)] = at_base.reason
            elif action.kind == "grasp" and len(pushes_before) == 1:
                # Pushed once from where it stood in the base, then not graspable: the
                # push look-ahead's rule, in hindsight (the look-ahead saw the other
                # objects as they stood at the push): that push is infeasible in the base.
                push = solved.actions[pushes_before[0]]
                if push.ik_fact() not in self.known():
                    new = {push.ik_fact()}
                    self.why.setdefault(action.obj, {})[_label(push)] = (
                        f"the push leaves {action.obj} where it cannot be grasped ({fail.reason})"
                    )
        self.timings["ik_s"] += time.perf_counter() - t0
        if new:
            (self.learnt0 if not self.prefix else self.learnt_here).update(new)
            if self.prefix:
                self.learnt_later.extend((len(self.prefix), f) for f in sorted(new))
            self.steps.append(failed_round(new))
        elif i == 0:
            # A failure in the base whose facts are known already: the planner would not
            # have planned the action. A bug, not a scene: say so rather than loop.
            raise PlannerError(f"backtracking learnt nothing from {action.pddl()} ({fail.reason})")
        else:
            # Nothing to say of the base: fix the checked actions before the failure and
            # plan the rest from the state they leave, where the failure is learnt.
            self.steps.append(failed_round(fail.facts(action)))
            # The facts known in the base, carried through the fixed actions by the
            # domain's effects, are the new base's facts.
            facts_now = self.known()
            for a in solved.actions[:i]:
                facts_now = progress(facts_now, a)
            self.prefix.extend(solved.actions[:i])
            self.prefix_checked.extend(checked[:i])
            self.base_ctx = ctx_i
            self.base_facts = facts_now
            self.learnt_here = set(fail.facts(action)) - facts_now
            self.learnt_later.extend((len(self.prefix), f) for f in sorted(self.learnt_here))
            self.why.setdefault(action.obj, {})[_label(action)] = fail.reason

    def result(self, solved: Solved, checked: Sequence[CheckedAction | None]) -> Plan:
        """The plan: the fixed prefix and ``solved`` after it."""
        self.timings["total_s"] = time.perf_counter() - self.t_start
        actions = tuple(self.prefix) + solved.actions
        all_checked = tuple(self.prefix_checked) + tuple(checked) + (None,) * (len(solved.actions) - len(checked))
        costs = self.state.push_costs or {}
        cost = sum(action_cost(a, costs) for a in self.prefix) + solved.cost
        # Pushes after the last grasp serve nothing (a fixed prefix can end so when the
        # rest turns out impossible): leave them out.
        keep = len(actions)
        while keep and actions[keep - 1].kind == "push":
            keep -= 1
        if keep < len(actions):
            actions, all_checked = actions[:keep], all_checked[:keep]
            cost = sum(action_cost(a, costs) for a in actions)
        removed = tuple(a.obj for a in actions if a.kind == "grasp")
        left = _left_objects(
            self.names,
            removed,
            self.ungraspable,
            self.unreachable,
            self.stuck,
            self.known(),
            self.why,
            self.describe_width,
        )
        return Plan(
            actions=actions,
            cost=cost,
            optimal=solved.optimal and not self.prefix,
            first=all_checked[0] if all_checked else None,
            ik_facts=frozenset(self.learnt0),
            unreachable=tuple(self.unreachable),
            replans=len(self.steps),
            timings_s=dict(self.timings),
            goal=removed,
            ungraspable=self.ungraspable,
            stuck=tuple(self.stuck),
            search=solved.config,
            steps=tuple(self.steps),
            checked=all_checked,
            check=self.mode,
            deadline=solved.deadline,
            learnt_later=tuple(self.learnt_later),
            left=left,
            max_backtracks=self.settings.max_backtracks,
        )


def _left_objects(
    names: Sequence[str],
    removed: Sequence[str],
    ungraspable: Sequence[str],
    unreachable: Sequence[str],
    stuck: Sequence[str],
    facts: frozenset[Fact],
    why: Mapping[str, Mapping[str, str]],
    describe_width: Callable[[str], tuple[str, float | None]] | None,
) -> tuple[LeftObject, ...]:
    """Every object the plan does not remove, with the reason."""
    gone = set(removed)
    left_names = [o for o in names if o not in gone]
    left_set = set(left_names)
    out = []
    for o in left_names:
        actions = dict(why.get(o, {}))
        if o in ungraspable:
            text, width = describe_width(o) if describe_width else ("too wide or narrow for the gripper", None)
            out.append(LeftObject(o, "ungraspable", text, actions, width_m=width))
        elif o in unreachable:
            detail = "; ".join(f"{k}: {v}" for k, v in actions.items()) or "no action has an arm motion"
            out.append(LeftObject(o, "unreachable", detail, actions))
        else:
            holders = sorted(
                {
                    f[1]
                    for f in facts
                    if f[0] in ("on", "block_grasp", "block_dir")
                    and len(f) > 2
                    and f[2] == o
                    and f[1] in left_set
                    and f[1] != o
                }
                | {f[2] for f in facts if f[0] == "on" and f[1] == o and f[2] in left_set},
                key=_name_key,
            )
            detail = "held by objects that cannot be moved: " + (", ".join(holders) if holders else "none found")
            out.append(LeftObject(o, "stuck", detail, actions, blockers=tuple(holders)))
    return tuple(out)


def _name_key(name: str) -> tuple[int, str]:
    return (int(name[1:]), "") if name[:1] == "o" and name[1:].isdigit() else (1 << 30, name)


def _no_plan_reason(plan: Plan) -> str:
    parts = []
    unreachable = [x for x in plan.left if x.reason == "unreachable"]
    stuck = [x for x in plan.left if x.reason == "stuck"]
    narrow = [x for x in plan.left if x.reason == "ungraspable"]
    if unreachable:
        detail = "; ".join(f"{x.name}: {x.detail}" for x in unreachable)
        parts.append(f"out of the robot's reach: {', '.join(x.name for x in unreachable)} ({detail})")
    if stuck:
        parts.append(f"blocked by objects that cannot be moved: {', '.join(x.name for x in stuck)}")
    if narrow:
        parts.append(f"too wide or narrow for the gripper: {', '.join(x.name for x in narrow)}")
    if not parts:
        parts.append("no object can be removed")
    return "; ".join(parts)


def make_plan(
    state: SymbolicState,
    settings: Settings,
    T_base_camera: np.ndarray | None = None,
    check: str | None = None,
    robot: Arm | None = None,
) -> Plan:
    """Plan for ``state`` (SymbolicState) with ``robot`` (the command's resolved arm,
    clearcli/robot/arm.py; else the one ``settings`` describe) at ``T_base_camera`` (else
    from ``[robot] camera_pose`` or derived from the table, see clearcli/robot/placement.py).
    ``check``: "whole" or "first" (default ``[plan] check``)."""
    arm = robot if robot is not None else resolve_arm(settings)
    plan_s = settings.plan
    gripper = settings.gripper
    kinds_on = parse_kinds(plan_s.grasps)
    state = with_grasp_kinds(state, kinds_on)
    if T_base_camera is None:
        T_base_camera, _ = arm.place(state)
    T_base_camera = np.asarray(T_base_camera, dtype=float)
    kin = arm.kinematics()
    obstacles = make_obstacles(state, T_base_camera, arm.settings.collision_margin_m)
    checker = IKActionChecker(state, T_base_camera, kin, obstacles, push_lookahead=plan_s.push_lookahead)

    has_fingers = "fingers" in tools_of(settings.robot.name)

    def describe_width(name: str) -> tuple[str, float | None]:
        obj = state.by_name(name)
        width = float(obj.grasp_width_m)
        if not has_fingers:
            text = "pinch: the robot's tool has no fingers"
        else:
            text = (
                "too wide or narrow for the gripper"
                if width <= 0
                else gripper_opening_text(width, gripper.opening_width_m, gripper.closing_width_m)
            )
        # the other kinds tried, and why each is not offered
        tried = [f"{grasp_kind(k).label}: {obj.kind_refusals[k]}" for k in kinds_on if k in obj.kind_refusals]
        if tried:
            text = f"{text}; " + "; ".join(tried)
        return text, (width if width > 0 else None)

    try:
        plan = Search(
            state,
            checker,
            plan_s,
            precheck=checker.beyond_reach if plan_s.reach_precheck else None,
            mode=check or plan_s.check,
            describe_width=describe_width,
        ).run()
    except NoPlanError as err:
        if getattr(err, "plan", None) is not None:
            err.plan = _with_pose(err.plan, T_base_camera)
        raise
    return _with_pose(plan, T_base_camera)


def _with_pose(plan: Plan, T_base_camera: np.ndarray) -> Plan:
    return dataclasses.replace(plan, T_base_camera=T_base_camera)
