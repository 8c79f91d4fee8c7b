"""Every numeric setting walked through NaN, infinities, 0, a negative and a huge value:
each is refused with one line naming the key, the value and the accepted range (exit 3
on the command line), or it lies in the documented range and the command it feeds runs
to a result or a user-facing error (a ClearError), never an internal error."""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import pytest

from clearcli.errors import ClearError, SettingsError
from clearcli.settings import SECTIONS, Settings, settings_from_dict
from clearcli.settings.fields import range_of

REPO = Path(__file__).resolve().parents[2]
WALK = (float("nan"), float("inf"), float("-inf"), 0, -1, 10**9)

# The command each section feeds, to run with an accepted extreme value.
PLAN = ("segment", "gripper", "push", "predicates", "plan", "robot")
REPLAY = ("replay", "tracking", "memory")
SIMULATE = ("world", "world_reach", "camera", "depth_noise")


def _numeric_keys(name: str) -> list[str]:
    cls = SECTIONS[name]
    return [f.name for f in dataclasses.fields(cls) if type(getattr(cls(), f.name)) in (int, float)]


def _run_plan(settings: Settings) -> None:
    from clearcli.tasks import plan
    from clearcli.tasks.base import Source

    plan.run(plan.Request(settings), Source(str(REPO / "fixtures" / "two_touching_boxes.pcd")))


def _run_replay(settings: Settings) -> None:
    from clearcli.tasks import replay

    replay.run(
        replay.Request(settings), REPO / "fixtures" / "simulated_session.mcap", None, lambda *a: None, lambda t: None
    )


def _run_simulate(settings: Settings, tmp: Path) -> None:
    from clearcli.tasks import simulate

    out = tmp / f"sim{time.monotonic_ns()}.mcap"
    simulate.run(simulate.Request(settings, scene="isolated_box", max_actions=3), out)


@pytest.mark.parametrize("section", list(SECTIONS))
def test_every_numeric_setting_is_refused_or_runs(section: str, tmp_path: Path) -> None:
    accepted: list[tuple[str, object]] = []
    for key in _numeric_keys(section):
        rng = range_of(SECTIONS[section], key)
        for value in WALK:
            try:
                settings = settings_from_dict({section: {key: value}})
            except SettingsError as exc:
                text = str(exc)
                assert "\n" not in text and f"[{section}] {key} = " in text, text
                assert rng.describe() in text, text
                continue
            # accepted: inside the documented range
            assert rng.holds(float(value)), (section, key, value)
            accepted.append((key, value))
            try:
                if section in PLAN:
                    _run_plan(settings)
                elif section in REPLAY:
                    _run_replay(settings)
                else:
                    _run_simulate(settings, tmp_path)
            except ClearError:
                pass  # a user-facing outcome (no table, no plan, ...), one line on the CLI
    # NaN, the infinities and the huge value are never accepted
    assert all(v in (0, -1) for _, v in accepted), accepted
