"""Plan-stage figures: Fast Downward per formulation/search, IK per action, whole plan.

    .venv/bin/python benchmarks/plan.py            # full (lifted 16/24 may take minutes)
    .venv/bin/python benchmarks/plan.py --quick    # small sizes, short lifted limit

Prints one table row per (objects, formulation, search): median wall time per
Fast Downward call (translation + search, one subprocess each), plan cost, and whether
the search proves optimality. Random states come from `compile.random_facts` and the goal
is every removable object.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tests"))

import plan_scenes as ps  # noqa: E402

from clearcli.errors import NoPlanError, PlannerError  # noqa: E402
from clearcli.planning import downward  # noqa: E402
from clearcli.planning.compile import compile_strips, random_facts, removable_objects  # noqa: E402


def fd_table(sizes: list[int], seeds: int, lifted_limit_s: float) -> None:
    # "grounded SAS" rows: planning/sas.py writes the SAS+ task itself; "search only" runs
    # just the search binary (run_sas with a search option), "via driver" the driver on
    # the .sas file (run_sas with an alias: no translator, but the driver's start-up).
    from clearcli.planning.sas import SasTask, compile_sas

    print(f"{'objs':>4} {'facts':>5} {'formulation':<26} {'search':<20} {'median s':>8} {'cost':>5} optimal")
    for n in sizes:
        rows: dict[tuple[str, str], list[tuple[float, int | str, bool]]] = {}
        n_facts = []
        for seed in range(seeds):
            names = [f"o{i}" for i in range(n)]
            facts = random_facts(n, seed)
            n_facts.append(len(facts))
            goal = sorted(removable_objects(names, facts))
            pos = compile_strips(names, facts, goal, positive=True)
            neg = compile_strips(names, facts, goal, positive=False)
            sas = compile_sas(names, facts, goal)
            lifted_d, lifted_p, which = ps.lifted_pddl(names, facts, goal)
            runs = [
                ("grounded, positive", "astar(lmcut())", pos, None, 60.0),
                ("grounded SAS, search only", "astar(lmcut())", sas, None, 60.0),
                ("grounded, negative", "astar(lmcut())", neg, None, 60.0),
                ("grounded, positive", "lama-first", pos, "lama-first", 60.0),
                ("grounded SAS, via driver", "lama-first", sas, "lama-first", 60.0),
                ("grounded, positive", "seq-sat-lama-2011/2s", pos, "seq-sat-lama-2011", 2.0),
                ("grounded SAS, via driver", "seq-sat-lama-2011/2s", sas, "seq-sat-lama-2011", 2.0),
                ("lifted", "astar(blind())", (lifted_d, lifted_p), None, lifted_limit_s),
                ("lifted", "astar(hmax())", (lifted_d, lifted_p), None, lifted_limit_s),
            ]
            for form, search, task, alias, limit in runs:
                t0 = time.perf_counter()
                try:
                    if isinstance(task, SasTask):
                        if alias:
                            res = downward.run_sas(task.text, alias=alias, time_limit_s=limit)
                        else:
                            res = downward.run_sas(task.text, search=search, time_limit_s=limit)
                    else:
                        dom, prob = (task.domain, task.problem) if hasattr(task, "domain") else task
                        if alias:
                            res = downward.run_downward(dom, prob, alias=alias, time_limit_s=limit)
                        else:
                            res = downward.run_downward(dom, prob, search=search, time_limit_s=limit)
                    rows.setdefault((form, search), []).append((res.time_s, res.cost, res.optimal))
                except PlannerError as exc:
                    tag = "t/o" if "timed out" in str(exc) else "err"
                    if tag == "err":
                        print(f"  {n} objects, {form}, {search}: {exc}")
                    rows.setdefault((form, search), []).append((time.perf_counter() - t0, tag, False))
        for (form, search), vals in rows.items():
            med = statistics.median(v[0] for v in vals)
            costs = "/".join(str(v[1]) for v in vals)
            print(
                f"{n:>4} {int(statistics.median(n_facts)):>5} {form:<26} {search:<20} {med:>8.3f} {costs:>5} {all(v[2] for v in vals)}"
            )
    print(f"(lifted domain: {which})")


def ik_per_action() -> None:
    from clearcli.planning.feasibility import IKActionChecker
    from clearcli.planning.types import Action, CheckedAction
    from clearcli.robot.collision import make_obstacles
    from clearcli.robot.wam_kinematics import WamKinematics

    state = ps.clutter(9)
    kin = WamKinematics()
    checker = IKActionChecker(state, ps.T_BASE_CAMERA, kin, make_obstacles(state, ps.T_BASE_CAMERA))
    feasible = 0
    n_poses = []
    for obj in state.objects:
        for action in [Action("grasp", obj.name)] + [Action("push", obj.name, d) for d in obj.pushes]:
            feasible += isinstance(checker(action), CheckedAction)
            n_poses.append(len(checker.poses(action)[0]))
    t = sorted(checker.per_action_s)
    print(
        f"IK check per action (9-object scene, {len(t)} actions, {feasible} feasible, "
        f"{min(n_poses)}-{max(n_poses)} poses each, both half-turns when needed): "
        f"median {1000 * statistics.median(t):.1f} ms, p90 {1000 * t[int(0.9 * len(t))]:.1f} ms, "
        f"max {1000 * t[-1]:.1f} ms; {kin.stats.solves} IK solves, "
        f"{kin.stats.iterations / max(kin.stats.solves, 1):.0f} iterations per solve"
    )


def _plan_both_ways(label: str, state, settings, T_base_camera, runs: int) -> None:  # type: ignore[no-untyped-def]
    """Median wall time of the plan stage (make_plan: IK model, obstacles, reach
    pre-check, Fast Downward calls, IK checks), --first-only against the whole-plan check."""
    from clearcli.planning.backtrack import make_plan

    for check in ("first", "whole"):
        times, plan = [], None
        for _ in range(runs + 1):  # the first run pays lazy imports: not counted
            t0 = time.perf_counter()
            try:
                plan = make_plan(state, settings, T_base_camera, check=check)
            except NoPlanError as err:
                plan = err.plan  # type: ignore[attr-defined]
            times.append(time.perf_counter() - t0)
        times = times[1:]
        assert plan is not None
        tm = plan.timings_s
        n_checked = sum(c is not None for c in plan.checked)
        print(
            f"  {label:<34} {check:<5} median {1000 * statistics.median(times):6.1f} ms "
            f"(max {1000 * max(times):6.1f}) | {plan.status}, {len(plan.actions)} actions, {n_checked} checked, "
            f"{plan.replans} FD call(s), planner {1000 * tm.get('planner_s', 0):.0f} ms, IK {1000 * tm.get('ik_s', 0):.0f} ms"
        )


def whole_plan(runs: int) -> None:
    import dataclasses

    from clearcli.settings import Settings

    s = Settings()
    print(f"plan stage, --first-only against the whole-plan check (median of {runs} runs, warm process):")
    pcd = REPO.parent / "shared" / "data" / "mosd" / "test" / "test57.pcd"
    if pcd.is_file():
        from clearcli.io.read import read_frame
        from clearcli.perception.segment import segment
        from clearcli.predicates.state_builder import compute_state
        from clearcli.robot.arm import resolve_arm

        frm = read_frame(pcd, None, 0)
        seg = segment(frm, s.segment)
        # Per action family: the alternatives out of mutual blocking (raised push
        # contacts, off-centre grasps) add IK fallback candidates; the thesis's poses alone
        # first. The robot placement is the default's for all four.
        state = compute_state(frm, seg, s)
        T, _ = resolve_arm(s).place(state)
        thesis_push = dataclasses.replace(s.push, raised_fingertips_m=())
        thesis_pred = dataclasses.replace(s.predicates, grasp_offcentre_fraction=0.0)
        for family, fs in (
            ("thesis poses", dataclasses.replace(s, push=thesis_push, predicates=thesis_pred)),
            ("+ raised pushes", dataclasses.replace(s, predicates=thesis_pred)),
            ("+ off-centre grasps", dataclasses.replace(s, push=thesis_push)),
            ("both (default)", s),
        ):
            fstate = compute_state(frm, seg, fs)
            _plan_both_ways(f"test57 ({len(fstate.objects)}), {family}", fstate, fs, T, runs)
    else:
        print(f"  ({pcd} not here: mOSD test57 skipped)")
    for label, state, settings in (
        ("clutter 6 + one object 2 m away", ps.clutter(6, far=True), s),
        ("clutter 9", ps.clutter(9), s),
        (
            "Figure 3.1, no reach pre-check",
            ps.figure_3_1(),
            dataclasses.replace(s, plan=dataclasses.replace(s.plan, reach_precheck=False)),
        ),
        (
            "second grasp without IK (relearns)",
            ps.scene({"o0": ps.Box(0.45, 0.0), "o1": ps.Box(0.12, 0.0)}, {("block_grasp", "o0", "o1")}),
            s,
        ),
    ):
        _plan_both_ways(label, state, settings, ps.T_BASE_CAMERA, runs)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--seeds", type=int, default=3)
    args = ap.parse_args()
    sizes = [4, 8] if args.quick else [4, 8, 16, 24]
    fd_table(sizes, 1 if args.quick else args.seeds, 10.0 if args.quick else 60.0)
    ik_per_action()
    whole_plan(5 if args.quick else 20)


if __name__ == "__main__":
    main()
