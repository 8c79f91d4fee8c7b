"""Tests of clearcli/planning/probe.py."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from helpers.clearing import _settings, _state

from clearcli.planning.types import Plan
from clearcli.settings.geometry import GripperSettings
from clearcli.sim import scene as S


def _merged_pair() -> S.Scene:
    yaw = 0.4
    a = S.Box(0, 0.12, 0.045, 0.065, x_m=0.0, y_m=0.05, yaw_rad=yaw)
    b = S.Box(1, 0.12, 0.05, 0.065, x_m=-math.sin(yaw) * 0.0476, y_m=0.05 + math.cos(yaw) * 0.0476, yaw_rad=yaw)
    return S.make_scene("merged_pair", [a, b])


def _empty_plan(unreachable: tuple[str, ...] = (), ungraspable: tuple[str, ...] = ()) -> Plan:
    """A plan of no action that leaves out these objects (what the probe is asked about)."""
    return Plan(
        actions=(),
        cost=0,
        optimal=True,
        first=None,
        ik_facts=frozenset(),
        unreachable=unreachable,
        replans=0,
        ungraspable=ungraspable,
    )


@pytest.mark.parametrize("seed", [0, 1])
def test_probe_push_separates_a_merged_pair_and_the_session_clears(seed: int) -> None:
    from clearcli.pipeline import Pipeline
    from clearcli.replay.session import ReplayOptions, Session
    from clearcli.sim.episode import Episode

    # two 6.5 cm-tall boxes touching along their long sides: one 9.5 cm-wide segment
    settings = _settings()
    episode = Episode(_merged_pair(), Session(Pipeline(settings), ReplayOptions()), seed=seed, max_actions=12)
    for _ in episode:
        pass
    result = episode.result
    assert result is not None and result.end == "cleared" and result.cleared_truly
    probes = [r["plan"]["probe"] for r in episode.reports if r["plan"] and r["plan"]["probe"] is not None]
    assert 1 <= len(probes) <= 2 and all(s.action.startswith("(push") for s in result.steps[: len(probes)])
    # without probing the same session ends at once: "too wide"
    off = dataclasses.replace(settings, plan=dataclasses.replace(settings.plan, probe_max_width_m=0.0))
    episode = Episode(_merged_pair(), Session(Pipeline(off), ReplayOptions()), seed=seed, max_actions=12)
    for _ in episode:
        pass
    assert episode.result is not None and episode.result.end == "no_plan" and episode.result.actions == 0
    assert "too wide" in episode.result.reason and not episode.result.cleared_truly


def test_probe_candidates_exclude_what_fits_and_what_is_far_too_wide() -> None:
    from clearcli.planning.probe import probe_candidates

    _, state = _state(
        S.make_scene(
            "three",
            [
                S.Box(0, 0.05, 0.05, 0.08, x_m=-0.15, y_m=0.05),  # fits the gripper
                S.Box(1, 0.10, 0.10, 0.08, x_m=0.0, y_m=0.05),  # 10 cm: may be two
                S.Box(2, 0.20, 0.20, 0.05, x_m=0.2, y_m=0.05),  # 20 cm: more than two of the widest
            ],
        ),
        _settings(),
    )
    by_width = sorted(state.objects, key=lambda o: o.grasp_width_m)
    plan = _empty_plan(ungraspable=tuple(o.name for o in by_width))
    assert probe_candidates(state, plan, 0.07, 0.14) == [by_width[1].name]


def test_a_wide_object_whose_slide_failed_is_probed_too() -> None:
    from clearcli.planning.probe import probe_candidates

    # the 10 cm box is too wide for the pinch; left "unreachable" because its other
    # grasps (a slide) kept failing when carried out, it may still be two merged objects:
    # a probe candidate. Unreachable with no failure (its slide has no arm motion), it is
    # not one: a push would not make it graspable. Nor is an object the pinch fits.
    _, state = _state(
        S.make_scene(
            "two",
            [
                S.Box(0, 0.05, 0.05, 0.08, x_m=-0.15, y_m=0.05),
                S.Box(1, 0.10, 0.10, 0.08, x_m=0.0, y_m=0.05),
            ],
        ),
        _settings(),
    )
    narrow, wide = sorted(state.objects, key=lambda o: o.grasp_width_m)
    assert ("ungraspable", wide.name) in state.facts and ("ungraspable", narrow.name) not in state.facts
    plan = _empty_plan(unreachable=(narrow.name, wide.name))
    assert probe_candidates(state, plan, 0.07, 0.14) == []
    assert probe_candidates(state, plan, 0.07, 0.14, failed={wide.name, narrow.name}) == [wide.name]


def test_off_seam_moves_the_push_contact_towards_either_end_of_the_face() -> None:
    from clearcli.planning.probe import off_seam

    _, state = _state(S.make_scene("wide", [S.Box(0, 0.12, 0.10, 0.06, x_m=0.0, y_m=0.05)]), _settings())
    obj = state.objects[0]
    gripper = GripperSettings()
    for d in ("dir1", "dir3"):
        moved = off_seam(state, obj.name, d, gripper).by_name(obj.name).pushes[d]
        push = obj.pushes[d]
        assert len(moved.candidates) == 2 * len(push.candidates)
        across = float(obj.extents_m[1] if d == "dir1" else obj.extents_m[0])
        for k, seq in enumerate(push.candidates):
            closing = np.asarray(seq[1])[:3, 0]
            along = abs(float(closing @ np.asarray(push.unit_vector))) >= 0.7
            contact_half = 0.015 if along else 0.025  # a finger's width, or the closed pair
            reach = across / 2 - contact_half - 0.005
            for _sign, shifted in zip((1.0, -1.0), moved.candidates[2 * k : 2 * k + 2]):
                offset = np.asarray(shifted[1])[:3, 3] - np.asarray(seq[1])[:3, 3]
                # across the push, in the table plane, by the reach
                assert abs(float(offset @ np.asarray(push.unit_vector))) < 1e-9
                assert abs(float(offset @ state.table.normal)) < 1e-9
                assert float(np.linalg.norm(offset)) == pytest.approx(reach, abs=1e-9)
    # a face too narrow to move the contact by 1 cm: unchanged
    _, narrow = _state(S.make_scene("narrow", [S.Box(0, 0.12, 0.04, 0.06, x_m=0.0, y_m=0.05)]), _settings())
    o = narrow.objects[0]
    assert (
        off_seam(narrow, o.name, "dir1", gripper).by_name(o.name).pushes["dir1"].candidates
        == o.pushes["dir1"].candidates
    )
