"""`SymbolicState`: what the planner reasons about, and the geometry the IK check needs.

Contract between `predicates` (which builds it) and `plan` (which consumes it). Objects are
named o0..oN-1 in a stable order by position, not by segmentation order.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from clearcli.perception.types import TablePlane

DIRECTIONS: tuple[str, ...] = ("dir1", "dir2", "dir3", "dir4")

# Fact tuples, all names as strings:
#   ("on", a, b)                 a stands on b
#   ("block_grasp", a, b)        a blocks grasping b
#   ("block_dir", a, b, d)       a blocks pushing b along d
#   ("ungraspable", o)           static: o's width across the closing direction is outside
#                                the gripper's [closing, opening] range
#   ("push_off_table", o, d)     static: pushing o along d would leave the table polygon
#   ("ik_unfeasible_grasp", o), ("ik_unfeasible_dir", o, d)   added by the planner only
#   ("rim_graspable", o), ("slidable", o)   static: that grasp kind is offered for o
#   ("block_rim", a, b), ("block_slide", a, b)   a blocks that kind's grasp of b
#   ("ik_unfeasible_rim", o), ("ik_unfeasible_slide", o)   added by the planner only
Fact = tuple[str, ...]


@dataclass(frozen=True, eq=False)
class PushModel:
    """One push direction of one object.

    candidates: gripper pose sequences T_camera_gripper (4x4 each), one sequence per
    half-turn of the symmetric gripper: [pre-push, push start, path points..., end, retreat].
    """

    direction: str
    unit_vector: np.ndarray  # (3,) on the table plane, sensor frame
    push_length_m: float
    object_path: tuple[np.ndarray, ...]  # (3,) translations of the object along the push
    candidates: tuple[tuple[np.ndarray, ...], ...]


@dataclass(frozen=True, eq=False)
class ObjectModel:
    """An object as the predicates and the IK check see it (sensor frame)."""

    name: str
    segment_index: int  # index into Segmentation.objects
    centroid: np.ndarray  # (3,)
    principal_axes: np.ndarray  # (3, 3) rows, projected/orthonormalised: row 2 = table normal
    extents_m: np.ndarray  # (3,) full sizes along principal_axes rows
    hull_vertices: np.ndarray  # (V, 3) convex hull of the points and their table projection
    hull_faces: np.ndarray  # (F, 3) int
    # candidate grasp sequences, one per half-turn: [pre-grasp, grasp, lift]
    grasp_candidates: tuple[tuple[np.ndarray, ...], ...]
    pushes: Mapping[str, PushModel]
    # added by the predicates stage (defaults keep older constructors valid)
    grasp_width_m: float = 0.0  # size across the grasp's closing direction
    height_m: float = 0.0  # top above the table
    # the grasp kinds beyond the pinch (clearcli/predicates/grasps), by kind name: their
    # candidate pose sequences T_camera_gripper, what the JSON tells of them (a rim, a
    # slide's path), why a kind is not offered; a slide's translation (sensor frame)
    kind_candidates: Mapping[str, tuple[tuple[np.ndarray, ...], ...]] = field(default_factory=dict)
    kind_details: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    kind_refusals: Mapping[str, str] = field(default_factory=dict)
    slide_translation: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class SymbolicState:
    objects: tuple[ObjectModel, ...]
    table: TablePlane
    table_polygon: np.ndarray  # (K, 3)
    facts: frozenset[Fact]
    # cost of each push action (object name, direction) -> positive int; 1 = unit costs
    push_costs: Mapping[tuple[str, str], int] = field(default_factory=dict)
    timings_s: Mapping[str, float] = field(default_factory=dict)
    source: str = ""
    # segments left out of the model: (index into Segmentation.objects, reason)
    skipped: tuple[tuple[int, str], ...] = ()

    def names(self) -> tuple[str, ...]:
        return tuple(o.name for o in self.objects)

    def by_name(self, name: str) -> ObjectModel:
        for obj in self.objects:
            if obj.name == name:
                return obj
        raise KeyError(name)
