"""Robot profiles (clearcli/robot/profiles): the registry, the defaults a profile
supplies, IK judged by forward kinematics on each profile, and the generic solver run
on the WAM beside its analytic one."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from helpers import run_clear as clear
from helpers.robot import solved_on_their_poses

from clearcli.errors import SettingsError
from clearcli.settings import load_settings


def _tool_down_poses(kin, n: int, seed: int) -> list[np.ndarray]:
    """Forward kinematics of random in-limit configurations whose gripper points down
    (approach within 30 degrees of straight down) and whose closing point is above the
    base's plane: the poses a table-clearing plan asks for."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        T = kin.fk(rng.uniform(kin.lower, kin.upper))
        if T[2, 2] < -np.cos(np.radians(30)) and T[2, 3] > -0.3:
            out.append(T)
    return out


def test_the_registry_and_the_settings_name_the_same_profiles() -> None:
    from clearcli.robot.profiles import PROFILES, profile
    from clearcli.settings.profiles import PROFILE_NAMES, REGISTRY

    assert (
        tuple(PROFILES)
        == tuple(REGISTRY)
        == tuple(PROFILE_NAMES)
        == ("wam", "panda", "ur5e", "panda-hybrid", "panda-suction", "ur5e-epick")
    )
    with pytest.raises(SettingsError, match="known: wam, panda, ur5e, panda-hybrid"):
        profile("kuka")
    for p in PROFILES.values():
        assert p.urdf.exists() and p.reach_m > 0.5


def test_a_profile_supplies_defaults_that_a_user_overrides(tmp_path) -> None:
    assert load_settings().robot.name == "wam" and load_settings().gripper.opening_width_m == 0.07
    panda = load_settings(sets=["robot.name=panda"])
    assert panda.gripper.opening_width_m == 0.08 and panda.robot.base_max_object_distance_m == 0.75
    # --set after the profile wins over it
    assert load_settings(sets=["robot.name=ur5e", "gripper.opening_width_m=0.1"]).gripper.opening_width_m == 0.1
    # a file's [gripper] wins over a profile given by --set, as over the tree's defaults
    f = tmp_path / "lab.toml"
    f.write_text("[gripper]\nopening_width_m = 0.09\n")
    s = load_settings(f, ["robot.name=panda"])
    assert s.robot.name == "panda" and s.gripper.opening_width_m == 0.09 and s.gripper.finger_width_m == 0.02
    # and a file that names the profile itself
    f.write_text('[robot]\nname = "ur5e"\n[gripper]\nopening_width_m = 0.07\n')
    s = load_settings(f)
    assert s.robot.name == "ur5e" and s.gripper.opening_width_m == 0.07 and s.gripper.base_width_m == 0.15
    with pytest.raises(SettingsError, match="robot"):
        load_settings(sets=["robot.name=kuka"])


@pytest.mark.parametrize("name", ["wam", "panda", "ur5e"])
def test_ik_of_each_profile_lands_on_the_pose_by_forward_kinematics(name: str) -> None:
    from clearcli.robot.profiles import kinematics_from_settings

    kin = kinematics_from_settings(load_settings(sets=[f"robot.name={name}"]).robot)
    poses = _tool_down_poses(kin, 150, seed=7)
    # within 1 mm and 0.01 rad, the default IK tolerances
    solved = solved_on_their_poses(kin, poses, 0.001 + 1e-9, 0.01 + np.radians(1e-6), slack=1e-9)
    assert solved >= 0.99 * len(poses), f"{name}: {solved} of {len(poses)}"
    # far beyond the stretch: no solution, at once
    far = np.eye(4)
    far[:3, 3] = [2.0, 0.0, 0.2]
    assert not kin.reachable(far) and kin.ik(far) is None


@pytest.mark.parametrize("name", ["panda", "ur5e"])
def test_the_measured_reach_bounds_hold_and_refuse_what_the_summed_links_let_through(name: str) -> None:
    import pinocchio as pin

    from clearcli.robot.profiles import kinematics_from_settings

    kin = kinematics_from_settings(load_settings(sets=[f"robot.name={name}"]).robot)
    w = kin._wrist
    model = kin.model
    data = model.createData()
    last = model.njoints - 1
    previous = int(model.parents[last])
    shoulder = int(kin._arm_from_joint)
    # the bounds against a denser random search than the one that made them: none of
    # 20,000 configurations puts the flange or the wrist joint beyond them
    rng = np.random.default_rng(11)
    far_flange = far_wrist = 0.0
    for q in rng.uniform(kin.lower, kin.upper, size=(20000, model.nq)):
        pin.framesForwardKinematics(model, data, q)
        o = data.oMi[shoulder].translation
        far_flange = max(far_flange, float(np.linalg.norm(data.oMf[kin.flange_id].translation - o)))
        far_wrist = max(far_wrist, float(np.linalg.norm(data.oMi[previous].translation - o)))
    assert far_flange <= w.flange_m and far_wrist <= w.previous_m
    # and not loose: the search comes within 2 cm of them (a Panda's flange 0.858 m,
    # the links summed 0.986 m)
    assert w.flange_m - far_flange < 0.02 and w.previous_m - far_wrist < 0.02
    links = sum(float(np.linalg.norm(model.jointPlacements[k].translation)) for k in range(shoulder + 1, model.njoints))
    links += float(np.linalg.norm(model.frames[kin.flange_id].placement.translation))
    assert w.flange_m < links
    # every pose of an in-limit configuration passes reachable(), with no slack at all
    for q in rng.uniform(kin.lower, kin.upper, size=(3000, model.nq)):
        assert kin.reachable(kin.fk(q), slack_m=0.0)
    # a tool-down pose within the summed links but past the measured flange bound: the
    # old test let it through to every IK start, the measured one refuses it at once
    down = np.diag([1.0, -1.0, -1.0, 1.0])
    shoulder_xyz = kin.shoulder_bound
    tcp_past_flange = float(np.linalg.norm(np.asarray(kin.M_flange_tcp.translation)))
    down[:3, 3] = shoulder_xyz + [w.flange_m + 0.03, 0.0, -tcp_past_flange]
    assert np.linalg.norm(down[:3, 3] + [0, 0, tcp_past_flange] - shoulder_xyz) < links
    assert not kin.reachable(down) and kin.ik(down) is None


def test_the_generic_solver_on_the_wam_agrees_with_the_analytic_one() -> None:
    from clearcli.robot.generic import UrdfKinematics
    from clearcli.robot.wam_kinematics import BASE_FRAME, TCP_FRAME, TOOL_PLATE_FRAME, URDF_PATH, WamKinematics

    analytic = WamKinematics()
    generic = UrdfKinematics(
        URDF_PATH,
        BASE_FRAME,
        TCP_FRAME,
        flange_frame=TOOL_PLATE_FRAME,
        rest=(0.0, 0.9, 0.0, 1.6, 0.0, 0.6, 0.0),
        n_seeds=16,
    )
    poses = _tool_down_poses(analytic, 100, seed=3)
    both = 0
    for T in poses:
        qa, qg = analytic.ik(T), generic.ik(T)
        assert qa is not None  # FK of an in-limit configuration: the analytic solver finds it
        if qg is not None:
            both += 1
            for kin, q in ((analytic, qa), (generic, qg)):
                assert np.linalg.norm(kin.fk(q)[:3, 3] - T[:3, 3]) < 0.001 + 1e-9
    assert both >= 97, both
    # one model: the two agree on forward kinematics and on the capsules' count
    q = np.array([0.3, 0.8, -0.2, 1.5, 0.1, 0.5, 0.2])
    np.testing.assert_allclose(generic.fk(q), analytic.fk(q), atol=1e-9)


def test_robots_lists_the_profiles_and_prints_one() -> None:
    res = clear("robots")
    assert res.returncode == 0 and [line.split()[0] for line in res.stdout.splitlines()] == list(
        ("wam", "panda", "ur5e", "panda-hybrid", "panda-suction", "ur5e-epick")
    )
    res = clear("robots", "panda", "--json")
    doc = json.loads(res.stdout)
    assert doc["schema"] == "clear.robots"
    facts = doc["profile"]
    assert facts["base_frame"] == "panda_link0" and len(facts["joints"]) == 7
    assert facts["defaults"]["gripper"]["opening_width_m"] == 0.08
    res = clear("robots", "kuka")
    assert res.returncode == 3 and "known: wam, panda, ur5e, panda-hybrid" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    res = clear("plan", "fixtures/clutter10.pcd", "--robot", "kuka")
    assert res.returncode == 3 and "known" in res.stderr
    res = clear("plan", "fixtures/clutter10.pcd", "--robot", "panda", "--camera-pose", "thesis")
    assert res.returncode == 3 and "WAM" in res.stderr


@pytest.mark.parametrize("name, base", [("panda", "panda_link0"), ("ur5e", "base_link")])
def test_plan_with_another_robot_lands_every_step_on_its_recorded_pose(name: str, base: str) -> None:
    from clearcli.robot.profiles import kinematics_from_settings

    res = clear("plan", "fixtures/clutter10.pcd", "--robot", name, "--json")
    assert res.returncode in (0, 10), res.stderr
    doc = json.loads(res.stdout)
    assert doc["version"] == 5 and doc["robot"]["name"] == name and doc["robot"]["base_frame"] == base
    kin = kinematics_from_settings(load_settings(sets=[f"robot.name={name}"]).robot)
    assert doc["robot"]["joint_names"] == list(kin.joint_names)
    checked = [s for s in doc["steps"] if s["checked"]]
    assert len(checked) >= 5, doc["steps"]
    for step in checked:
        for q, T in zip(step["joints_rad"], step["T_base_gripper"]):
            assert len(q) == len(kin.joint_names)
            got = kin.fk(np.array(q))
            assert np.linalg.norm(got[:3, 3] - np.array(T)[:3, 3]) < 0.001 + 2e-6  # the JSON rounds to 1e-6


def _panda_of_a_user(urdf: object) -> list[str]:
    """The --set options that make ``urdf`` (a third-party Panda) the robot as a user's own
    file: its flange named, the closing point given as an offset from the flange."""
    sets = (
        f"robot.urdf={urdf}",
        "robot.flange_frame=panda_link8",
        "robot.tcp_xyz_m=[0, 0, 0.1034]",
        "robot.tcp_yaw_deg=45",
    )
    return [word for value in sets for word in ("--set", value)]


def test_a_users_urdf_plans_as_the_profile_of_that_arm() -> None:
    # the third-party Panda (with finger joints, held at 0) read as a user's own file,
    # the closing point given as an offset from its flange: the plan of the panda profile
    from helpers import shared_path

    urdf = shared_path("robots/panda/panda_collision.urdf")
    user = clear("plan", "fixtures/clutter10.pcd", "--robot", "panda", "--json", *_panda_of_a_user(urdf))
    ours = clear("plan", "fixtures/clutter10.pcd", "--robot", "panda", "--json")
    # 10: clutter10's partial plan (two touching boxes one segment since issue 37's grid)
    assert user.returncode == ours.returncode and ours.returncode in (0, 10), user.stderr
    a, b = json.loads(user.stdout), json.loads(ours.stdout)
    assert a["actions"] == b["actions"] and a["status"] == b["status"]
    assert a["robot"]["name"] == "urdf" and a["robot"]["joint_names"] == b["robot"]["joint_names"]
    for x, y in zip(a["steps"], b["steps"]):
        if x["T_base_gripper"] is not None and y["T_base_gripper"] is not None and x["candidate"] == y["candidate"]:
            np.testing.assert_allclose(x["T_base_gripper"], y["T_base_gripper"], atol=2e-6)


def test_bad_robot_settings_are_one_line_exit_3(tmp_path) -> None:
    from helpers import shared_path

    panda = shared_path("robots/panda/panda_collision.urdf")
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'/><joint name='j' type='revolute'>")
    short = tmp_path / "short.urdf"  # three revolute joints
    links = "".join(f"<link name='l{k}'/>" for k in range(4))
    joints = "".join(
        f"<joint name='j{k}' type='revolute'><parent link='l{k}'/><child link='l{k + 1}'/><axis xyz='0 0 1'/>"
        f"<origin xyz='0 0 0.1'/><limit lower='-1' upper='1' effort='1' velocity='1'/></joint>"
        for k in range(3)
    )
    short.write_text(f"<robot name='s'>{links}{joints}</robot>")
    cases = [
        (["--robot", "kuka"], "known: wam, panda, ur5e"),
        (["--set", f"robot.urdf={bad}"], "not a URDF"),
        (["--set", f"robot.urdf={tmp_path / 'none.urdf'}"], "not found"),
        (["--set", f"robot.urdf={panda}", "--set", "robot.flange_frame=tool0"], "no frame 'tool0'"),
        (["--set", f"robot.urdf={short}"], "6 or more revolute"),
        (["--set", "gripper.closing_width_m=0.09"], "closing_width_m"),
        (["--set", f"robot.urdf={panda}", "--set", "robot.tcp_xyz_m=[0.4, 0, 0.4]"], "0.5 m"),
        (["--set", "robot.flange_frame=x"], "give urdf too"),
    ]
    for args, words in cases:
        res = clear("plan", "fixtures/clutter10.pcd", *args)
        assert res.returncode == 3, (args, res.stderr)
        lines = res.stderr.strip().splitlines()
        assert len(lines) == 1 and words in lines[0], (args, res.stderr)
    # the frame error lists the file's frames
    res = clear("plan", "fixtures/clutter10.pcd", "--set", f"robot.urdf={panda}", "--set", "robot.flange_frame=tool0")
    assert "panda_link8" in res.stderr


def test_a_urdf_whose_meshes_are_missing_loads_with_one_warning() -> None:
    from helpers import shared_path

    urdf = shared_path("robots/panda/panda.urdf")  # mesh references, meshes not shipped
    res = clear("plan", "fixtures/clutter10.pcd", "--robot", "panda", *_panda_of_a_user(urdf))
    assert res.returncode in (0, 10), res.stderr
    warnings = [line for line in res.stderr.splitlines() if "collision mesh(es) not found, left out" in line]
    assert len(warnings) == 1 and "Traceback" not in res.stderr


def test_a_missing_mesh_leaves_the_other_collision_shapes(tmp_path) -> None:
    # the shipped Panda with link 3's collision shapes replaced by a mesh that is not
    # there: link 3 loses its capsules, every other link keeps its own
    from clearcli.robot.generic import UrdfKinematics
    from clearcli.robot.profiles import PROFILES

    text = PROFILES["panda"].urdf.read_text()
    start = text.index('<link name="panda_link3"')
    end = text.index("</link>", start)
    body = text[start:end]
    first, last = body.index("<collision>"), body.rindex("</collision>") + len("</collision>")
    body = (
        body[:first]
        + '<collision><geometry><mesh filename="package://nowhere/link3.stl"/></geometry></collision>'
        + body[last:]
    )
    urdf = tmp_path / "panda_mixed.urdf"
    urdf.write_text(text[:start] + body + text[end:])
    args = dict(flange_frame="panda_link8", tcp_xyz_m=(0, 0, 0.1034))
    full = UrdfKinematics(PROFILES["panda"].urdf, "panda_link0", "", **args)
    mixed = UrdfKinematics(urdf, "panda_link0", "", **args)
    joints = lambda kin: sorted(j for j, *_ in kin._capsule_parts)  # noqa: E731
    assert 3 in joints(full) and 3 not in joints(mixed)
    assert [j for j in joints(full) if j != 3] == joints(mixed)


@pytest.mark.parametrize("name, base", [("panda", "panda_link0"), ("ur5e", "base_link")])
def test_a_simulated_session_per_profile(tmp_path, name: str, base: str) -> None:
    # the world judges reach with its own solver (SciPy's least squares) for the arm,
    # records the profile's base frame on /tf_static, and replay finds it there
    log = tmp_path / f"{name}.mcap"
    res = clear("simulate", log, "--seed", "1000", "--robot", name, "--json")
    assert res.returncode == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["end"] == "cleared" and doc["cleared_truly"]
    res = clear("replay", log, "--robot", name)
    assert res.returncode == 0 and f"robot base: {base}" in res.stderr, res.stderr


def test_the_worlds_solver_for_another_arm_lands_on_the_pose() -> None:
    from clearcli.robot.arm import resolve_arm
    from clearcli.settings.geometry import GripperSettings, PushSettings
    from clearcli.sim.reach import WorldReach

    settings = load_settings(sets=["robot.name=panda"])
    world = WorldReach(np.eye(4), GripperSettings(), PushSettings(), robot=resolve_arm(settings))
    assert world.solver == "least_squares"
    solved = 0
    for T in _tool_down_poses(world.kin, 20, seed=5):
        T = T.copy()
        T[2, 3] = max(T[2, 3], 0.15)  # above the world's table top (z = 0 here)
        q = world._solve(T, None)
        if q is not None:
            solved += 1
            assert np.linalg.norm(world.kin.fk(q)[:3, 3] - T[:3, 3]) < 0.001
    assert solved >= 10, solved


def test_the_ur_closed_form_matches_the_description_and_its_solutions_land() -> None:
    # ur_ik's DH table is the shipped UR5e: its frame 6 in its base frame is Pinocchio's
    # wrist_3_link in base_link_inertia; every solution it gives lands on the pose
    import pinocchio as pin

    from clearcli.robot.profiles import PROFILES
    from clearcli.robot.ur_ik import UR5E, fk, solutions

    model = pin.buildModelFromUrdf(str(PROFILES["ur5e"].urdf))
    data = model.createData()
    rng = np.random.default_rng(4)
    for _ in range(200):
        q = rng.uniform(-np.pi, np.pi, 6)
        pin.framesForwardKinematics(model, data, q)
        M = data.oMf[model.getFrameId("base_link_inertia")].actInv(data.oMf[model.getFrameId("wrist_3_link")])
        T = fk(UR5E, q)
        np.testing.assert_allclose(T, M.homogeneous, atol=1e-8)
        sols = solutions(UR5E, T)
        assert 1 <= len(sols) <= 8
        assert any(np.allclose(np.angle(np.exp(1j * (s - q))), 0, atol=1e-6) for s in sols)  # q itself among them
        for s in sols:
            np.testing.assert_allclose(fk(UR5E, s), T, atol=1e-8)
    far = np.eye(4)
    far[:3, 3] = [0.0, 0.0, 2.0]
    assert solutions(UR5E, far) == []


def test_profile_names_are_written_in_the_registry_only() -> None:
    # clearcli/settings/profiles.py names the profiles; no other module of the package
    # holds a profile's name as text (no `name == "wam"`: a profile says what differs)
    import ast
    from pathlib import Path

    import clearcli
    from clearcli.settings.profiles import REGISTRY

    root = Path(clearcli.__file__).parent
    found = []
    for path in sorted(root.rglob("*.py")):
        if path == root / "settings" / "profiles.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in REGISTRY:
                found.append(f"{path.relative_to(root)}:{node.lineno}: {node.value!r}")
    assert not found, found
    # the --robot help and the settings' choices are made from the registry
    from clearcli.settings.fields import range_of
    from clearcli.settings.profiles import DEFAULT_PROFILE, names_text
    from clearcli.settings.robot import RobotSettings

    assert tuple(range_of(RobotSettings, "name").choices) == tuple(REGISTRY)
    assert RobotSettings().name == DEFAULT_PROFILE == next(iter(REGISTRY))
    res = clear("plan", "--help")
    # (the help wraps a hyphenated name at its hyphen: joined back before comparing)
    assert res.returncode == 0 and names_text() in re.sub(r"-\s+", "-", " ".join(res.stdout.split()))


def test_a_plan_resolves_its_robot_once(monkeypatch: pytest.MonkeyPatch, tmp_path) -> None:
    # placement, planning, the payload's robot block and the picture share one resolved
    # arm: the profile is looked up once per frame (it was four times)
    from helpers import FIXTURES

    import clearcli.robot.profiles as profiles
    from clearcli.tasks import plan as task
    from clearcli.tasks.base import Outputs, Source

    looked_up: list[str] = []
    real = profiles.profile
    monkeypatch.setattr(profiles, "profile", lambda name: looked_up.append(name) or real(name))
    png = tmp_path / "plan.png"
    outcome = task.run(task.Request(load_settings(), outputs=Outputs.of(png=png)), Source(FIXTURES / "clutter10.pcd"))
    assert outcome.exit_code in (0, 10) and outcome.payload["robot"]["name"] == "wam" and png.stat().st_size > 0
    assert looked_up == ["wam"]
