"""A new grasp kind costs its module and one registry line: the toy magnet kind
(tests/helpers/toy_kind.py), registered here by one monkeypatched entry of
clearcli/settings/kinds.py and nothing else, is a setting, offered by the predicates,
planned by Fast Downward through the SAS+ compiler, IK-checked, accepted by two
independent plan validators on the lifted domain, drawn, and carried out in the
simulated world."""

from __future__ import annotations

import numpy as np
import pytest

from clearcli.settings import kinds
from clearcli.sim import scene as S

TOY = kinds.KindEntry("magnet", "a magnet on a flat top", module="helpers.toy_kind")
ALL = "pinch,rim,slide,magnet"
# 12 cm square: too wide for the Panda's 8 cm pinch, closed (no rim), 8 cm thick (no
# slide: the jaws span at most 7 cm x cos 20 deg = 6.6 cm at an edge); its top is flat
WIDE = S.Box(0, 0.12, 0.12, 0.08, -0.10, -0.05)
SMALL = S.Box(1, 0.04, 0.04, 0.06, 0.12, -0.12)  # the pinch takes it


@pytest.fixture
def toy(monkeypatch):  # type: ignore[no-untyped-def]
    monkeypatch.setattr(kinds, "GRASP_KINDS", (*kinds.GRASP_KINDS, TOY))  # the one registry line


def _settings(grasps: str = ALL):  # type: ignore[no-untyped-def]
    from clearcli.settings.tree import load_settings

    return load_settings(None, ["robot.name=panda", f'plan.grasps="{grasps}"'])


def _state(scene: S.Scene, settings):  # type: ignore[no-untyped-def]
    from clearcli.predicates.state_builder import compute_state
    from clearcli.sim.camera import render
    from clearcli.sim.truth import truth_segment

    frame = render(scene, seed=0)
    seg = truth_segment(frame)
    return frame, seg, compute_state(frame, seg, settings)


def _named(state, scene: S.Scene, obj: S.SceneObject) -> str:  # type: ignore[no-untyped-def]
    T = scene.T_camera_table
    want = T[:3, :3] @ np.array([obj.x_m, obj.y_m, 0.0]) + T[:3, 3]
    return min(state.objects, key=lambda o: float(np.linalg.norm((o.centroid - want)[:2]))).name


def test_unregistered_it_is_no_setting() -> None:
    from clearcli.errors import SettingsError
    from clearcli.predicates.grasps import kind_names

    assert "magnet" not in kind_names()
    with pytest.raises(SettingsError, match="comma-separated list of pinch, rim, slide, suction "):
        _settings()


def test_registered_it_is_a_setting_in_the_help_and_the_domain(toy) -> None:  # type: ignore[no-untyped-def]
    from clearcli.planning.pddl import domain_text
    from clearcli.predicates.grasps import kind_names, parse_kinds
    from clearcli.settings.fields import range_of
    from clearcli.settings.plan import PlanSettings

    assert kind_names() == ("pinch", "rim", "slide", "suction", "magnet")
    assert parse_kinds("magnet, pinch") == ("pinch", "magnet")
    assert "pinch, rim, slide, suction, magnet" in range_of(PlanSettings, "grasps").describe()
    assert "magnet (a magnet on a flat top)" in kinds.help_text()
    assert _settings("magnet,pinch").plan.grasps == "pinch,magnet"
    text = domain_text(kinds=parse_kinds("pinch,magnet"))
    # its action, made from its facts and flags; the push deletes its blocks and IK fact
    assert "(:action magnet_grasp" in text and "(increase (total-cost) 4)" in text
    assert "(not (block_magnet ?x ?o))" in text and "(not (ik_unfeasible_magnet ?o))" in text
    assert "magnet_grasp" not in domain_text(kinds=("pinch",))


def test_offered_planned_checked_and_validated(toy, tmp_path) -> None:  # type: ignore[no-untyped-def]
    import dataclasses

    from helpers.validate import second_verdict, validate_files, validate_files_second

    from clearcli.planning.backtrack import make_plan
    from clearcli.planning.compile import ground_actions
    from clearcli.planning.payload import predicates_payload
    from clearcli.planning.pddl import domain_for, write_plan, write_problem
    from clearcli.render.plan_png import render_plan
    from clearcli.robot.profiles import kinematics_from_settings

    scene = S.make_scene("toy", [WIDE, SMALL])
    settings = _settings()
    frame, seg, state = _state(scene, settings)
    wide, small = _named(state, scene, WIDE), _named(state, scene, SMALL)
    assert wide != small
    # offered: for the wide box, which no kind before it takes; not for the small one
    assert {("ungraspable", wide), ("magnet_graspable", wide)} <= state.facts
    assert ("magnet_graspable", small) not in state.facts
    assert state.by_name(small).kind_refusals["magnet"] == "the pinch from above fits it"
    assert len(state.by_name(wide).kind_candidates["magnet"]) == 1
    assert "magnet" in next(o for o in predicates_payload(state)["objects"] if o["name"] == wide)["grasp_kinds"]
    # grounded by the compiler, planned by Fast Downward, every action IK-checked
    assert f"magnet_grasp_{wide}" in {a.name for a in ground_actions(state.names(), state.facts)}
    plan = make_plan(state, settings)
    assert sorted(a.pddl() for a in plan.actions) == sorted([f"(magnet_grasp {wide})", f"(grasp {small})"])
    assert plan.status == "complete" and plan.cost == 1 + 4
    kin = kinematics_from_settings(settings.robot)
    (checked,) = [c for c in plan.checked if c is not None and c.action.grasp_kind == "magnet"]
    for q, T in zip(checked.joint_solutions, checked.T_base_gripper):
        assert np.linalg.norm(kin.fk(q)[:3, 3] - T[:3, 3]) < 1e-3
    # two independent validators accept the plan on the lifted domain the kind wrote
    files = [tmp_path / "domain.pddl", tmp_path / "problem.pddl", tmp_path / "plan.txt"]
    files[0].write_text(domain_for(state))
    files[1].write_text(write_problem(state, plan.goal, plan.ik_facts))
    files[2].write_text(write_plan(plan.actions, plan.cost, unit_cost=False))
    assert "magnet_graspable" in files[1].read_text()
    assert validate_files(*files)
    assert validate_files_second(*files), second_verdict(*files).reason
    # and both refuse it without the fact that offers the kind
    stripped = dataclasses.replace(state, facts=frozenset(f for f in state.facts if f[0] != "magnet_graspable"))
    files[1].write_text(write_problem(stripped, plan.goal, plan.ik_facts))
    assert not validate_files(*files) and not validate_files_second(*files)
    # drawn (its label is its name)
    render_plan(tmp_path / "plan.png", frame, state, plan, seg)
    assert (tmp_path / "plan.png").stat().st_size > 0


def test_left_out_of_plan_grasps_the_thesis_model_stands(toy) -> None:  # type: ignore[no-untyped-def]
    from clearcli.errors import NoPlanError
    from clearcli.planning.backtrack import make_plan

    settings = _settings("pinch,rim,slide")
    _, _, state = _state(S.make_scene("toy", [WIDE]), settings)
    with pytest.raises(NoPlanError) as err:
        make_plan(state, settings)
    (left,) = err.value.plan.left  # type: ignore[attr-defined]
    assert left.reason == "ungraspable" and "magnet" not in left.detail


def test_carried_out_in_the_simulated_world(toy) -> None:  # type: ignore[no-untyped-def]
    import dataclasses

    from clearcli.pipeline import Pipeline
    from clearcli.replay.session import ReplayOptions, Session
    from clearcli.sim.episode import Episode
    from clearcli.sim.physics import truly_ungraspable_by
    from clearcli.sim.truth import truth_segment

    settings = _settings()
    settings = dataclasses.replace(settings, plan=dataclasses.replace(settings.plan, probe_max_width_m=0.0))
    # the world's verdict reads the kinds the planner is given
    assert truly_ungraspable_by(WIDE, settings.gripper, ("pinch", "rim", "slide"))
    assert not truly_ungraspable_by(WIDE, settings.gripper, ("pinch", "rim", "slide", "magnet"))
    episode = Episode(
        S.make_scene("toy", [WIDE, SMALL]),
        Session(Pipeline(settings, segment_fn=truth_segment), ReplayOptions()),
        seed=0,
        max_actions=4,
    )
    for _ in episode:
        pass
    result = episode.result
    assert result is not None
    done = [(s.action, s.outcome) for s in result.steps if s.action]
    assert ("(magnet_grasp 0)", "removed") in done and ("(grasp 1)", "removed") in done, done
    assert result.end == "cleared" and result.cleared_truly
    # the replay's report names the kind
    kinds_seen = {a.get("grasp_kind") for r in episode.reports if r["plan"] for a in r["plan"]["actions"]}
    assert "magnet" in kinds_seen
