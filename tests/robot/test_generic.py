"""Tests of clearcli/robot/generic.py (`UrdfKinematics`, the generic IK): forward
kinematics against IK round trips on our descriptions and on the third-party ones in
../shared/data (robots/, wam/), the steps that read a description, the public interface
the simulated world solves with, and a fresh search on a model read once."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers import shared_path
from helpers.robot import solved_on_their_poses

from clearcli.errors import SettingsError
from clearcli.robot.generic import UrdfKinematics


def _round_trips(kin: UrdfKinematics, n: int, seed: int) -> int:
    """FK of ``n`` random configurations within the limits, each solved by IK from no
    warm start; every solution within the limits and landing on its pose within the
    IK's tolerances. Returns how many were solved."""
    rng = np.random.default_rng(seed)
    poses = [kin.fk(q) for q in rng.uniform(kin.lower, kin.upper, size=(n, kin.lower.size))]
    return solved_on_their_poses(kin, poses, kin.tolerance_m + 1e-9, kin.tolerance_rad + 1e-9, slack=1e-12)


def _profile_kinematics(name: str) -> UrdfKinematics:
    from clearcli.robot.profiles import kinematics_from_settings
    from clearcli.settings import load_settings

    kin = kinematics_from_settings(load_settings(sets=[f"robot.name={name}"]).robot)
    assert isinstance(kin, UrdfKinematics)
    return kin


@pytest.mark.parametrize("name", ["panda", "ur5e"])
def test_the_shipped_descriptions_round_trip(name: str) -> None:
    # the Panda by damped least squares with restarts, the UR5e in closed form: every
    # pose of an in-limit configuration, whatever its orientation, is solved
    kin = _profile_kinematics(name)
    assert _round_trips(kin, 40, seed=1) == 40


def test_the_ur5e_round_trips_without_its_closed_form() -> None:
    from clearcli.robot.profiles import PROFILES

    kin = UrdfKinematics(PROFILES["ur5e"].urdf, "base_link", "robotiq_tcp", flange_frame="tool0")
    assert kin._closed is None
    assert _round_trips(kin, 40, seed=2) == 40


def test_the_third_party_panda_round_trips_and_is_our_panda() -> None:
    # example-robot-data's Panda with its two finger joints (held at 0), the closing point
    # given as an offset from its flange: the same arm as the profile's description
    urdf = shared_path("robots/panda/panda_collision.urdf")
    kin = UrdfKinematics(urdf, "", "", flange_frame="panda_link8", tcp_xyz_m=(0.0, 0.0, 0.1034), tcp_yaw_deg=45.0)
    assert kin.joint_names == tuple(f"panda_joint{k}" for k in range(1, 8))  # the fingers held
    assert kin.base_frame == "panda_link0" and kin.flange_frame == "panda_link8"
    assert _round_trips(kin, 40, seed=3) == 40
    ours = _profile_kinematics("panda")
    rng = np.random.default_rng(4)
    for q in rng.uniform(ours.lower, ours.upper, size=(50, 7)):
        np.testing.assert_allclose(kin.fk(q), ours.fk(q), atol=1e-12)
    # one pose solved by each lands on it by the other's forward kinematics
    T = ours.fk(rng.uniform(ours.lower, ours.upper))
    for a, b in ((kin, ours), (ours, kin)):
        q = a.ik(T)
        assert q is not None and np.linalg.norm(b.fk(q)[:3, 3] - T[:3, 3]) < 0.001


def test_the_third_party_wam_round_trips_with_the_generic_solver(caplog: pytest.LogCaptureFixture) -> None:
    # IRI's WAM description: its meshes are not shipped, so it loads without collision
    # shapes (one warning); the frames by default: the root link, the end of the chain
    urdf = shared_path("wam/iri_wam_description/urdf/wam.urdf")
    kin = UrdfKinematics(urdf, "", "", flange_frame="")
    assert len(kin.joint_names) == 7 and kin.base_frame == "iri_wam_link_footprint"
    assert kin.capsules(np.zeros(7))[0].shape == (0, 3)
    assert _round_trips(kin, 30, seed=5) == 30
    # the flange's reach from the shoulder: the WAM's 0.915 m (our analytic model's figure)
    from clearcli.robot.wam_kinematics import REACH_TOOL_PLATE_M

    assert kin.stretch_m == pytest.approx(REACH_TOOL_PLATE_M, abs=0.003)


def test_every_pose_of_the_arm_is_within_reach_and_far_ones_are_refused_at_once() -> None:
    kin = _profile_kinematics("panda")
    rng = np.random.default_rng(6)
    for q in rng.uniform(kin.lower, kin.upper, size=(300, 7)):
        assert kin.reachable(kin.fk(q), slack_m=0.0)
    far = np.eye(4)
    far[:3, 3] = kin.shoulder_bound + [kin.stretch_m + 0.2, 0.0, 0.0]
    starts = kin.stats.starts
    assert not kin.reachable(far) and kin.ik(far) is None
    assert kin.stats.starts == starts  # no IK start paid


def test_the_public_interface_the_world_solves_with() -> None:
    # target, solve_from, within_tolerance, pose_error: what clearcli/sim/reach.py uses
    kin = _profile_kinematics("panda")
    rng = np.random.default_rng(7)
    q = rng.uniform(kin.lower, kin.upper)
    T = kin.fk(q)
    target = kin.target(T)
    assert kin.within_tolerance(target, q)
    np.testing.assert_allclose(kin.pose_error(target, q), np.zeros(6), atol=1e-9)
    assert np.linalg.norm(kin.pose_error(target, np.clip(q + 0.1, kin.lower, kin.upper))) > 0.01
    start = np.clip(q + 0.05, kin.lower, kin.upper)
    got = kin.solve_from(target, start)
    assert got is not None and kin.within_tolerance(target, got)
    assert kin.solve_from(target, start, iterations=0) is None  # no step: not there yet
    # outside the limits: never within the tolerance
    assert not kin.within_tolerance(target, kin.upper + 0.1)


def test_a_fresh_search_answers_as_a_new_model_and_shares_what_was_read() -> None:
    kin = _profile_kinematics("panda")
    rng = np.random.default_rng(8)
    poses = [kin.fk(q) for q in rng.uniform(kin.lower, kin.upper, size=(12, 7))]
    first = [kin.ik(T) for T in poses]  # fills the cache and the ring of solved poses
    assert kin.stats.solves == 12
    fresh = kin.fresh()
    built = _profile_kinematics("panda")
    assert fresh.model is kin.model and fresh.data is not kin.data
    assert fresh.stats.solves == 0 and not fresh._cache and fresh._n_solved == 0
    again, new = [fresh.ik(T) for T in poses], [built.ik(T) for T in poses]
    for a, b in zip(again, new):
        assert (a is None) == (b is None)
        if a is not None:
            np.testing.assert_array_equal(a, b)
    # the original keeps its own search: its cache still answers
    hits = kin.stats.cache_hits
    np.testing.assert_array_equal(kin.ik(poses[0]), first[0])
    assert kin.stats.cache_hits == hits + 1 and fresh.stats.cache_hits == 0


def test_the_steps_that_read_a_description(tmp_path: Path) -> None:
    from clearcli.robot import generic
    from clearcli.robot.profiles import PROFILES

    panda = PROFILES["panda"].urdf
    full = generic._read_model(panda)
    # the root link and the end of the longest chain when not given
    base, flange = generic._arm_frames(full, panda, "", "", "")
    assert base == "panda_link0" and flange in ("panda_link8", "panda_hand", "panda_tcp")
    with pytest.raises(SettingsError, match="no frame 'nowhere'"):
        generic._arm_frames(full, panda, "nowhere", "", "")
    # nothing held on the shipped arm from its base; the whole chain above link 3 from there
    assert generic._joints_off_the_arm(full, panda, "panda_link0", "panda_link8") == [
        k for k in range(1, full.njoints) if full.names[k] not in {f"panda_joint{i}" for i in range(1, 8)}
    ]
    held = generic._joints_off_the_arm(full, panda, "panda_link3", "panda_link8")
    assert [full.names[k] for k in held][:3] == ["panda_joint1", "panda_joint2", "panda_joint3"]
    # the closing point as an offset: 0.1 m along the flange's z
    import pinocchio as pin

    model = pin.buildModelFromUrdf(str(panda))
    name = generic._add_tcp(model, "panda_link8", (0.0, 0.0, 0.1), 0.0)
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.zeros(model.nq))
    M = data.oMf[model.getFrameId("panda_link8")].actInv(data.oMf[model.getFrameId(name)])
    np.testing.assert_allclose(M.translation, [0.0, 0.0, 0.1], atol=1e-12)
    # a chain of three revolute joints is refused by name
    links = "".join(f"<link name='l{k}'/>" for k in range(4))
    joints = "".join(
        f"<joint name='j{k}' type='revolute'><parent link='l{k}'/><child link='l{k + 1}'/><axis xyz='0 0 1'/>"
        f"<origin xyz='0 0 0.1'/><limit lower='-1' upper='1' effort='1' velocity='1'/></joint>"
        for k in range(3)
    )
    short = tmp_path / "short.urdf"
    short.write_text(f"<robot name='s'>{links}{joints}</robot>")
    with pytest.raises(SettingsError, match="6 or more revolute"):
        generic._check_revolute(generic._read_model(short), short)
