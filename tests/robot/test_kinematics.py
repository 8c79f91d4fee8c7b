"""Tests of clearcli/robot/wam_kinematics.py (the WAM's kinematics)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import shared_path
from helpers.robot import (
    _trans,
    kin,  # noqa: F401  (fixtures)
)

from clearcli.robot.kinematics import half_turn
from clearcli.robot.wam_kinematics import REACH_TOOL_PLATE_M, WamKinematics


def test_urdf_straight_up_at_zero(kin: WamKinematics) -> None:
    # Hand-derived from the DH table: 0.55 + 0.30 + 0.06 = 0.91 m to the tool plate,
    # the gripper TCP 0.115 m further; the shoulder 0.346 m above the footprint.
    q = np.zeros(7)
    np.testing.assert_allclose(kin.fk(q, "wam_tool_plate"), _trans(0, 0, 0.91), atol=1e-12)
    np.testing.assert_allclose(kin.fk(q), _trans(0, 0, 1.025), atol=1e-12)
    np.testing.assert_allclose(kin.fk(q, "wam_link_footprint"), _trans(0, 0, -0.346), atol=1e-12)
    # Joint limits: the manual's column.
    np.testing.assert_allclose(kin.lower, [-2.6, -2.0, -2.8, -0.9, -4.76, -1.6, -3.0])
    np.testing.assert_allclose(kin.upper, [2.6, 2.0, 2.8, 3.1, 1.24, 1.6, 3.0])
    assert REACH_TOOL_PLATE_M == pytest.approx(0.915, abs=0.001)


def test_elbow_bent_by_hand(kin: WamKinematics) -> None:
    # q4 = pi/2: the forearm (0.30 m) and tool plate (0.06 m) point along base +x (the elbow
    # turns about base +y... through DH frames: rows 3/4 give x offsets 0.045 - ...).
    q = np.array([0.0, 0.0, 0.0, math.pi / 2, 0.0, 0.0, 0.0])
    T = kin.fk(q, "wam_tool_plate")
    # Shoulder to elbow: (0.045, 0, 0.55). Elbow frame turned by +pi/2 about base y
    # sends the forearm's z along +x, and the -0.045 offset along +z.
    np.testing.assert_allclose(T[:3, 3], [0.045 + 0.36, 0.0, 0.55 + 0.045], atol=1e-9)


def test_fk_matches_third_party_urdf(kin: WamKinematics) -> None:
    import pinocchio as pin

    urdf = shared_path("wam/iri_wam_description/urdf/wam.urdf")
    ref = pin.buildModelFromUrdf(str(urdf))
    data = ref.createData()
    base = ref.getFrameId("iri_wam_link_base")  # the shoulder; footprint offset (0.22, 0.14, 0.346)
    tcp = ref.getFrameId("iri_wam_link_tcp")  # 0.06 m past link 7 = our tool plate
    lo = np.maximum(kin.lower, ref.lowerPositionLimit)
    hi = np.minimum(kin.upper, ref.upperPositionLimit)
    rng = np.random.default_rng(7)
    worst_m, worst_rad = 0.0, 0.0
    for _ in range(300):
        q = rng.uniform(lo, hi)
        ours = kin.fk(q, "wam_tool_plate")
        pin.framesForwardKinematics(ref, data, q)
        theirs = np.array((data.oMf[base].inverse() * data.oMf[tcp]).homogeneous)
        worst_m = max(worst_m, float(np.linalg.norm(ours[:3, 3] - theirs[:3, 3])))
        worst_rad = max(worst_rad, float(np.linalg.norm(pin.log3(ours[:3, :3].T @ theirs[:3, :3]))))
    assert worst_m < 0.001
    assert worst_rad < 0.01


def test_ik_round_trips(kin: WamKinematics) -> None:
    rng = np.random.default_rng(3)
    solved = 0
    for _ in range(60):
        q_true = rng.uniform(kin.lower, kin.upper)
        target = kin.fk(q_true)
        q = kin.ik(target)
        if q is None:
            continue
        solved += 1
        got = kin.fk(q)
        assert np.linalg.norm(got[:3, 3] - target[:3, 3]) < 0.001
        R_err = got[:3, :3].T @ target[:3, :3]
        assert math.acos(np.clip((np.trace(R_err) - 1) / 2, -1, 1)) < 0.01
        assert np.all(q >= kin.lower - 1e-12) and np.all(q <= kin.upper + 1e-12)
    assert solved >= 57  # FK-generated targets are reachable by construction


def test_ik_top_grasp_and_out_of_reach(kin: WamKinematics) -> None:
    down = np.diag([1.0, -1.0, -1.0])  # approach along -z
    T = np.eye(4)
    T[:3, :3] = down
    T[:3, 3] = [0.6, 0.1, -0.25]  # on a table 0.346 m below the shoulder
    q = kin.ik(T)
    assert q is not None
    np.testing.assert_allclose(kin.fk(q)[:3, 3], T[:3, 3], atol=0.001)
    # warm start from that solution converges to a nearby pose
    T2 = T.copy()
    T2[:3, 3] += [0.0, 0.03, 0.0]
    q2 = kin.ik(T2, warm=q)
    assert q2 is not None and np.max(np.abs(q2 - q)) < 0.5
    far = T.copy()
    far[:3, 3] = [1.3, 0.0, -0.25]
    assert not kin.reachable(far)
    assert kin.ik(far) is None
    # half-turn about the approach axis: same position and approach, closing axis flipped
    H = half_turn(T)
    np.testing.assert_allclose(H[:3, 2], T[:3, 2])
    np.testing.assert_allclose(H[:3, 0], -T[:3, 0])


TABLE_Z = -0.346  # table top in the base frame at the default placement


def _top_down(x: float, y: float, z: float, yaw: float = 0.0) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    T = np.eye(4)
    T[:3, :3] = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ np.diag([1.0, -1.0, -1.0])
    T[:3, 3] = [x, y, z]
    return T


def _top_down_configs(kin: WamKinematics, n: int, seed: int) -> list[np.ndarray]:
    """Random joint configurations within the limits whose tool points straight down,
    with the TCP 0.01-0.30 m above the table and 0.25-0.90 m in front of the shoulder's
    axis: q1-q4 and q7 uniform, q5 and q6 turn the tool down (Pinocchio's FK of link 5's
    frame at q5 = 0, i.e. DH frame 4)."""
    rng = np.random.default_rng(seed)
    out: list[np.ndarray] = []
    while len(out) < n:
        q = rng.uniform(kin.lower, kin.upper)
        q[4:6] = 0.0
        R4 = kin.fk(q, "wam_link_5")[:3, :3]
        u = R4.T @ np.array([0.0, 0.0, -1.0])  # want Rz(q5) Ry(q6) z = u
        q6 = math.acos(float(np.clip(u[2], -1.0, 1.0))) * rng.choice([-1.0, 1.0])
        q5 = math.atan2(u[1], u[0]) + (math.pi if q6 < 0 else 0.0)
        q5 = kin.lower[4] + (q5 - kin.lower[4]) % (2 * math.pi)
        q[4], q[5] = q5, q6
        if np.any(q < kin.lower) or np.any(q > kin.upper):
            continue
        T = kin.fk(q)
        h, r = T[2, 3] - TABLE_Z, math.hypot(T[0, 3], T[1, 3])
        if 0.01 <= h <= 0.30 and 0.25 <= r <= 0.90 and T[0, 3] > 0:
            assert T[2, 2] == pytest.approx(-1.0, abs=1e-9)  # straight down by construction
            out.append(q)
    return out


def _assert_solves(kin: WamKinematics, q: np.ndarray | None, T: np.ndarray) -> None:
    assert q is not None
    assert np.all(q >= kin.lower) and np.all(q <= kin.upper)
    got = kin.fk(q)
    assert np.linalg.norm(got[:3, 3] - T[:3, 3]) < kin.tolerance_m
    R_err = got[:3, :3].T @ T[:3, :3]
    assert math.acos(np.clip((np.trace(R_err) - 1) / 2, -1, 1)) < kin.tolerance_rad


def test_ik_top_down_poses_checked_by_fk(kin: WamKinematics) -> None:
    # FK of 150 top-down configurations: each has a solution, so all should be found,
    # by the default solver and by the swivel sweep alone.
    configs = _top_down_configs(kin, 150, seed=11)
    fresh, sweep = WamKinematics(), WamKinematics()  # no cache shared with other tests
    sweep.track_iterations = 0
    for solver in (fresh, sweep):
        for q_true in configs:
            T = kin.fk(q_true)
            _assert_solves(kin, solver.ik(T), T)
    assert sweep.analytic and sweep.stats.starts == 0 and sweep.stats.sweeps >= len(configs)
    # the same pose gets the same answer from another instance
    for solver in (fresh, sweep):
        other = WamKinematics()
        other.track_iterations = solver.track_iterations
        for q_true in configs[:10]:
            T = kin.fk(q_true)
            np.testing.assert_array_equal(other.ik(T), solver.ik(T))


def test_ik_warm_start_stays_near(kin: WamKinematics) -> None:
    # Warm-started from the configuration a pose came from, IK returns (nearly) it; and
    # along a push (1 cm steps), each solution warm-started from the previous one stays
    # near it: nearly always within 0.3 rad (at a joint limit or near a singularity the
    # arm may have to change its posture; without the warm start a fifth of the steps
    # jump by more). Both for the default solver and for the swivel sweep alone.
    fresh, sweep = WamKinematics(), WamKinematics()
    sweep.track_iterations = 0
    configs = _top_down_configs(kin, 20, seed=12)
    for solver in (fresh, sweep):
        steps, near = 0, 0
        for q_true in configs:
            T = kin.fk(q_true)
            q = solver.ik(T, warm=q_true)
            _assert_solves(kin, q, T)
            assert np.max(np.abs(q - q_true)) < 0.05
            for i in range(1, 6):
                T2 = T.copy()
                T2[0, 3] -= 0.01 * i
                q2 = solver.ik(T2, warm=q)
                if q2 is None:
                    break
                _assert_solves(kin, q2, T2)
                near += np.max(np.abs(q2 - q)) < 0.3
                q = q2
                steps += 1
        assert steps >= 80 and near >= 0.95 * steps


def test_ik_without_the_analytic_path(kin: WamKinematics) -> None:
    # The damped least squares fallback (a URDF that is not the DH arm) still solves.
    dls = WamKinematics()
    dls.analytic = False
    T = _top_down(0.6, 0.1, -0.25)
    _assert_solves(kin, dls.ik(T), T)
    assert dls.stats.starts >= 1 and dls.stats.sweeps == 0


def test_ik_rejects_beyond_the_stretch(kin: WamKinematics) -> None:
    # Top-down poses straight out along x with the wrist centre (0.175 m above the TCP)
    # at the fully stretched elbow's distance from the shoulder, +- a few mm.
    fresh = WamKinematics()
    # |shoulder -> wrist centre| with the elbow offsets in line (DH table): the longest
    a, b = np.array([0.045, 0.55]), np.array([-0.045, 0.30])
    w_max = math.sqrt(a @ a + b @ b + 2 * math.hypot(a @ b, a[0] * b[1] - a[1] * b[0]))
    z = -0.25
    wz = z + 0.175

    def pose(extra: float) -> np.ndarray:
        return _top_down(math.sqrt((w_max + extra) ** 2 - wz**2), 0.0, z)

    _assert_solves(kin, fresh.ik(pose(-0.003)), pose(-0.003))
    # just beyond, within what the tolerances make up (1 mm and 0.01 rad x 0.175 m)
    _assert_solves(kin, fresh.ik(pose(0.0015)), pose(0.0015))
    starts = fresh.stats.starts
    far = pose(0.004)
    assert kin.reachable(far)  # the cheap pre-check lets it through...
    assert fresh.ik(far) is None  # ...the elbow cannot stretch that far
    assert fresh.elbow_angles(far) == []
    # and well beyond: the pre-check and IK both say no
    very_far = _top_down(1.3, 0.2, TABLE_Z + 0.05)
    assert not kin.reachable(very_far)
    assert fresh.ik(very_far) is None
    assert fresh.stats.starts == starts  # both rejected in closed form, without a search


def test_ik_rejects_top_down_at_the_shoulder_axis(kin: WamKinematics) -> None:
    # A top-down grasp right beside the base: the wrist centre is too near the shoulder
    # for the elbow (q4 would have to fold past 3.1 rad). In reach, but no solution.
    fresh = WamKinematics()
    for x, h in ((0.0, 0.05), (0.05, 0.15), (0.15, 0.02)):
        T = _top_down(x, 0.0, TABLE_Z + h, yaw=0.3)
        assert kin.reachable(T)
        assert fresh.elbow_angles(T) == []
        assert fresh.ik(T) is None
    assert fresh.stats.starts == 0 and fresh.stats.sweeps == 0  # in closed form
    # an independent check: damped least squares from many random starts finds nothing
    T = _top_down(0.0, 0.0, TABLE_Z + 0.05)
    target = kin.target(T)
    rng = np.random.default_rng(5)
    assert all(kin._solve_from(target, rng.uniform(kin.lower, kin.upper)) is None for _ in range(16))
    # ...while 0.35 m out, beyond the fold, the same grasp has one
    T = _top_down(0.35, 0.0, TABLE_Z + 0.05, yaw=0.3)
    _assert_solves(kin, fresh.ik(T), T)


def test_dh_fk_is_the_urdf(kin: WamKinematics) -> None:
    # what the analytic IK inverts is the model Pinocchio loads
    from clearcli.robot.wam_kinematics import dh_fk

    rng = np.random.default_rng(8)
    for q in rng.uniform(kin.lower, kin.upper, size=(50, 7)):
        np.testing.assert_allclose(dh_fk(q), kin.fk(q), atol=1e-12)


def test_numpy_chain_is_pinocchios(kin: WamKinematics) -> None:
    """The WAM's FK, TCP Jacobian, pose error (log6) and capsules are computed with NumPy
    (no Pinocchio import at plan time, issue 39): the same as Pinocchio's on our URDF."""
    import pinocchio as pin

    from clearcli.robot import wam_kinematics as wk

    model = pin.buildModelFromUrdf(str(wk.URDF_PATH))
    data = model.createData()
    tcp = model.getFrameId(wk.TCP_FRAME)
    assert kin.joint_names == tuple(model.names[1:])
    assert np.array_equal(kin.lower, model.lowerPositionLimit) and np.array_equal(kin.upper, model.upperPositionLimit)
    pin.framesForwardKinematics(model, data, np.zeros(7))
    M_base_root = data.oMf[model.getFrameId(wk.BASE_FRAME)].inverse()
    rng = np.random.default_rng(3)
    for q in rng.uniform(kin.lower, kin.upper, size=(40, 7)):
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacement(model, data, tcp)
        poses = kin.chain.joint_poses(q)
        T_root_tcp = kin.chain.frame_pose(poses, wk.TCP_FRAME)
        np.testing.assert_allclose(T_root_tcp, data.oMf[tcp].homogeneous, atol=1e-14)
        np.testing.assert_allclose(
            kin._tcp_jacobian(poses, T_root_tcp), pin.getFrameJacobian(model, data, tcp, pin.LOCAL), atol=1e-14
        )
        # the solver's inner loop on the DH arm (plain floats): the same error and Jacobian
        T_target = T_root_tcp.copy()
        T_target[:3, 3] += [0.01, -0.02, 0.005]
        err, J = wk._dh_error_and_jacobian(q, (kin.M_base_root @ T_target).tolist())
        np.testing.assert_allclose(J, pin.getFrameJacobian(model, data, tcp, pin.LOCAL), atol=1e-14)
        np.testing.assert_allclose(err, pin.log6(data.oMf[tcp].actInv(pin.SE3(T_target))).vector, atol=1e-14)
        starts, ends, _ = kin.capsules(q)
        pin.framesForwardKinematics(model, data, q)
        expected = np.array([(M_base_root * data.oMi[i]).translation for i, _, _ in wk._CAPSULES])
        np.testing.assert_allclose(starts, expected, atol=1e-14)
        # pose errors from tiny (the Taylor branches) to near a half turn (the singular one)
        for angle in (1e-9, 1e-4, 0.3, 2.0, np.pi - 1e-6):
            axis = rng.normal(size=3)
            T = np.eye(4)
            T[:3, :3] = pin.exp3(axis / np.linalg.norm(axis) * angle) @ T_root_tcp[:3, :3]
            T[:3, 3] = T_root_tcp[:3, 3] + rng.normal(size=3) * min(angle, 0.2)
            theirs = pin.log6(data.oMf[tcp].actInv(pin.SE3(T))).vector
            np.testing.assert_allclose(kin.pose_error(T, q), theirs, atol=1e-12)
            assert kin.within_tolerance(T, q) == (
                bool(np.all(q >= kin.lower) and np.all(q <= kin.upper))
                and np.linalg.norm(theirs[:3]) < kin.tolerance_m
                and np.linalg.norm(theirs[3:]) < kin.tolerance_rad
            )


def test_plan_time_kinematics_import_no_pinocchio() -> None:
    import subprocess
    import sys

    code = (
        "import sys, numpy as np\n"
        "from clearcli.robot.wam_kinematics import WamKinematics\n"
        "kin = WamKinematics().fresh()\n"
        "T = kin.fk(np.array([0.0, 0.6, 0.0, 1.6, 0.0, 0.6, 0.0]))\n"
        "assert kin.ik(T) is not None and kin.capsules(np.zeros(7))[0].shape == (4, 3)\n"
        "print('pinocchio' in sys.modules, 'coal' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "False"]
