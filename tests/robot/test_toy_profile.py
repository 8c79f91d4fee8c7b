"""What a new robot profile costs: its module, its description (URDF) and one line in the
registry (clearcli/settings/profiles.py `REGISTRY`). Here a toy arm -- the Panda's
description under another profile name -- is made by the test alone, in a temporary
folder, with the registry line added for the test's duration: nothing of the package is
edited. It is listed by `clear robots`, selectable with --robot (and [robot] name), has
its own picture label and plans a fixture frame, its every checked step landing on its
pose by the toy arm's own forward kinematics."""

from __future__ import annotations

import json
import shutil
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from helpers import FIXTURES

from clearcli.errors import SettingsError

TOY_MODULE = '''"""A toy arm: the Panda's description under another profile name."""

from pathlib import Path

from clearcli.robot.profiles.base import generic_profile

PROFILE = generic_profile(
    summary="Toy arm: the Panda's description under another name",
    urdf=Path(__file__).resolve().parent / "toy.urdf",
    base_frame="panda_link0",
    flange_frame="panda_link8",
    tcp_frame="panda_tcp",
    shoulder_base=(0.0, 0.0, 0.333),
    reach_m=0.855,
    tcp_past_flange_m=0.1034,
    gripper="toy hand (0.08 m open)",
    rest=(0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785),
)
'''


@pytest.fixture
def toy(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """The toy profile: its module and its URDF in ``tmp_path``, and one registry line."""
    from clearcli.robot.profiles import PROFILES
    from clearcli.settings.profiles import REGISTRY, ProfileEntry

    shutil.copy(PROFILES["panda"].urdf, tmp_path / "toy.urdf")
    (tmp_path / "toy_arm.py").write_text(TOY_MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    # the registry line (its [robot] and [gripper] defaults: the Panda's)
    monkeypatch.setitem(REGISTRY, "toy", ProfileEntry("toy_arm", REGISTRY["panda"].defaults))
    yield tmp_path
    sys.modules.pop("toy_arm", None)


def test_the_toy_profile_is_listed_by_clear_robots(toy: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from clearcli.commands.basic import robots_cmd
    from clearcli.tasks.robots import robots_payload

    robots_cmd(None, False)
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == [
        "wam",
        "panda",
        "ur5e",
        "panda-hybrid",
        "panda-suction",
        "ur5e-epick",
        "toy",
    ]
    assert (
        lines[-1].split(maxsplit=1) == ["toy", "Toy arm: the Panda's description under another name"]
        and "(default)" not in lines[-1]
    )
    facts = robots_payload("toy")["profile"]
    assert facts["name"] == "toy" and facts["urdf"] == str(toy / "toy.urdf")
    assert facts["base_frame"] == "panda_link0" and len(facts["joints"]) == 7
    assert facts["defaults"]["gripper"]["opening_width_m"] == 0.08
    robots_cmd("toy", True)
    assert json.loads(capsys.readouterr().out)["profile"]["name"] == "toy"


def test_the_toy_profile_is_selectable(toy: Path) -> None:
    from clearcli.commands.options import resolve_settings
    from clearcli.robot.arm import resolve_arm
    from clearcli.settings import load_settings

    settings = resolve_settings(None, None, "plan", robot="toy")
    assert settings.robot.name == "toy" and settings.gripper.opening_width_m == 0.08
    assert load_settings(sets=["robot.name=toy"]).robot.base_max_object_distance_m == 0.75
    (toy / "lab.toml").write_text('[robot]\nname = "toy"\n[gripper]\nopening_width_m = 0.07\n')
    assert load_settings(toy / "lab.toml").gripper.opening_width_m == 0.07
    with pytest.raises(SettingsError, match="known: wam, panda, ur5e, panda-hybrid, panda-suction, ur5e-epick, toy"):
        load_settings(sets=["robot.name=kuka"])
    arm = resolve_arm(settings)
    assert arm.name == "toy" and arm.profile.urdf == toy / "toy.urdf"
    assert arm.profile.picture_label == "TOY" and not arm.profile.thesis_camera
    with pytest.raises(SettingsError, match="thesis"):
        arm.place(None, "thesis")


def test_the_toy_profile_plans_a_fixture_frame(toy: Path) -> None:
    from clearcli.commands.options import resolve_settings
    from clearcli.robot.arm import resolve_arm
    from clearcli.tasks import plan as task
    from clearcli.tasks.base import Outputs, Source

    settings = resolve_settings(None, None, "plan", robot="toy")
    png = toy / "plan.png"
    outcome = task.run(task.Request(settings, outputs=Outputs.of(png=png)), Source(FIXTURES / "clutter10.pcd"))
    assert outcome.exit_code in (0, 10)
    doc = outcome.payload
    robot = doc["robot"]
    assert robot["name"] == "toy" and robot["base_frame"] == "panda_link0"
    assert robot["joint_names"] == [f"panda_joint{k}" for k in range(1, 8)]
    assert robot["gripper"] == {"name": "toy hand (0.08 m open)", "opening_width_m": 0.08, "closing_width_m": 0.01}
    assert png.stat().st_size > 0
    kin = resolve_arm(settings).kinematics()
    checked = [s for s in doc["steps"] if s["checked"]]
    assert len(checked) >= 5, doc["steps"]
    for step in checked:
        for q, T in zip(step["joints_rad"], step["T_base_gripper"]):
            got = kin.fk(np.array(q))
            assert np.linalg.norm(got[:3, 3] - np.array(T)[:3, 3]) < 0.001 + 2e-6


def test_without_its_registry_line_there_is_no_toy() -> None:
    from clearcli.robot.profiles import PROFILES
    from clearcli.settings import load_settings

    assert "toy" not in PROFILES
    with pytest.raises(SettingsError, match="known: wam, panda, ur5e, panda-hybrid, panda-suction, ur5e-epick \\("):
        load_settings(sets=["robot.name=toy"])
