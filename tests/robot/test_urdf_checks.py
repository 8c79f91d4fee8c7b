"""A user's robot description ([robot] urdf, base_frame, flange_frame, the tool-centre
offset and [gripper]) is checked once, before any frame is read: each fault is one line
on stderr naming the file and what is wrong, exit 3, no traceback and no frame's output,
for a single call and for a batch alike (clearcli/robot/urdf_joints.py `checked_urdf`,
clearcli/robot/generic.py `UrdfKinematics`, called by clearcli/tasks/robots.py
`check_robot` while the settings are resolved)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from helpers import FIXTURES
from helpers import run_clear as clear

from clearcli.robot.profiles import PROFILES

PANDA = PROFILES["panda"].urdf  # the shipped description: 7 revolute joints, primitives only
FRAME = FIXTURES / "clutter10.pcd"


def _panda_with(tmp_path: Path, name: str, old: str, new: str, joint: str = "panda_joint4") -> Path:
    """The shipped Panda with ``old`` replaced by ``new`` in ``joint``'s element."""
    text = PANDA.read_text()
    start = text.index(f'<joint name="{joint}"')
    end = text.index("</joint>", start)
    block = text[start:end]
    assert old in block, (old, block)
    path = tmp_path / f"{name}.urdf"
    path.write_text(text[:start] + block.replace(old, new) + text[end:])
    return path


def _refused(*args: object, frame: Path = FRAME) -> str:
    """The one line of a refused `clear plan` (exit 3, nothing on stdout)."""
    res = clear("plan", frame, *args)
    assert res.returncode == 3, (args, res.returncode, res.stderr)
    assert res.stdout == "" and "Traceback" not in res.stderr, (args, res.stderr)
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("clear: error: "), (args, res.stderr)
    return lines[0]


def test_a_joint_whose_lower_limit_exceeds_its_upper_is_one_line_exit_3(tmp_path: Path) -> None:
    # before: exit 1, "internal error: ValueError: high - low < 0" (the reach bounds drew
    # random configurations between the swapped limits)
    urdf = _panda_with(tmp_path, "swapped", 'lower="-3.0718" upper="-0.0698"', 'lower="-0.0698" upper="-3.0718"')
    line = _refused("--set", f"robot.urdf={urdf}")
    assert str(urdf) in line and "'panda_joint4'" in line and "-0.0698" in line and "-3.0718" in line


def test_a_base_frame_equal_to_the_flange_frame_is_one_line_exit_3() -> None:
    # before: exit 5, "no plan: out of the robot's reach" (the base frame moved with the
    # arm's joints, and the flange never left it)
    line = _refused(
        "--set",
        f"robot.urdf={PANDA}",
        "--set",
        "robot.base_frame=panda_link8",
        "--set",
        "robot.flange_frame=panda_link8",
    )
    assert str(PANDA) in line and "both 'panda_link8'" in line


@pytest.mark.parametrize(
    "old, new, words",
    [
        (
            'xyz="0.0825 0 0"',
            'xyz="0.0825 nan 0"',
            ["joint 'panda_joint4'", '<origin xyz="0.0825 nan 0">', "3 finite numbers"],
        ),
        ('rpy="1.5707963267948966 0 0"', 'rpy="inf 0 0"', ["joint 'panda_joint4'", '<origin rpy="inf 0 0">']),
        ('<axis xyz="0 0 1"/>', '<axis xyz="0 0 nan"/>', ["joint 'panda_joint4'", '<axis xyz="0 0 nan">']),
        ('<axis xyz="0 0 1"/>', '<axis xyz="0 0 0"/>', ["joint 'panda_joint4'", "has no direction"]),
        ('<axis xyz="0 0 1"/>', '<axis xyz="0 1"/>', ["joint 'panda_joint4'", '<axis xyz="0 1">', "3 finite numbers"]),
        ('upper="-0.0698"', 'upper="inf"', ["joint 'panda_joint4'", '<limit upper="inf">', "a finite number"]),
        ('lower="-3.0718"', 'lower="nan"', ["joint 'panda_joint4'", '<limit lower="nan">']),
        (
            '<limit lower="-3.0718" upper="-0.0698" effort="87" velocity="2.175"/>',
            "",
            ["'panda_joint4' (revolute) has no <limit>"],
        ),
        # what urdfdom refuses that the checks do not know: its own reason, not its dump
        ('<child link="panda_link4"/>', '<child link="nowhere"/>', ["not a URDF Pinocchio can read", "[nowhere]"]),
    ],
    ids=[
        "nan-origin",
        "inf-rpy",
        "nan-axis",
        "zero-axis",
        "short-axis",
        "inf-limit",
        "nan-limit",
        "no-limit",
        "unknown-link",
    ],
)
def test_bad_numbers_of_a_joint_are_one_line_exit_3(tmp_path: Path, old: str, new: str, words: list[str]) -> None:
    urdf = _panda_with(tmp_path, "bad", old, new)
    line = _refused("--set", f"robot.urdf={urdf}")
    assert str(urdf) in line and all(w in line for w in words), line


def test_bad_numbers_of_a_links_collision_shape_are_one_line_exit_3(tmp_path: Path) -> None:
    text = PANDA.read_text()
    assert text.count('<sphere radius="0.09"/>') > 1
    urdf = tmp_path / "nan_sphere.urdf"
    urdf.write_text(text.replace('<sphere radius="0.09"/>', '<sphere radius="nan"/>', 1))
    line = _refused("--set", f"robot.urdf={urdf}")
    assert "link 'panda_link" in line and '<sphere radius="nan">' in line


def test_a_file_that_is_no_urdf_is_one_line_exit_3(tmp_path: Path) -> None:
    binary = tmp_path / "binary.urdf"
    binary.write_bytes(b"\x00\xff\xfe not xml")
    other = tmp_path / "other.urdf"
    other.write_text("<sdf version='1.6'><model name='m'/></sdf>")
    assert "not well-formed XML" in _refused("--set", f"robot.urdf={binary}")
    assert "root element is <sdf>, not <robot>" in _refused("--set", f"robot.urdf={other}")
    assert "a folder, not a URDF file" in _refused("--set", f"robot.urdf={tmp_path}")
    assert "URDF file not found" in _refused("--set", f"robot.urdf={tmp_path / 'none.urdf'}")


@pytest.mark.parametrize(
    "base, flange, words",
    [
        ("panda_link8", "panda_link3", "flange_frame 'panda_link3' does not hang from base_frame 'panda_link8'"),
        (
            "panda_link8",
            "panda_hand",
            "no movable joint between base_frame 'panda_link8' and flange_frame 'panda_hand'",
        ),
        ("panda_joint1", "panda_link8", "no frame 'panda_joint1' (base_frame); its frames (links): panda_link0"),
        ("panda_link0", "panda_tcp_joint", "no frame 'panda_tcp_joint' (flange_frame)"),
    ],
    ids=["flange-upstream", "fixed-to-each-other", "base-a-joint", "flange-a-joint"],
)
def test_frames_that_make_no_arm_are_one_line_exit_3(base: str, flange: str, words: str) -> None:
    line = _refused(
        "--set", f"robot.urdf={PANDA}", "--set", f"robot.base_frame={base}", "--set", f"robot.flange_frame={flange}"
    )
    assert words in line, line


def test_a_flange_on_another_branch_than_the_base_is_one_line_exit_3(tmp_path: Path) -> None:
    # a second branch from link 2 (a sensor on its own joint): its link is no base of the flange
    text = PANDA.read_text()
    side = (
        '<link name="side"/><joint name="side_joint" type="revolute"><parent link="panda_link2"/><child link="side"/>'
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>\n</robot>'
    )
    urdf = tmp_path / "branched.urdf"
    urdf.write_text(text.replace("</robot>", side))
    line = _refused(
        "--set", f"robot.urdf={urdf}", "--set", "robot.base_frame=side", "--set", "robot.flange_frame=panda_link8"
    )
    assert "flange_frame 'panda_link8' does not hang from base_frame 'side'" in line


@pytest.mark.parametrize(
    "setting, words",
    [
        ("robot.tcp_xyz_m=[nan, 0, 0.1]", "[robot] tcp_xyz_m"),
        ("robot.tcp_xyz_m=[0, 0, 0.6]", "[robot] tcp_xyz_m"),
        ("robot.tcp_yaw_deg=inf", "[robot] tcp_yaw_deg"),
        ("gripper.opening_width_m=0", "[gripper] opening_width_m"),
        ("gripper.opening_width_m=-0.08", "[gripper] opening_width_m"),
        ("gripper.finger_depth_m=nan", "[gripper] finger_depth_m"),
    ],
)
def test_bad_tool_settings_with_a_urdf_are_one_line_exit_3(setting: str, words: str) -> None:
    assert words in _refused("--set", f"robot.urdf={PANDA}", "--set", setting)


def test_checked_before_any_frame_is_read(tmp_path: Path) -> None:
    # a frame that cannot be read either: the description's line is the one given
    corrupt = tmp_path / "corrupt.pcd"
    corrupt.write_bytes(b"not a point cloud")
    urdf = _panda_with(tmp_path, "swapped", 'lower="-3.0718" upper="-0.0698"', 'lower="-0.0698" upper="-3.0718"')
    assert "'panda_joint4'" in _refused("--set", f"robot.urdf={urdf}", frame=corrupt)


@pytest.mark.parametrize(
    "sets, words",
    [
        (["robot.urdf={swapped}"], "its lower limit -0.0698 is above its upper limit -3.0718"),
        (
            ["robot.urdf={panda}", "robot.base_frame=panda_link8", "robot.flange_frame=panda_link8"],
            "both 'panda_link8'",
        ),
    ],
    ids=["swapped-limits", "base-is-flange"],
)
def test_a_batch_with_a_bad_description_fails_once_with_no_frame_line(
    tmp_path: Path, sets: list[str], words: str
) -> None:
    folder = tmp_path / "frames"
    folder.mkdir()
    for name in ("isolated_box.pcd", "two_touching_boxes.pcd"):
        shutil.copy(FIXTURES / name, folder / name)
    swapped = _panda_with(tmp_path, "swapped", 'lower="-3.0718" upper="-0.0698"', 'lower="-0.0698" upper="-3.0718"')
    out = tmp_path / "out"
    args = [a for s in sets for a in ("--set", s.format(swapped=swapped, panda=PANDA))]
    for extra in ([], ["--json", "--out-dir", out]):
        res = clear("plan", folder, *args, *extra)
        assert res.returncode == 3, (extra, res.stderr)
        assert res.stdout == "" and "Traceback" not in res.stderr  # no frame line: nothing ran
        lines = res.stderr.strip().splitlines()
        assert len(lines) == 1 and words in lines[0], res.stderr
        assert not out.exists() or not any(out.iterdir())  # no marks to make --resume skip frames


def test_a_continuous_joint_is_read_over_two_turns(tmp_path: Path) -> None:
    # URDF gives a continuous joint no limits: the generic IK takes it over [-2 pi, 2 pi]
    # (urdf_joints.CONTINUOUS_RANGE_RAD); its kinematics are the revolute joint's
    from clearcli.robot.generic import UrdfKinematics

    urdf = _panda_with(tmp_path, "continuous", 'type="revolute"', 'type="continuous"', joint="panda_joint1")
    args = dict(flange_frame="panda_link8", tcp_xyz_m=(0, 0, 0.1034))
    ours, theirs = UrdfKinematics(PANDA, "panda_link0", "", **args), UrdfKinematics(urdf, "panda_link0", "", **args)
    assert theirs.joint_names == ours.joint_names
    np.testing.assert_allclose([theirs.lower[0], theirs.upper[0]], [-2 * np.pi, 2 * np.pi])
    np.testing.assert_array_equal(theirs.lower[1:], ours.lower[1:])
    rng = np.random.default_rng(3)
    for q in rng.uniform(ours.lower, ours.upper, size=(20, ours.lower.size)):
        np.testing.assert_allclose(theirs.fk(q), ours.fk(q), atol=1e-12)
    res = clear("plan", FRAME, "--robot", "panda", "--set", f"robot.urdf={urdf}")
    assert res.returncode in (0, 10), res.stderr


def test_joints_above_the_base_frame_are_held_at_zero() -> None:
    # the README's rule (joints off the base-to-flange chain are held at 0), for a base
    # that is not the root: poses are in that frame, which must not move with the arm
    from clearcli.robot.generic import UrdfKinematics

    args = dict(flange_frame="panda_link8")
    whole = UrdfKinematics(PANDA, "panda_link0", "", **args)
    upper = UrdfKinematics(PANDA, "panda_link1", "", **args)
    assert upper.joint_names == whole.joint_names[1:]
    T_link0_link1 = whole.fk(np.zeros(7), "panda_link1")
    for q in np.random.default_rng(4).uniform(upper.lower, upper.upper, size=(10, 6)):
        T_link0_flange = whole.fk(np.concatenate([[0.0], q]), "panda_link8")
        np.testing.assert_allclose(
            upper.fk(q, "panda_link8"), np.linalg.inv(T_link0_link1) @ T_link0_flange, atol=1e-12
        )


@pytest.mark.parametrize("xyz", ["1e308 0 0", "82.5 0 -250"])
def test_a_joint_origin_hundreds_of_metres_away_is_one_line_exit_3(tmp_path: Path, xyz: str) -> None:
    # before: "1e308 0 0" overflowed the kinematics (a NumPy RuntimeWarning on stderr, then
    # exit 4); "82.5 0 -250" is millimetres written as metres
    urdf = _panda_with(tmp_path, "far", 'origin xyz="0.0825 0 0"', f'origin xyz="{xyz}"')
    line = _refused("--set", f"robot.urdf={urdf}")
    assert "'panda_joint4'" in line and f'<origin xyz="{xyz}">' in line and "more than 100 m from its parent" in line


def test_a_urdf_name_too_long_for_the_file_system_is_bad_settings_not_a_write_error() -> None:
    # the check's is_dir() raised ENAMETOOLONG, which the CLI took for a failed write to
    # stdout (exit 8, "cannot write the results to stdout")
    from clearcli.errors import SettingsError
    from clearcli.robot.urdf_joints import checked_urdf

    with pytest.raises(SettingsError, match="cannot be read"):
        checked_urdf(Path("a" * 5000))
