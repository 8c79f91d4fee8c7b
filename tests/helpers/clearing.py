"""Helpers that several test modules share (from the tests of clearing)."""

from __future__ import annotations

import dataclasses

from clearcli.settings import Settings
from clearcli.sim import scene as S


def _settings(raised: tuple[float, ...] | None = None) -> Settings:
    s = Settings()
    push = s.push if raised is None else dataclasses.replace(s.push, raised_fingertips_m=raised)
    plan = dataclasses.replace(s.plan, check="whole", replay_check="whole")
    return dataclasses.replace(s, push=push, plan=plan)


def _state(scene: S.Scene, settings: Settings, seed: int = 1):  # type: ignore[no-untyped-def]
    from clearcli.pipeline import Pipeline
    from clearcli.sim.camera import render
    from clearcli.sim.truth import truth_segment

    pipeline = Pipeline(settings, segment_fn=truth_segment)
    frame = render(scene, seed=seed)
    return pipeline, pipeline.state(frame, truth_segment(frame))
