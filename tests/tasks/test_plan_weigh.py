"""A plan that would remove nothing because a cup's load was judged on the estimated mass
is planned once more as light as a household object plausibly is (clearcli/tasks/plan.py
``_weigh_on_lift``, clearcli/settings/weigh.py), and says so: ``assumes`` in the
document, one line of text, exit 0 for a plan found."""

from __future__ import annotations

import json

import pytest
from helpers import FIXTURES, run_clear, shared_path

from clearcli.settings.tree import load_settings
from clearcli.settings.weigh import LIGHTEST_DENSITY_KG_M3, lightest_plausible
from clearcli.tasks import plan as task
from clearcli.tasks.base import Source

# a muesli box and a cereal box: both refused by suction as "too heavy for the cup" at
# [suction] density_kg_m3 650 with safety factor 2, both too wide for the fingers
LEARN26 = "mosd/learn/learn26.pcd"


def test_the_relaxed_settings_are_a_cracker_box_on_the_cups_own_hold() -> None:
    relaxed = lightest_plausible(load_settings(None, ["robot.name=panda-hybrid"]))
    assert relaxed is not None
    assert relaxed.suction.density_kg_m3 == LIGHTEST_DENSITY_KG_M3 == 170.0
    assert relaxed.suction.safety_factor == 1.0
    # a density the user set lighter still is kept, not raised
    lighter = lightest_plausible(load_settings(None, ["robot.name=panda-hybrid", "suction.density_kg_m3=90"]))
    assert lighter is not None and lighter.suction.density_kg_m3 == 90.0


@pytest.mark.parametrize(
    "sets",
    [
        ["robot.name=panda"],  # no cup
        ["robot.name=panda-hybrid", "plan.grasps=pinch,rim,slide"],  # suction not asked for
        ["robot.name=panda-hybrid", "suction.safety_factor=1"],  # the user's factor 1 is meant
    ],
)
def test_nothing_is_relaxed_without_a_cup_suction_or_a_margin(sets: list[str]) -> None:
    assert lightest_plausible(load_settings(None, sets)) is None


def test_learn26_with_the_hybrid_tool_plans_suction_and_says_it_assumes_a_light_mass() -> None:
    frame = shared_path(LEARN26)
    done = run_clear("plan", frame, "--robot", "panda-hybrid", "--json")
    assert done.returncode == 0, done.stderr  # a plan found is exit 0 (docs/exit-codes.md)
    doc = json.loads(done.stdout)  # validated against clearcli/schemas/plan.json by the helper
    suction = [s for s in doc["steps"] if s["grasp_kind"] == "suction"]
    assert suction and doc["status"] == "complete" and doc["left"] == []
    light = doc["assumes"]["suction_mass"]
    assert light["density_kg_m3"] == 170.0 and light["safety_factor"] == 1.0
    assert light["estimate_density_kg_m3"] == 650.0 and light["estimate_safety_factor"] == 2.0
    # the objects named are exactly those the plan lifts by suction (both boxes)
    assert light["objects"] == sorted({s["object"] for s in suction}) == ["o0", "o1"]
    text = run_clear("plan", frame, "--robot", "panda-hybrid")
    assert text.returncode == 0
    said = [line for line in text.stdout.splitlines() if line.startswith("assumes ")]
    assert said == [
        "assumes o0, o1 as light as 170 kg/m^3 on the cup's own hold (factor 1): the estimate at "
        "650 kg/m^3 with factor 2 refused them; the lift weighs them"
    ]


def test_learn26_without_a_cup_stays_no_plan() -> None:
    done = run_clear("plan", shared_path(LEARN26), "--robot", "panda", "--json")
    assert done.returncode == 5, done.stderr
    doc = json.loads(done.stdout)
    assert doc["status"] == "no_plan" and doc["actions"] == [] and "assumes" not in doc


def test_learn26_with_the_users_factor_1_is_planned_on_the_estimate_alone() -> None:
    # factor 1 is the user's word: no second attempt; the cereal box (o1) holds at 650
    # kg/m^3 on the cup's own hold, the muesli box (o0) does not and is left, unmarked
    args = ("--robot", "panda-hybrid", "--set", "suction.safety_factor=1", "--json")
    done = run_clear("plan", shared_path(LEARN26), *args)
    assert done.returncode == 10, done.stderr
    doc = json.loads(done.stdout)
    assert doc["actions"] == ["(grasp_suction o1)"] and "assumes" not in doc
    assert [x["object"] for x in doc["left"]] == ["o0"]
    assert "too heavy for the cup" in doc["left"][0]["detail"]


def test_learn26_through_the_task_layer_carries_the_marker() -> None:
    frame = shared_path(LEARN26)
    settings = load_settings(None, ["robot.name=panda-hybrid"])
    outcome = task.run(task.Request(settings), Source(str(frame)))
    assert outcome.exit_code == 0
    assert [s["grasp_kind"] for s in outcome.payload["steps"]] == ["suction", "suction"]
    assert outcome.payload["assumes"]["suction_mass"]["objects"] == ["o0", "o1"]


def test_a_frame_that_plans_on_the_estimate_has_no_marker() -> None:
    settings = load_settings(None, ["robot.name=panda-hybrid"])
    outcome = task.run(task.Request(settings), Source(str(FIXTURES / "box_on_box.pcd")))
    assert outcome.exit_code == 0 and outcome.payload["actions"]
    assert "assumes" not in outcome.payload
