"""Simulated sessions with a cup (issue 36): the panda-hybrid profile on `suction_mix`
scenes, each suction step judged by the world's own rules (clearcli/sim/physics.py
`world_suction`), not the planner's."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from clearcli.predicates.grasps.suction import SuctionGrasp
from clearcli.settings import Settings
from clearcli.sim.episode import EpisodeResult
from clearcli.sim.families import suction_mix
from clearcli.sim.scene import Scene


def _probe_axis() -> np.ndarray:
    """The axis the suction kind's `simulate` hands the world for a cup coming straight
    down (its pose's z, into the face, is -z of the table)."""
    T = np.eye(4)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])
    T[:3, 3] = (0.0, 0.0, 0.2)
    seen: list[np.ndarray] = []

    def world_suction(scene: Any, lip: np.ndarray, axis: np.ndarray, s: Any) -> tuple[bool, str, int | None]:
        seen.append(np.asarray(axis, dtype=float))
        return False, "missed: probe", None

    world = SimpleNamespace(
        model=SimpleNamespace(kind_candidates={"suction": ((T, T, T),)}),
        settings=Settings(),
        T_table_camera=np.eye(4),
        rules=SimpleNamespace(world_suction=world_suction),
        scene=None,
        k=0,
        chosen_pose=lambda candidates, pose=1, candidate=0: candidates[candidate][pose],
    )
    SuctionGrasp().simulate(world)
    return seen[0]


def test_the_suction_kind_hands_the_world_the_axis_into_the_face() -> None:
    assert _probe_axis() @ np.array([0.0, 0.0, -1.0]) > 0.99


def _session(seed: int, max_actions: int) -> tuple[EpisodeResult, Scene]:
    """The session's result and the world as it ended."""
    from clearcli.pipeline import Pipeline
    from clearcli.replay.session import ReplayOptions, Session
    from clearcli.settings.tree import load_settings
    from clearcli.sim.episode import Episode
    from clearcli.sim.truth import truth_segment

    settings = load_settings(None, ["robot.name=panda-hybrid"])
    pipeline = Pipeline(settings, segment_fn=truth_segment)
    episode = Episode(suction_mix(seed), Session(pipeline, ReplayOptions()), seed=seed, max_actions=max_actions)
    for _ in episode:
        pass
    assert episode.result is not None
    return episode.result, episode.scene


def test_a_suction_mix_scene_is_cleared_with_the_cup_and_the_fingers() -> None:
    # suction_mix(19): a lidded container 12.5 cm across, a flat box 29 x 19 cm, a box
    # 4.5 cm wide
    world = suction_mix(19)
    result, _ = _session(19, max_actions=6)
    done = [(s.action, s.outcome) for s in result.steps if s.action]
    assert result.end == "cleared" and result.cleared_truly, done
    by_cup = [a for a, o in done if a.startswith("(grasp_suction ") and o == "removed"]
    assert len(by_cup) == 2 and len(done) == 3, done
    assert sorted(by_cup) == ["(grasp_suction 0)", "(grasp_suction 1)"]
    assert [o.object_id for o in world.objects] == [0, 1, 3]


def test_the_world_drops_a_heavy_object_and_does_not_seal_on_a_porous_top() -> None:
    # suction_mix(5): the planner weighs object 2 by its volume and takes it by its top;
    # the world's 4.4 kg takes more than the cup holds there: it drops, and the next plan
    # does not try that top again (the slide takes it). Then object 3, whose top is
    # porous: no seal. It stays where it stood.
    world = suction_mix(5)
    truth = {o.object_id: o for o in world.objects}
    result, end = _session(5, max_actions=3)
    (a, first), (a2, again), (b, second) = [(s.action, s.outcome) for s in result.steps if s.action]
    assert a == "(grasp_suction 2)" and first.startswith("suction failed: dropped: too heavy: 4.36 kg"), first
    assert truth[2].mass_kg > 4.0 and truth[2].surface == "smooth"
    assert a2 != "(grasp_suction 2)" and again == "removed", (a2, again)
    assert (b, second) == ("(grasp_suction 3)", "suction failed: no seal: the top is porous")
    assert truth[3].surface == "porous"
    left = {o.object_id: o for o in end.objects}
    assert left[3] == truth[3]  # no seal, not moved


def test_a_top_that_did_not_seal_is_not_tried_again_and_another_way_takes_the_object() -> None:
    # suction_mix(1001): object 0's top is ribbed (the planner cannot see it): the cup
    # does not seal there; the next plan leaves the top out (the session's memory of the
    # face) and takes the object another way (its sides, or the slide) instead of trying
    # the same top again (which, before, also survived a push)
    truth = {o.object_id: o for o in suction_mix(1001).objects}
    assert truth[0].surface == "ribbed"
    result, end = _session(1001, max_actions=8)
    done = [(s.action, s.outcome) for s in result.steps if s.action]
    on_0 = [(a, o) for a, o in done if a.endswith(" 0)") or " 0 " in a]
    assert on_0[0] == ("(grasp_suction 0)", "suction failed: no seal: the top is ribbed"), done
    assert on_0[1][1] == "removed" and on_0[1][0] != "(grasp_suction 0)" or "side" in on_0[1][0], done
    assert 0 not in {o.object_id for o in end.objects}
    assert result.end == "cleared", done


def test_the_predicates_leave_out_a_face_the_session_says_failed() -> None:
    # the same scene's first frame: an object the cup takes by its top; told the top
    # failed, the kind offers a side or says why not, never the top; told both failed,
    # nothing
    from clearcli.predicates.state_builder import compute_state
    from clearcli.settings.tree import load_settings
    from clearcli.sim.camera import render
    from clearcli.sim.truth import truth_segment

    settings = load_settings(None, ["robot.name=panda-hybrid"])
    frame = render(suction_mix(1001), seed=1001)
    seg = truth_segment(frame, settings.segment)
    free = compute_state(frame, seg, settings)
    # a segment the cup takes by its top
    k = next(o.segment_index for o in free.objects if o.kind_details.get("suction", {}).get("face") == "top")
    told = compute_state(frame, seg, settings, avoid_faces={k: frozenset({"top"})})
    name = next(o.name for o in free.objects if o.segment_index == k)
    assert free.by_name(name).kind_details["suction"]["face"] == "top"
    after = told.by_name(name).kind_details.get("suction")
    assert after is None or after["face"] == "side"
    both = compute_state(frame, seg, settings, avoid_faces={k: frozenset({"top", "side"})})
    assert "suction" not in both.by_name(name).kind_details
    assert ("ik_unfeasible_suction", name) in both.facts or ("suctionable", name) not in both.facts


def test_clear_simulate_takes_the_suction_mix_scene(tmp_path: Path) -> None:
    from clearcli.settings.tree import load_settings
    from clearcli.tasks import simulate as task

    settings = load_settings(None, ["robot.name=panda-hybrid"])
    request = task.Request(settings, scene="suction_mix", seed=1, max_actions=1, truth_segmentation=True)
    payload = task.run(request, tmp_path / "suction.mcap")
    assert payload["scene"] == "suction_mix(1)" and payload["objects"] == suction_mix(1).n_objects
    assert payload["steps"][0]["action"] == "(grasp_suction 0)" and payload["steps"][0]["outcome"] == "removed"


def _alone(box: Any, max_actions: int) -> tuple[EpisodeResult, Scene]:
    from clearcli.pipeline import Pipeline
    from clearcli.replay.session import ReplayOptions, Session
    from clearcli.settings.tree import load_settings
    from clearcli.sim.episode import Episode
    from clearcli.sim.scene import make_scene
    from clearcli.sim.truth import truth_segment

    settings = load_settings(None, ["robot.name=panda-hybrid"])
    pipeline = Pipeline(settings, segment_fn=truth_segment)
    episode = Episode(make_scene("alone", [box]), Session(pipeline, ReplayOptions()), seed=3, max_actions=max_actions)
    for _ in episode:
        pass
    assert episode.result is not None
    return episode.result, episode.scene


def test_a_big_light_box_the_estimate_calls_too_heavy_is_tried_and_taken() -> None:
    # 28 x 26 x 7 cm: 5.1 l, estimated at 650 kg/m^3 (the median household object's) 3.3
    # kg, which the cup does not hold with a safety factor of 2; truly 0.2 kg (a cereal
    # box). The session plans once more as if it were as light as a cracker box, against
    # the cup's own hold, and the world's cup lifts it
    from clearcli.sim.scene import Box

    box = Box(0, 0.28, 0.26, 0.07, 0.0, 0.0, 0.3, mass_kg=0.2)
    result, end = _alone(box, max_actions=3)
    done = [(s.action, s.outcome) for s in result.steps if s.action]
    assert done == [("(grasp_suction 0)", "removed")], done
    assert result.end == "cleared" and not end.objects


def test_a_box_truly_too_heavy_for_the_cup_costs_one_try() -> None:
    # the same box truly 8 kg (78 N against the cup's 57 N): the lift drops it where it
    # stood, and the cup is not tried on it again (its sides are too low for the hand's
    # body, its top failed)
    from clearcli.sim.scene import Box

    box = Box(0, 0.28, 0.26, 0.07, 0.0, 0.0, 0.3, mass_kg=8.0)
    result, end = _alone(box, max_actions=4)
    done = [(s.action, s.outcome) for s in result.steps if s.action]
    cups = [o for a, o in done if a.startswith("(grasp_suction ")]
    assert len(cups) == 1 and cups[0].startswith("suction failed: dropped: too heavy"), done
    assert result.end != "budget" and [o.object_id for o in end.objects] == [0], done
