"""Self-made SymbolicStates for the plan stage's tests and benchmark.

A table in a world frame W (z up, surface at z = 0, x away from the robot), boxes on it,
a camera above the near edge looking at the table (optical frame: z forward, y down).
Gripper poses follow thesis 4.3: grasp = [pre-grasp, grasp, lift], push = [pre-push,
start, path points..., end, retreat]; gripper frame z = approach, x = closing direction.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clearcli.perception.types import TablePlane
from clearcli.predicates.state import (
    DIRECTIONS,
    Fact,
    ObjectModel,
    PushModel,
    SymbolicState,
)
from clearcli.predicates.synthetic import camera_pose

# The robot footprint in W: 0.10 m outside the near edge (x = 0), facing +x.
T_WORLD_BASE = np.array([[1.0, 0, 0, -0.10], [0, 1.0, 0, 0.0], [0, 0, 1.0, 0.346], [0, 0, 0, 1.0]])
TABLE_X = (0.0, 1.6)
TABLE_Y = (-0.8, 0.8)


T_WORLD_CAMERA = camera_pose((-0.05, 0.0, 0.75), (0.45, 0.0, 0.0))
T_CAMERA_WORLD = np.linalg.inv(T_WORLD_CAMERA)
T_BASE_CAMERA = np.linalg.inv(T_WORLD_BASE) @ T_WORLD_CAMERA


@dataclass(frozen=True)
class Box:
    x: float
    y: float
    size: tuple[float, float, float] = (0.10, 0.05, 0.12)  # along the principal axis, across, height
    yaw: float = 0.0
    z0: float = 0.0  # bottom height (stacked boxes)


def _pose(origin: np.ndarray, z: np.ndarray, x: np.ndarray) -> np.ndarray:
    z = z / np.linalg.norm(z)
    x = x - (x @ z) * z
    x /= np.linalg.norm(x)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    T[:3, 3] = origin
    return T


def _to_camera(Ts: list[np.ndarray]) -> tuple[np.ndarray, ...]:
    return tuple(T_CAMERA_WORLD @ T for T in Ts)


def _half(T: np.ndarray) -> np.ndarray:
    out = T.copy()
    out[:3, :2] *= -1
    return out


def box_object(name: str, box: Box, index: int = 0) -> ObjectModel:
    from scipy.spatial import ConvexHull

    c, s = np.cos(box.yaw), np.sin(box.yaw)
    a1 = np.array([c, s, 0.0])
    a2 = np.array([-s, c, 0.0])
    up = np.array([0.0, 0.0, 1.0])
    L, W, H = box.size
    centre = np.array([box.x, box.y, box.z0 + H / 2])
    corners = np.array(
        [
            centre + sx * L / 2 * a1 + sy * W / 2 * a2 + sz * H / 2 * up
            for sx in (-1, 1)
            for sy in (-1, 1)
            for sz in (-1, 1)
        ]
    )
    hull = ConvexHull(corners)
    down = -up
    # grasp: close across the principal axis, approach from above
    top = box.z0 + H
    g = _pose(np.array([box.x, box.y, max(top - 0.0225, box.z0 + 0.01)]), down, a2)
    pre = g.copy()
    pre[:3, 3] += 0.10 * up
    grasp_seq = [pre, g, pre.copy()]
    grasp = (_to_camera(grasp_seq), _to_camera([_half(T) for T in grasp_seq]))
    pushes = {}
    units = {"dir1": a1, "dir2": -a1, "dir3": a2, "dir4": -a2}
    for d in DIRECTIONS:
        u = units[d]
        extent = L if d in ("dir1", "dir2") else W
        length = min(1.0 * extent, 0.6)
        closing = u if d in ("dir1", "dir2") else np.cross(up, u)
        z_tcp = box.z0 + min(max(0.0325, H / 2), H)
        start_p = centre - u * (extent / 2 + 0.03)
        start_p[2] = z_tcp
        n = max(1, int(np.ceil(length / 0.03)))
        path = [start_p + u * length * (k / n) for k in range(n + 1)]
        seq = [_pose(p, down, closing) for p in path]
        pre_p = seq[0].copy()
        pre_p[:3, 3] += 0.10 * up
        retreat = seq[-1].copy()
        retreat[:3, 3] += 0.10 * up
        full = [pre_p, *seq, retreat]
        pushes[d] = PushModel(
            direction=d,
            unit_vector=T_CAMERA_WORLD[:3, :3] @ u,
            push_length_m=length,
            object_path=tuple(T_CAMERA_WORLD[:3, :3] @ (u * length * k / n) for k in range(n + 1)),
            candidates=(_to_camera(full), _to_camera([_half(T) for T in full])),
        )
    R = T_CAMERA_WORLD[:3, :3]
    t = T_CAMERA_WORLD[:3, 3]
    return ObjectModel(
        name=name,
        segment_index=index,
        centroid=R @ centre + t,
        principal_axes=np.array([R @ a1, R @ a2, R @ up]),
        extents_m=np.array([L, W, H]),
        hull_vertices=corners @ R.T + t,
        hull_faces=hull.simplices.astype(np.int64),
        grasp_candidates=grasp,
        pushes=pushes,
    )


def table_camera() -> tuple[TablePlane, np.ndarray]:
    R = T_CAMERA_WORLD[:3, :3]
    t = T_CAMERA_WORLD[:3, 3]
    n = R @ np.array([0.0, 0.0, 1.0])
    p0 = t  # the world origin (on the table) in the camera frame
    poly_w = np.array(
        [
            [TABLE_X[0], TABLE_Y[0], 0],
            [TABLE_X[1], TABLE_Y[0], 0],
            [TABLE_X[1], TABLE_Y[1], 0],
            [TABLE_X[0], TABLE_Y[1], 0],
        ]
    )
    return TablePlane(normal=n, offset=float(-n @ p0)), poly_w @ R.T + t


def scene(
    boxes: dict[str, Box],
    facts: set[Fact] | frozenset[Fact] = frozenset(),
    push_costs: dict[tuple[str, str], int] | None = None,
) -> SymbolicState:
    table, polygon = table_camera()
    objects = tuple(box_object(name, b, i) for i, (name, b) in enumerate(boxes.items()))
    return SymbolicState(
        objects=objects,
        table=table,
        table_polygon=polygon,
        facts=frozenset(facts),
        push_costs=dict(push_costs or {}),
        source="synthetic",
    )


def figure_3_1() -> SymbolicState:
    """Thesis Figure 3.1 rebuilt: o0 (black box) and o1 (red box) block each other's
    grasps; the white cup o2 blocks both and is out of the robot's reach."""
    boxes = {
        "o0": Box(0.55, 0.00),
        "o1": Box(0.55, 0.07),
        "o2": Box(1.10, 0.04, (0.07, 0.07, 0.10)),  # 1.2 m from the footprint
    }
    facts: set[Fact] = {
        ("block_grasp", "o2", "o0"),
        ("block_grasp", "o2", "o1"),
        ("block_grasp", "o0", "o1"),
        ("block_grasp", "o1", "o0"),
        ("block_dir", "o2", "o0", "dir1"),
    }
    for d in ("dir2", "dir3", "dir4"):
        facts.add(("block_dir", "o1", "o0", d))
    for d in DIRECTIONS:
        facts.add(("block_dir", "o0", "o1", d))
        facts.add(("block_dir", "o2", "o1", d))
    return scene(boxes, facts)


def clutter(n: int = 6, far: bool = False) -> SymbolicState:
    """n boxes in a loose grid within reach, with a few blocking facts; ``far`` adds an
    object 2 m away (o{n}) that blocks nothing."""
    boxes = {}
    for i in range(n):
        boxes[f"o{i}"] = Box(0.40 + 0.12 * (i // 3), -0.15 + 0.15 * (i % 3), yaw=0.3 * i)
    facts: set[Fact] = set()
    for i in range(n - 1):
        facts.add(("block_grasp", f"o{i + 1}", f"o{i}"))
        facts.add(("block_dir", f"o{i + 1}", f"o{i}", "dir1"))
    if n >= 3:
        facts.add(("on", "o2", "o1"))
    if far:
        boxes[f"o{n}"] = Box(2.0, 0.3)
    return scene(boxes, facts)


# -- the lifted model, for cross-checks ---------------------------------------------------

REPO = __import__("pathlib").Path(__file__).resolve().parents[2]

_LIFTED_DOMAIN = """(define (domain table-clearing-check)
  ; The thesis's model (listings 3.1/3.2) with the push direction as a parameter, written
  ; here only to cross-check the grounded compilation while pddl/domain.pddl is absent.
  (:requirements :typing :negative-preconditions :existential-preconditions
                 :universal-preconditions :conditional-effects :disjunctive-preconditions{costreq})
  (:types obj direction)
  (:constants dir1 dir2 dir3 dir4 - direction)
  (:predicates (on ?a ?b - obj) (block_grasp ?a ?b - obj) (block_dir ?a ?b - obj ?d - direction)
               (removed ?o - obj) (ungraspable ?o - obj) (push_off_table ?o - obj ?d - direction)
               (ik_unfeasible_grasp ?o - obj) (ik_unfeasible_dir ?o - obj ?d - direction)
               (dropped ?o - obj))
  {functions}
  (:action grasp
    :parameters (?o - obj)
    :precondition (and (not (ik_unfeasible_grasp ?o)) (not (ungraspable ?o))
                       (not (exists (?x - obj) (on ?x ?o)))
                       (not (exists (?x - obj) (block_grasp ?x ?o))))
    :effect (and (removed ?o)
                 (forall (?x - obj) (and (when (on ?o ?x) (not (on ?o ?x)))
                                         (when (block_grasp ?o ?x) (not (block_grasp ?o ?x)))))
                 (forall (?x - obj ?e - direction)
                   (when (block_dir ?o ?x ?e) (not (block_dir ?o ?x ?e))))
                 {grasp_cost}))
  (:action push
    :parameters (?o - obj ?d - direction)
    :precondition (and (not (ik_unfeasible_dir ?o ?d)) (not (push_off_table ?o ?d))
                       (not (exists (?x - obj) (block_dir ?x ?o ?d)))
                       (not (exists (?x - obj) (on ?x ?o)))
                       (not (exists (?x - obj) (on ?o ?x))))
    :effect (and (forall (?x - obj ?e - direction)
                   (and (when (block_dir ?o ?x ?e) (not (block_dir ?o ?x ?e)))
                        (when (block_dir ?x ?o ?e) (not (block_dir ?x ?o ?e)))))
                 (forall (?x - obj)
                   (and (when (block_grasp ?x ?o) (not (block_grasp ?x ?o)))
                        (when (block_grasp ?o ?x) (not (block_grasp ?o ?x)))))
                 (when (ik_unfeasible_grasp ?o) (not (ik_unfeasible_grasp ?o)))
                 {push_cost}))
)
"""


def own_lifted_pddl(
    names: list[str] | tuple[str, ...],
    facts: frozenset[Fact] | set[Fact],
    goal: list[str] | tuple[str, ...],
    push_costs: dict[tuple[str, str], int] | None = None,
) -> tuple[str, str]:
    push_costs = {k: v for k, v in (push_costs or {}).items() if v != 1}
    costs = bool(push_costs)
    domain = _LIFTED_DOMAIN.format(
        costreq=" :action-costs" if costs else "",
        functions="(:functions (total-cost) - number (push_cost ?o - obj ?d - direction) - number)" if costs else "",
        grasp_cost="(increase (total-cost) 1)" if costs else "",
        push_cost="(increase (total-cost) (push_cost ?o ?d))" if costs else "",
    )
    init = [f"({' '.join(f)})" for f in sorted(facts)]
    init += [f"(dropped {o})" for o in names if o not in goal]
    if costs:
        init.append("(= (total-cost) 0)")
        init += [f"(= (push_cost {o} {d}) {push_costs.get((o, d), 1)})" for o in names for d in DIRECTIONS]
    problem = (
        "(define (problem check) (:domain table-clearing-check)\n"
        f"  (:objects {' '.join(names)} - obj)\n"
        "  (:init " + " ".join(init) + ")\n"
        "  (:goal (forall (?x - obj) (or (removed ?x) (dropped ?x))))"
        + ("\n  (:metric minimize (total-cost))" if costs else "")
        + ")\n"
    )
    return domain, problem


def bare_object(
    name: str, centroid: np.ndarray, extents_m: np.ndarray, pushes: dict[str, PushModel], segment_index: int = 0
) -> ObjectModel:
    """An ObjectModel of placeholder geometry (axes the camera's, no hull, no grasp
    candidates) with these pushes: what symbolic tests need of an object."""
    return ObjectModel(
        name=name,
        segment_index=segment_index,
        centroid=centroid,
        principal_axes=np.eye(3),
        extents_m=extents_m,
        hull_vertices=np.zeros((0, 3)),
        hull_faces=np.zeros((0, 3), dtype=np.int64),
        grasp_candidates=(),
        pushes=pushes,
    )


def dummy_state(names: list[str], facts: frozenset[Fact], push_costs: dict | None = None) -> SymbolicState:
    """A SymbolicState with the given facts and placeholder geometry (symbolic tests)."""
    table, polygon = table_camera()
    objs = tuple(bare_object(n, np.zeros(3), np.zeros(3), {}, segment_index=i) for i, n in enumerate(names))
    return SymbolicState(objs, table, polygon, frozenset(facts), dict(push_costs or {}))


def lifted_pddl(
    names: list[str] | tuple[str, ...],
    facts: frozenset[Fact] | set[Fact],
    goal: list[str] | tuple[str, ...],
    push_costs: dict[tuple[str, str], int] | None = None,
    state: SymbolicState | None = None,
) -> tuple[str, str, str]:
    """(domain, problem, which): the project's lifted domain (pddl/domain.pddl +
    clearcli.planning.pddl.write_problem) when present, else the one above."""
    domain_file = REPO / "pddl" / "domain.pddl"
    try:
        from clearcli.planning import pddl as project_pddl  # type: ignore[attr-defined]

        if not domain_file.is_file():
            raise ImportError
    except ImportError:
        d, p = own_lifted_pddl(list(names), frozenset(facts), list(goal), push_costs)
        return d, p, "tests/plan_scenes.py (pddl/domain.pddl not present)"
    base_facts = frozenset(f for f in facts if not f[0].startswith("ik_unfeasible"))
    ik = tuple(sorted(f for f in facts if f[0].startswith("ik_unfeasible")))
    st = state if state is not None else dummy_state(list(names), base_facts, push_costs)
    problem = project_pddl.write_problem(st, goal_objects=list(goal), extra_facts=ik)
    return domain_file.read_text(encoding="utf-8"), problem, "pddl/domain.pddl"


def validate(domain: str, problem: str, actions) -> bool:  # type: ignore[no-untyped-def]
    """unified-planning's SequentialPlanValidator on the lifted files."""
    import tempfile
    from pathlib import Path

    from unified_planning.engines import SequentialPlanValidator
    from unified_planning.engines.results import ValidationResultStatus
    from unified_planning.io import PDDLReader
    from unified_planning.plans import ActionInstance, SequentialPlan

    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "d.pddl").write_text(domain)
        (Path(tmp) / "p.pddl").write_text(problem)
        prob = PDDLReader().parse_problem(str(Path(tmp) / "d.pddl"), str(Path(tmp) / "p.pddl"))
    names = {a.name for a in prob.actions}
    steps = []
    for a in actions:
        if a.kind == "grasp":
            steps.append(ActionInstance(prob.action("grasp"), (prob.object(a.obj),)))
        elif "push" in names and len(prob.action("push").parameters) == 2:
            steps.append(ActionInstance(prob.action("push"), (prob.object(a.obj), prob.object(a.direction))))
        else:
            steps.append(ActionInstance(prob.action(f"push_{a.direction}"), (prob.object(a.obj),)))
    with SequentialPlanValidator() as v:
        res = v.validate(prob, SequentialPlan(steps))
    return res.status == ValidationResultStatus.VALID
