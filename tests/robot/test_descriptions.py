"""Cross-checks of clearcli/robot/panda.urdf and ur5e.urdf against third-party descriptions."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from helpers import shared_path

ROBOT_DIR = Path(__file__).resolve().parents[2] / "clearcli" / "robot"
PANDA = ROBOT_DIR / "panda.urdf"
UR5E = ROBOT_DIR / "ur5e.urdf"
PANDA_ARM = [f"panda_link{i}" for i in range(1, 8)]
UR5E_ARM = ["shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link", "wrist_2_link", "wrist_3_link"]
CASES = {
    # robot: (ours, reference, root frame, flange frame)
    "panda": (PANDA, "robots/panda/panda_collision.urdf", "panda_link0", "panda_link8"),
    "ur5e": (UR5E, "robots/ur5e/ur5e.urdf", "base_link", "tool0"),
}


def _rel(model: pin.Model, data: pin.Data, a: str, b: str) -> pin.SE3:
    return data.oMf[model.getFrameId(a)].inverse() * data.oMf[model.getFrameId(b)]


def _angle(R: np.ndarray) -> float:
    return float(np.linalg.norm(pin.log3(R)))


@pytest.mark.parametrize("robot", CASES)
def test_kinematics_match_reference(robot: str) -> None:
    ours_path, ref_rel, root, flange = CASES[robot]
    ours = pin.buildModelFromUrdf(str(ours_path))
    ref = pin.buildModelFromUrdf(str(shared_path(ref_rel)))
    n = ours.nq
    assert n == {"panda": 7, "ur5e": 6}[robot]
    assert ref.nq == n + (2 if robot == "panda" else 0)  # the reference Panda has 2 finger joints last
    assert list(ours.names[1:]) == list(ref.names[1 : n + 1])
    np.testing.assert_array_equal(ours.lowerPositionLimit, ref.lowerPositionLimit[:n])
    np.testing.assert_array_equal(ours.upperPositionLimit, ref.upperPositionLimit[:n])
    d_ours, d_ref = ours.createData(), ref.createData()
    rng = np.random.default_rng(0)
    worst_m = worst_rad = 0.0
    for _ in range(1000):
        q = rng.uniform(ours.lowerPositionLimit, ours.upperPositionLimit)
        pin.framesForwardKinematics(ours, d_ours, q)
        pin.framesForwardKinematics(ref, d_ref, np.concatenate([q, np.zeros(ref.nq - n)]))
        a, b = _rel(ours, d_ours, root, flange), _rel(ref, d_ref, root, flange)
        worst_m = max(worst_m, float(np.linalg.norm(a.translation - b.translation)))
        worst_rad = max(worst_rad, _angle(a.rotation.T @ b.rotation))
        if robot == "panda":  # the hand's mounting turn too
            h_a, h_b = _rel(ours, d_ours, root, "panda_hand"), _rel(ref, d_ref, root, "panda_hand")
            worst_m = max(worst_m, float(np.linalg.norm(h_a.translation - h_b.translation)))
            worst_rad = max(worst_rad, _angle(h_a.rotation.T @ h_b.rotation))
    assert worst_m < 0.001
    assert worst_rad < np.radians(0.1)


def test_panda_tcp_offset() -> None:
    model = pin.buildModelFromUrdf(str(PANDA))
    data = model.createData()
    rng = np.random.default_rng(1)
    for q in [np.zeros(7), *rng.uniform(model.lowerPositionLimit, model.upperPositionLimit, (5, 7))]:
        pin.framesForwardKinematics(model, data, q)
        T = _rel(model, data, "panda_hand", "panda_tcp")
        np.testing.assert_allclose(T.translation, [0, 0, 0.1034], atol=1e-9)
        # clear's gripper frame: z = approach (the hand's z), x = the closing direction
        # (the hand's y, along which the reference's finger joints slide)
        np.testing.assert_allclose(T.rotation, [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-9)
        # 0.1034 m from the hand is the maker's "closing point past the flange": the hand sits on it
        np.testing.assert_allclose(_rel(model, data, "panda_link8", "panda_tcp").translation, [0, 0, 0.1034], atol=1e-9)


def _robotiq_closing_point() -> np.ndarray:
    """Midpoint of the 2F-85's finger pads, fully closed, in the gripper's base frame."""
    model = pin.buildModelFromUrdf(str(shared_path("robots/robotiq_2f_85/urdf/robotiq_2f_85.urdf")), True)
    assert model.nq == 1  # finger_joint; the linkage follows through its mimic joints
    data = model.createData()
    pin.framesForwardKinematics(model, data, model.upperPositionLimit.copy())
    pads = [data.oMf[model.getFrameId(f"{side}_inner_finger_pad")].translation.copy() for side in ("left", "right")]
    assert np.linalg.norm(pads[0] - pads[1]) < 0.01  # closed: the pads (6.35 mm thick) nearly touch
    # open, the pads stand apart along the gripper's x: its closing direction, which is
    # clear's gripper frame's x (robotiq_tcp is not turned against tool0)
    pin.framesForwardKinematics(model, data, model.lowerPositionLimit.copy())
    apart = (
        data.oMf[model.getFrameId("left_inner_finger_pad")].translation
        - data.oMf[model.getFrameId("right_inner_finger_pad")].translation
    )
    assert abs(apart[0]) > 0.98 * np.linalg.norm(apart)
    return (pads[0] + pads[1]) / 2


def test_ur5e_tcp_offset() -> None:
    point = _robotiq_closing_point()
    assert np.linalg.norm(point[:2]) < 1e-4  # on the gripper's axis
    model = pin.buildModelFromUrdf(str(UR5E))
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.random.default_rng(2).uniform(-3, 3, 6))
    T = _rel(model, data, "tool0", "robotiq_tcp")
    np.testing.assert_allclose(T.translation[:2], [0, 0], atol=1e-9)
    assert T.translation[2] == pytest.approx(point[2], abs=0.001)
    np.testing.assert_allclose(T.rotation, np.eye(3), atol=1e-9)
    assert _rel(model, data, "tool0", "robotiq_base_link").isIdentity()  # mounted on the flange face


@pytest.mark.parametrize(("path", "arm"), [(PANDA, PANDA_ARM), (UR5E, UR5E_ARM)])
def test_collision_is_primitives_only(path: Path, arm: list[str]) -> None:
    root = ET.parse(path).getroot()
    count: dict[str, int] = {}
    for link in root.iter("link"):
        for collision in link.iter("collision"):
            shapes = [child.tag for child in collision.find("geometry")]
            assert len(shapes) == 1 and shapes[0] in ("cylinder", "sphere", "box"), (link.get("name"), shapes)
            count[link.get("name")] = count.get(link.get("name"), 0) + 1
    assert root.find(".//mesh") is None
    assert all(count.get(name, 0) >= 1 for name in arm), count
    model = pin.buildModelFromUrdf(str(path))
    geom = pin.buildGeomFromUrdf(model, str(path), pin.GeometryType.COLLISION)
    assert geom.ngeoms == sum(count.values())
    assert {type(g.geometry).__name__ for g in geom.geometryObjects} <= {"Cylinder", "Sphere", "Box"}


def _shape_key(g: pin.GeometryObject) -> tuple:
    s = g.geometry
    size = [s.radius, s.halfLength] if hasattr(s, "halfLength") else [getattr(s, "radius", 0.0)]
    return type(s).__name__, *np.round(size, 6)


def _same_pose(a: pin.SE3, b: pin.SE3) -> bool:
    return bool(np.linalg.norm(a.translation - b.translation) < 1e-6 and _angle(a.rotation.T @ b.rotation) < 1e-6)


def test_panda_collision_matches_reference() -> None:
    """Every reference primitive (fingers open) is one of ours, same size, same pose."""
    ref_path = shared_path("robots/panda/panda_collision.urdf")
    ours = pin.buildModelFromUrdf(str(PANDA))
    ref = pin.buildModelFromUrdf(str(ref_path))
    g_ours = pin.buildGeomFromUrdf(ours, str(PANDA), pin.GeometryType.COLLISION)
    g_ref = pin.buildGeomFromUrdf(ref, str(ref_path), pin.GeometryType.COLLISION)
    q = np.random.default_rng(3).uniform(ours.lowerPositionLimit, ours.upperPositionLimit)
    placed = []
    for model, geom, qq in ((ours, g_ours, q), (ref, g_ref, np.concatenate([q, [0.04, 0.04]]))):
        data, gdata = model.createData(), geom.createData()
        pin.forwardKinematics(model, data, qq)
        pin.updateGeometryPlacements(model, data, geom, gdata)
        placed.append([(_shape_key(g), gdata.oMg[i]) for i, g in enumerate(geom.geometryObjects)])
    assert len(placed[1]) == len(placed[0])
    for key, M in placed[1]:
        assert any(k == key and _same_pose(M, N) for k, N in placed[0]), key


def test_ur5e_cylinders_bound_reference_meshes() -> None:
    """Each reference collision mesh lies inside our cylinder(s) on the same joint."""
    trimesh = pytest.importorskip("trimesh")
    ref_path = shared_path("robots/ur5e/ur5e.urdf")
    ref = pin.buildModelFromUrdf(str(ref_path))
    g_ref = pin.buildGeomFromUrdf(ref, str(ref_path), pin.GeometryType.COLLISION, package_dirs=[str(ref_path.parent)])
    ours = pin.buildModelFromUrdf(str(UR5E))
    g_ours = pin.buildGeomFromUrdf(ours, str(UR5E), pin.GeometryType.COLLISION)
    checked = set()
    for g in g_ref.geometryObjects:
        if not g.meshPath.endswith(".obj"):
            continue  # the reference's base spheres
        v = np.asarray(trimesh.load(g.meshPath, force="mesh", process=False).vertices) * g.meshScale
        v = v @ g.placement.rotation.T + g.placement.translation  # in the parent joint's frame
        joint = ref.names[g.parentJoint]
        inside = np.zeros(len(v), dtype=bool)
        for c in g_ours.geometryObjects:
            if ours.names[c.parentJoint] != joint:
                continue
            local = (v - c.placement.translation) @ c.placement.rotation  # into the cylinder's frame
            s = c.geometry
            radial = np.hypot(local[:, 0], local[:, 1])
            inside |= (np.abs(local[:, 2]) <= s.halfLength + 1e-6) & (radial <= s.radius + 1e-6)
        assert inside.all(), (joint, int((~inside).sum()))
        checked.add(joint)
    assert checked == set(ours.names[1:])


def test_gripper_widths_are_the_makers_figures() -> None:
    # the openings the profiles give [gripper] against the figures quoted beside the
    # third-party descriptions (../shared/data/robots/README.md)
    import re

    from clearcli.settings import load_settings

    text = shared_path("robots/README.md").read_text(encoding="utf-8")
    hand = float(re.search(r"Franka Hand opens to ([0-9.]+) m", text).group(1))
    robotiq = float(re.search(r"Robotiq 2F-85: opens to ([0-9.]+) m", text).group(1))
    assert load_settings(sets=["robot.name=panda"]).gripper.opening_width_m == pytest.approx(hand)
    assert load_settings(sets=["robot.name=ur5e"]).gripper.opening_width_m == pytest.approx(robotiq)
