"""Simulated sessions with the grasp kinds beyond the pinch, judged by the world's own
rules (clearcli/sim/physics.py: world_rim_grasp, world_slide, world_edge_pinch)."""

from __future__ import annotations

import dataclasses

from clearcli.sim import scene as S


def _session(world: S.Scene, robot: str = "panda", max_actions: int = 6):  # type: ignore[no-untyped-def]
    from clearcli.pipeline import Pipeline
    from clearcli.replay.session import ReplayOptions, Session
    from clearcli.settings.tree import load_settings
    from clearcli.sim.episode import Episode
    from clearcli.sim.truth import truth_segment

    settings = load_settings(None, [f"robot.name={robot}"])
    settings = dataclasses.replace(settings, plan=dataclasses.replace(settings.plan, probe_max_width_m=0.0))
    episode = Episode(
        world, Session(Pipeline(settings, segment_fn=truth_segment), ReplayOptions()), seed=0, max_actions=max_actions
    )
    for _ in episode:
        pass
    assert episode.result is not None
    return episode.result


def test_a_bowl_is_taken_by_its_rim_and_a_flat_box_slid_off_the_edge() -> None:
    bowl = S.Cylinder(0, 0.07, 0.06, -0.12, -0.05, wall_m=0.005)
    flat = S.Box(1, 0.20, 0.14, 0.03, 0.25, -0.15)
    result = _session(S.make_scene("wide", [bowl, flat]))
    done = [(s.action, s.outcome) for s in result.steps]
    assert ("(grasp_rim 0)", "removed") in done, done
    assert ("(slide_grasp 1)", "removed") in done, done
    assert result.cleared_truly


def test_the_world_refuses_a_rim_grasp_whose_finger_meets_the_handle() -> None:
    # The planner's rim model has no handle (the rim band is the top 8 mm; the handle
    # hangs below it): turned so that the handle lies where the chosen candidate's outer
    # finger goes down, the world's finger meets it and nothing is taken; turned away,
    # the same grasp holds.
    import math

    outcomes = {}
    for k in range(8):
        mug = S.Cylinder(0, 0.045, 0.095, -0.12, -0.05, yaw_rad=k * math.pi / 4, wall_m=0.004, handle_m=0.025)
        (step,) = _session(S.make_scene("mug", [mug]), max_actions=1).steps
        assert step.action == "(grasp_rim 0)"
        outcomes[k] = step.outcome
    assert any(o.startswith("rim grasp failed") and "handle" in o for o in outcomes.values()), outcomes
    assert any(o == "removed" for o in outcomes.values()), outcomes


def test_a_slide_into_a_neighbour_stops_short_and_the_pinch_fails() -> None:
    from clearcli.predicates.grasps.slide import EDGE_GRIP_M
    from clearcli.sim.physics import world_edge_pinch, world_slide

    # the world's rules alone, as _act applies them to the planner's slide: a block 2 cm
    # past the flat box's right face stops it before it overhangs the edge
    flat = S.Box(1, 0.20, 0.14, 0.03, 0.25, -0.15)
    block = S.Box(2, 0.03, 0.03, 0.05, 0.375, -0.15)
    world = S.make_scene("blocked", [flat, block])
    moved, travelled = world_slide(world, 0, [1.0, 0.0], 0.085)
    assert abs(travelled - 0.01) < 1e-3  # 0.35 -> 0.36, where the block's face is
    ok, why = world_edge_pinch(moved, 0, [1.0, 0.0], EDGE_GRIP_M, 0.08, 0.01)
    assert not ok and "slip" in why


def test_a_thick_flat_box_is_pinched_from_the_lower_tilt_the_planner_chose() -> None:
    # 5.5 cm thick: from 45 deg the Panda's jaws span at most 7 cm x cos 45 = 4.9 cm, so
    # the world holds it only because the arm came down at the planner's lower tilt
    # (about 35 deg, read off the checked pose), where they span 5.7 cm
    flat = S.Box(1, 0.20, 0.14, 0.055, 0.25, -0.15)
    result = _session(S.make_scene("thick", [flat]))
    done = [(s.action, s.outcome) for s in result.steps if s.action]
    assert done == [("(slide_grasp 1)", "removed")], done
    assert result.cleared_truly


def test_a_slide_that_moved_nothing_is_given_up_at_once(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    from clearcli.pipeline import Pipeline
    from clearcli.replay import session as session_mod
    from clearcli.replay.session import ReplayOptions, Session
    from clearcli.settings.tree import load_settings
    from clearcli.sim.episode import Episode

    # `clear simulate --seed 1000 --robot ur5e`: the segmenter sees boxes 2 and 4, which
    # touch, as one segment too wide for the 2F-85; its slide pushes box 2 into box 4 and
    # moves nothing. Given up after that one try, the segment is probed apart and cleared
    # (three tries, the pinch's rule, without the "moved nothing" check).
    def run():  # type: ignore[no-untyped-def]
        settings = load_settings(None, ["robot.name=ur5e"])
        episode = Episode(S.clutter(6, 1000), Session(Pipeline(settings), ReplayOptions()), seed=1000, max_actions=12)
        for _ in episode:
            pass
        assert episode.result is not None
        return episode.result

    result = run()
    slides = [s.outcome for s in result.steps if s.action.startswith("(slide_grasp")]
    assert len(slides) == 1 and "slid 0.000 m" in slides[0], slides
    assert result.end == "cleared" and result.cleared_truly
    monkeypatch.setattr(session_mod, "_STAYED_M", 0.0)
    slides = [s.outcome for s in run().steps if s.action.startswith("(slide_grasp")]
    assert len(slides) == 3, slides
