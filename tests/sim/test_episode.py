"""Tests of clearcli/sim/episode.py."""

from __future__ import annotations

import dataclasses

import pytest
from helpers import REPO
from helpers.clearing import _settings, _state

from clearcli.errors import NoPlanError
from clearcli.sim import scene as S

DOMAIN = REPO / "pddl" / "domain.pddl"


def test_hemmed_in_scene_ends_with_no_plan_and_the_reason_without_spinning() -> None:
    """A 9 cm box hemmed in on all four sides by boxes too wide for the gripper too (the
    middle one the tallest: lower, the front box would hide part of it from the camera)."""
    from clearcli.pipeline import Pipeline
    from clearcli.replay.session import ReplayOptions, Session
    from clearcli.sim.episode import Episode
    from clearcli.sim.truth import truth_segment

    centre = S.Box(0, 0.09, 0.09, 0.12, x_m=0.0, y_m=0.05)
    ring = [
        S.Box(1, 0.09, 0.09, 0.06, x_m=0.0915, y_m=0.05),
        S.Box(2, 0.09, 0.09, 0.06, x_m=-0.0915, y_m=0.05),
        S.Box(3, 0.09, 0.09, 0.06, x_m=0.0, y_m=0.05 + 0.0915),
        S.Box(4, 0.09, 0.09, 0.06, x_m=0.0, y_m=0.05 - 0.0915),
    ]
    world = S.make_scene("hemmed_in", [centre, *ring])
    settings = _settings()
    pipeline, state = _state(world, settings)
    with pytest.raises(NoPlanError, match="too wide") as err:
        pipeline.plan(state)
    plan = err.value.plan  # type: ignore[attr-defined]
    # every object seen is left with its reason: too wide (the box behind the tall one
    # may be hidden from the camera altogether)
    assert not plan.actions and len(state.objects) >= 4
    assert len(plan.left) == len(state.objects) and {left.reason for left in plan.left} == {"ungraspable"}
    assert plan.replans <= plan.max_backtracks == settings.plan.max_backtracks
    # the closed loop may push each of them to see whether it is two objects merged (at
    # most once along each of its two axes: [plan] probe_max_width_m), then stops with
    # "no plan" and the reason, well before the action budget; the world agrees that
    # nothing there fits the gripper, so the session counts as cleared
    episode = Episode(
        world, Session(Pipeline(settings, segment_fn=truth_segment), ReplayOptions()), seed=0, max_actions=40
    )
    frames = sum(1 for _ in episode)
    result = episode.result
    assert result is not None and result.end == "no_plan" and "too wide" in result.reason
    assert frames == result.actions + 1 and result.actions < 40 // 2
    probes = [r["plan"]["probe"] for r in episode.reports if r["plan"] and r["plan"]["probe"] is not None]
    assert probes and max(probes.count(p) for p in set(probes)) <= 2  # per track
    # a grasp the world refuses (the box behind, half hidden, looks narrower than it is)
    # is tried at most [plan] max_failed_grasps times in a row
    run = longest = 0
    previous = ""
    for step in result.steps:
        run = run + 1 if step.action.startswith("(grasp") and step.action == previous else 1
        previous = step.action
        if step.action.startswith("(grasp"):
            longest = max(longest, run)
    assert longest <= settings.plan.max_failed_grasps
    # without probing: no action at all
    no_probe = dataclasses.replace(settings, plan=dataclasses.replace(settings.plan, probe_max_width_m=0.0))
    episode = Episode(
        world, Session(Pipeline(no_probe, segment_fn=truth_segment), ReplayOptions()), seed=0, max_actions=40
    )
    assert sum(1 for _ in episode) == 1 and episode.result is not None and episode.result.actions == 0
    assert set(result.truly_ungraspable) == {0, 1, 2, 3, 4} and result.cleared_truly


def test_budget_spent_on_the_last_object_counts_as_cleared() -> None:
    from clearcli.pipeline import Pipeline
    from clearcli.replay.session import ReplayOptions, Session
    from clearcli.sim.episode import Episode
    from clearcli.sim.truth import truth_segment

    world = S.make_scene("one", [S.Box(0, 0.05, 0.04, 0.08, x_m=0.0, y_m=0.05)])
    episode = Episode(
        world, Session(Pipeline(_settings(), segment_fn=truth_segment), ReplayOptions()), seed=3, max_actions=1
    )
    for _ in episode:
        pass
    result = episode.result
    # (4 cm across: far from the 7 cm opening, a grasp of it never slips)
    assert result is not None and result.actions == 1 and result.remaining == ()
    assert result.end == "cleared" and result.cleared_truly


def test_cleared_truly_is_the_worlds_judgment_not_the_planners() -> None:
    from clearcli.sim.episode import EpisodeResult

    base = EpisodeResult(scene="s", seed=0, n_objects=3, steps=(), end="no_plan", remaining=(1, 2), unreachable=(1, 2))
    # the planner called 1 too wide and 2 out of reach: the old criterion passes either way
    claimed = dataclasses.replace(base, claimed_ungraspable=(1,))
    assert claimed.cleared_reachable and not claimed.cleared_truly and claimed.false_ungraspable == (1,)
    # the world agrees that 1 is too wide, but its own arm reaches 2: not cleared
    truly = dataclasses.replace(claimed, truly_ungraspable=(1,))
    assert not truly.cleared_truly and truly.false_ungraspable == ()
    # ... and when the world's arm cannot reach 2 either: cleared
    world = dataclasses.replace(truly, world_unreachable=(2,))
    assert world.cleared_truly
    # the world's verdict alone counts: the planner's "unreachable" list is not needed
    assert dataclasses.replace(world, unreachable=()).cleared_truly
    # out of reach because the robot pushed it there: not excused
    assert not dataclasses.replace(world, moved=(2,)).cleared_truly
    # anything else left is never excused, nor is anything when the budget ran out
    assert not dataclasses.replace(world, remaining=(1, 2, 3)).cleared_truly
    assert not dataclasses.replace(world, end="budget").cleared_truly
