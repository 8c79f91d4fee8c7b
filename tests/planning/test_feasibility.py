"""Tests of clearcli/planning/feasibility.py: the scene as earlier actions leave it, what a
failure teaches, the arm's obstacles in a context, the IK check of one pose sequence and
of an action of every grasp kind.

The arm here is a stand-in (`PointArm`) whose answers are known by hand: its "joint
vector" is the pose's position, it reaches `reach_m` from its base, has no IK at the
positions it is told, and is one sphere of radius 1 cm at the pose."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from helpers import plan_scenes as ps

from clearcli.planning.feasibility import (
    EMPTY,
    IKActionChecker,
    Infeasible,
    SceneContext,
    _failure_rank,
    check_sequence,
    context_obstacles,
    gripper_opening_text,
)
from clearcli.planning.types import Action
from clearcli.robot.collision import Obstacles, make_obstacles


class PointArm:
    def __init__(self, reach_m: float = 10.0, no_ik: tuple[tuple[float, float, float], ...] = ()) -> None:
        self.reach_m = reach_m
        self.no_ik = [np.asarray(p, dtype=float) for p in no_ik]
        self.ik_calls = 0

    def reachable(self, T: np.ndarray) -> bool:
        return float(np.linalg.norm(T[:3, 3])) <= self.reach_m

    def ik(self, T: np.ndarray, warm: np.ndarray | None = None) -> np.ndarray | None:
        self.ik_calls += 1
        p = np.asarray(T[:3, 3], dtype=float)
        if any(np.allclose(p, q) for q in self.no_ik):
            return None
        return np.concatenate([p, np.zeros(4)])

    def capsules(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return q[None, :3], q[None, :3], np.array([0.01])


def _at(x: float, y: float, z: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def _cube_obstacles(margin_m: float = 0.0) -> Obstacles:
    """The table z = 0 and one cube "o1": x 0.4..0.6, y -0.1..0.1, z 0..0.2 (base frame)."""
    lo, hi = np.array([0.4, -0.1, 0.0]), np.array([0.6, 0.1, 0.2])
    # n.x + d <= 0 inside: one plane per face
    planes = np.array(
        [
            [1, 0, 0, -hi[0]],
            [-1, 0, 0, lo[0]],
            [0, 1, 0, -hi[1]],
            [0, -1, 0, lo[1]],
            [0, 0, 1, -hi[2]],
            [0, 0, -1, lo[2]],
        ],
        dtype=float,
    )
    return Obstacles(np.array([0.0, 0.0, 1.0]), 0.0, ("o1",), (planes,), ((lo, hi),), margin_m)


# --- SceneContext ---------------------------------------------------------------------------


def _two_boxes():  # type: ignore[no-untyped-def]
    return ps.scene({"o0": ps.Box(0.45, 0.0), "o1": ps.Box(0.45, 0.25)})


def test_a_context_moves_pushed_objects_and_forgets_grasped_ones() -> None:
    state = _two_boxes()
    push = Action("push", "o0", "dir1")
    end = np.asarray(state.by_name("o0").pushes["dir1"].object_path[-1])
    once = EMPTY.after(push, state)
    assert once.moved("o0") and not once.moved("o1") and not EMPTY.moved("o0")
    assert np.allclose(once.shift_of("o0"), end, atol=1e-9) and not np.any(once.shift_of("o1"))
    # a second push adds its translation; a grasp takes the object and its shift away
    twice = once.after(push, state)
    assert np.allclose(twice.shift_of("o0"), 2 * end, atol=1e-9)
    gone = twice.after(Action("grasp", "o0"), state)
    assert gone.removed == frozenset({"o0"}) and gone.shifts == () and gone.moved("o0")
    # the same scene reached in another order is the same context (a cache key)
    a = EMPTY.after(Action("push", "o1", "dir3"), state).after(push, state)
    b = EMPTY.after(push, state).after(Action("push", "o1", "dir3"), state)
    assert a == b and hash(a) == hash(b) and [n for n, _ in a.shifts] == ["o0", "o1"]


# --- what a failure teaches -------------------------------------------------------------------


@pytest.mark.parametrize("kind, block", [("pinch", "block_grasp"), ("rim", "block_rim"), ("slide", "block_slide")])
def test_a_collision_teaches_the_blocking_facts_of_the_actions_grasp_kind(kind: str, block: str) -> None:
    grasp = Action("grasp", "o2", None, kind)
    hit = Infeasible("arm collides with o1, o3 at pose 2/3", "collision", ("o1", "o3"))
    assert hit.facts(grasp) == ((block, "o1", "o2"), (block, "o3", "o2"))
    # anything else: the action's own IK fact
    for why in ("reach", "ik", "lookahead", "poses"):
        assert Infeasible("x", why).facts(grasp) == (grasp.ik_fact(),)
    assert (
        grasp.ik_fact()[0]
        == {"pinch": "ik_unfeasible_grasp", "rim": "ik_unfeasible_rim", "slide": "ik_unfeasible_slide"}[kind]
    )


def test_a_collision_of_a_push_teaches_block_dir_in_its_direction() -> None:
    push = Action("push", "o2", "dir3")
    assert Infeasible("x", "collision", ("o1",)).facts(push) == (("block_dir", "o1", "o2", "dir3"),)
    assert Infeasible("x", "collision").facts(push) == (("ik_unfeasible_dir", "o2", "dir3"),)  # no colliders
    assert Infeasible("x", "ik").facts(push) == (("ik_unfeasible_dir", "o2", "dir3"),)


def test_the_most_promising_failure_is_a_collision_with_the_fewest_objects() -> None:
    failures = [
        Infeasible("a", "reach"),
        Infeasible("b", "collision", ("o1", "o2")),
        Infeasible("c", "ik"),
        Infeasible("d", "collision", ("o3",)),
        Infeasible("e", "lookahead"),
    ]
    assert min(failures, key=_failure_rank).reason == "d"
    assert min(failures[:1] + failures[2:3] + failures[4:], key=_failure_rank).reason == "e"


# --- the arm's obstacles in a context ----------------------------------------------------------


def test_context_obstacles_leave_out_grasped_objects_and_move_pushed_ones() -> None:
    base = _cube_obstacles()
    assert context_obstacles(base, EMPTY, np.eye(4)) is base
    assert context_obstacles(base, SceneContext(frozenset({"o1"})), np.eye(4)).names == ()
    # shifted 0.3 m along the camera's x; the camera's x is the base's y here
    T_base_camera = np.eye(4)
    T_base_camera[:3, :3] = [[0, 0, 1], [1, 0, 0], [0, 1, 0]]
    moved = context_obstacles(base, SceneContext(shifts=(("o1", (0.3, 0.0, 0.0)),)), T_base_camera)
    lo, hi = moved.boxes[0]
    assert np.allclose(lo, [0.4, 0.2, 0.0]) and np.allclose(hi, [0.6, 0.4, 0.2])
    spheres = np.array([[0.5, 0.0, 0.1], [0.5, 0.3, 0.1]]), np.array([0.01, 0.01])
    assert base.collisions(np.array([[0.5, 0.0, 0.1]]), np.array([0.01])) == ["o1"]
    assert moved.collisions(spheres[0][:1], spheres[1][:1]) == []  # where it stood
    assert moved.collisions(spheres[0][1:], spheres[1][1:]) == ["o1"]  # where it went


# --- one pose sequence ----------------------------------------------------------------------------


def test_check_sequence_says_which_pose_fails_and_how() -> None:
    obstacles = _cube_obstacles()
    # 0.374 m, 0.245 m and 0.374 m from the base, clear of the table and of o1
    free = [_at(0.2, 0.1, 0.3), _at(0.2, 0.1, 0.1), _at(0.2, 0.1, 0.3)]
    spheres: dict = {}
    ok = check_sequence(PointArm(), obstacles, free, "o0", spheres)
    assert ok.failure is None and ok.joints is not None and len(ok.joints) == 3
    assert np.allclose(ok.joints[1][:3], (0.2, 0.1, 0.1)) and len(spheres) == 2  # two distinct poses
    # beyond reach (0.436 m > 0.40 m): found before any IK
    arm = PointArm(reach_m=0.40)
    far = check_sequence(arm, obstacles, [free[0], _at(0.3, 0.3, 0.1), free[2]], "o0")
    assert far.failure == Infeasible("pose 2/3 beyond the arm's reach", "reach") and arm.ik_calls == 0
    # no IK at the second pose
    none = check_sequence(PointArm(no_ik=((0.2, 0.1, 0.1),)), obstacles, free, "o0")
    assert none.failure == Infeasible("no IK solution for pose 2/3", "ik")
    # the arm in the table (5 mm above it, a 1 cm sphere): no motion, whatever moves (an
    # "ik" failure, not a collision)
    low = check_sequence(PointArm(), obstacles, [free[0], _at(0.2, 0.1, 0.005), free[2]], "o0")
    assert low.failure is not None and low.failure.kind == "ik" and "table" in low.failure.reason
    # through o1 at the second pose: every object hit is collected, for backtracking
    through = [free[0], _at(0.5, 0.0, 0.1), free[2]]
    hit = check_sequence(PointArm(), obstacles, through, "o0")
    assert hit.failure == Infeasible("arm collides with o1 at pose 2/3", "collision", ("o1",))
    # ... unless o1 is the action's own object
    assert check_sequence(PointArm(), obstacles, through, "o1").joints is not None


# --- an action of each kind ---------------------------------------------------------------------


def _checker(state, arm: PointArm | None = None, **kw) -> IKActionChecker:  # type: ignore[no-untyped-def]
    return IKActionChecker(
        state, ps.T_BASE_CAMERA, arm or PointArm(), make_obstacles(state, ps.T_BASE_CAMERA, 0.0), **kw
    )


def _with_kinds(state):  # type: ignore[no-untyped-def]
    """o0 with one rim and one slide candidate: its pinch's poses, raised 1 and 2 cm."""
    o0 = state.by_name("o0")

    def raised(dz: float) -> tuple[np.ndarray, ...]:
        out = []
        for T in o0.grasp_candidates[0]:
            T2 = np.array(T, dtype=float)
            T2[:3, 3] += dz * np.asarray(state.table.normal)
            out.append(T2)
        return tuple(out)

    o0 = dataclasses.replace(o0, kind_candidates={"rim": (raised(0.01),), "slide": (raised(0.02),)})
    return dataclasses.replace(state, objects=(o0, *state.objects[1:]))


def test_each_kind_is_checked_on_its_own_poses() -> None:
    state = _with_kinds(_two_boxes())
    checker = _checker(state)
    o0 = state.by_name("o0")
    pinch = checker.poses(Action("grasp", "o0"))
    assert len(pinch) == 2  # the pinch's two half-turns, as the model holds them
    assert np.allclose(pinch[0][1], ps.T_BASE_CAMERA @ o0.grasp_candidates[0][1])
    for kind, dz in (("rim", 0.01), ("slide", 0.02)):
        cands = checker.poses(Action("grasp", "o0", None, kind))
        # one candidate: its half-turn is added (the gripper is symmetric)
        assert len(cands) == 2
        assert np.allclose(cands[0][1][:3, 3], pinch[0][1][:3, 3] + [0.0, 0.0, dz], atol=1e-9)
        assert np.allclose(cands[1][1][:3, :2], -cands[0][1][:3, :2]) and np.allclose(
            cands[1][1][:3, 2], cands[0][1][:3, 2]
        )
    # an object without a kind's poses: no motion, and it says so
    assert checker(Action("grasp", "o1", None, "rim")) == Infeasible("no gripper poses for this action", "poses")


def test_poses_move_with_a_pushed_object_but_a_slide_is_refused_after_a_push() -> None:
    state = _with_kinds(_two_boxes())
    checker = _checker(state)
    pushed = EMPTY.after(Action("push", "o0", "dir1"), state)
    shift_base = ps.T_BASE_CAMERA[:3, :3] @ pushed.shift_of("o0")
    for kind in ("pinch", "rim"):
        grasp = Action("grasp", "o0", None, kind)
        moved = checker.poses(grasp, pushed)
        assert np.allclose(moved[0][1][:3, 3], checker.poses(grasp)[0][1][:3, 3] + shift_base, atol=1e-9)
        assert checker(grasp, pushed).action == grasp  # checked where the push leaves it
    slide = Action("grasp", "o0", None, "slide")
    assert checker(slide).action == slide  # where it stands
    refused = checker(slide, pushed)
    assert isinstance(refused, Infeasible) and refused.kind == "poses" and "not after a push" in refused.reason
    assert refused.facts(slide) == (("ik_unfeasible_slide", "o0"),)


def test_the_check_is_cached_per_action_and_context_and_reports_the_candidate() -> None:
    state = _two_boxes()
    arm = PointArm()
    checker = _checker(state, arm)
    grasp = Action("grasp", "o0")
    first = checker(grasp)
    calls = arm.ik_calls
    assert checker(grasp) is first and arm.ik_calls == calls and len(checker.per_action_s) == 1
    assert first.candidate == 0 and len(first.joint_solutions) == len(first.T_base_gripper) == 3
    # no IK at the first candidate's grasp pose: the second (its half-turn, same position)
    # fails too; raised out of reach, none reaches
    p = first.T_base_gripper[1][:3, 3]
    blocked = _checker(state, PointArm(no_ik=(tuple(p),)))(grasp)
    assert blocked == Infeasible("no IK solution for pose 2/3", "ik")
    far = _checker(state, PointArm(reach_m=0.05))
    assert far.beyond_reach(grasp) == "beyond the arm's reach"
    assert _checker(state).beyond_reach(grasp) == ""


def test_push_lookahead_refuses_a_push_after_which_no_grasp_has_a_motion() -> None:
    state = _two_boxes()
    push = Action("push", "o0", "dir1")
    assert _checker(state, push_lookahead=True)(push).action == push
    # no IK at the grasp pose moved by the push (either half-turn: the same position)
    o0 = state.by_name("o0")
    shift = np.asarray(o0.pushes["dir1"].object_path[-1])
    moved_grasp = ps.T_BASE_CAMERA @ np.array(o0.grasp_candidates[0][1])
    moved_grasp[:3, 3] += ps.T_BASE_CAMERA[:3, :3] @ shift
    arm = PointArm(no_ik=(tuple(moved_grasp[:3, 3]),))
    refused = _checker(state, arm, push_lookahead=True)(push)
    assert isinstance(refused, Infeasible) and refused.kind == "lookahead"
    assert refused.reason.startswith("the push leaves o0 where it cannot be grasped (no IK solution for pose 2/3")
    assert refused.facts(push) == (("ik_unfeasible_dir", "o0", "dir1"),)
    # without the look-ahead, the same arm pushes
    assert _checker(state, arm)(push).action == push
    # an ungraspable object is pushed only out of the way: no look-ahead for it
    wide = dataclasses.replace(state, facts=frozenset({("ungraspable", "o0")}))
    assert _checker(wide, arm, push_lookahead=True)(push).action == push


def test_gripper_opening_text() -> None:
    assert gripper_opening_text(0.093, 0.07, 0.03) == "0.093 m wide across the grasp; the gripper opens to 0.070 m"
    assert gripper_opening_text(0.02, 0.07, 0.03) == "0.020 m wide across the grasp; the gripper closes to 0.030 m"


def test_poses_go_to_the_base_frame_moved_by_the_shift_bit_for_bit() -> None:
    # the base 1 m along the camera's x, the camera turned 90 deg about z: a pose at the
    # camera's origin, moved 0.1 m along the camera's x, is at (1, 0.1, 0) in the base
    T_base_camera = np.array([[0.0, -1.0, 0.0, 1.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0, 0, 0, 1.0]])
    checker = IKActionChecker(_two_boxes(), T_base_camera, PointArm(), None)
    turned = np.eye(4)
    turned[:3, :3] = [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]  # 90 deg about x
    turned[:3, 3] = [0.0, 0.2, 0.3]
    poses = (np.eye(4), turned.astype(np.float32))
    shift = np.array([0.1, 0.0, 0.0])
    base = checker._to_base(poses, shift)
    assert len(base) == 2 and all(T.shape == (4, 4) and T.dtype == np.float64 for T in base)
    assert np.allclose(base[0][:3, 3], [1.0, 0.1, 0.0], atol=1e-12)
    assert np.allclose(base[1][:3, 3], [0.8, 0.1, 0.3], atol=1e-7)  # camera (0.1, 0.2, 0.3) -> (1 - 0.2, 0.1, 0.3)
    assert np.allclose(base[1][:3, :3], T_base_camera[:3, :3] @ turned[:3, :3], atol=1e-7)
    # the same numbers, bit for bit, as one product per pose (what the plan's IK cache keys on)
    rng = np.random.default_rng(3)
    many = tuple(rng.normal(size=(4, 4)) for _ in range(5))
    for T, got in zip(many, checker._to_base(many, shift)):
        one = np.array(T, dtype=float)
        one[:3, 3] += shift
        assert (T_base_camera @ one).tobytes() == got.tobytes()
    assert poses[0][0, 3] == 0.0 and checker._to_base((), shift) == ()  # inputs left as they were; none: none
