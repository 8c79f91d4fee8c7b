"""Tests of clearcli/sim/scene.py."""

from __future__ import annotations

from itertools import combinations

import numpy as np
import pytest
from helpers.sim import clutter_scene  # noqa: F401  (fixtures)

from clearcli.sim import scene as S
from clearcli.sim.camera import render
from clearcli.sim.scene import Box


@pytest.mark.parametrize("seed", [0, 1, 3, 7])
def test_clutter_objects_are_graspable_and_do_not_overlap(seed: int) -> None:
    scene = S.clutter(10, seed=seed)
    assert scene.n_objects == 10
    assert [o.object_id for o in scene.objects] == list(range(10))
    gaps = []
    for obj in scene.objects:
        width = min(obj.size_x_m, obj.size_y_m) if isinstance(obj, Box) else 2 * obj.radius_m
        assert S.MIN_WIDTH_M <= width <= S.MAX_WIDTH_M
        assert obj.base_z_m == 0.0
    for a, b in combinations(scene.objects, 2):
        assert not S.polygons_overlap(a.footprint(), b.footprint(), clearance_m=-1e-9)
        gaps.append(_gap(a.footprint(), b.footprint()))
    touching = sum(g < 0.001 for g in gaps)
    assert touching >= 1
    # Objects not in contact are clearly apart.
    assert all(g < 0.001 or g >= S.CLUTTER_MIN_GAP_M - 1e-9 for g in gaps)


def _gap(a: np.ndarray, b: np.ndarray) -> float:
    """Largest separation along the polygons' edge normals (0 or less when they touch)."""
    best = -np.inf
    for poly in (a, b):
        edges = np.roll(poly, -1, axis=0) - poly
        normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1)
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        pa, pb = a @ normals.T, b @ normals.T
        best = max(best, float(np.max(np.maximum(pb.min(0) - pa.max(0), pa.min(0) - pb.max(0)))))
    return best


def test_moving_and_removing_objects_returns_new_scenes(clutter_scene: S.Scene) -> None:
    moved = S.with_object_pose(clutter_scene, 2, 0.05, -0.2, 0.3)
    assert moved is not clutter_scene and moved.objects[2].x_m == 0.05
    assert clutter_scene.objects[2].x_m != 0.05  # the original is untouched
    assert moved.objects[2].object_id == 2 and moved.objects[:2] == clutter_scene.objects[:2]
    removed = S.without_object(moved, 0)
    assert removed.n_objects == 9
    assert [o.object_id for o in removed.objects] == list(range(1, 10))
    frame = render(removed, seed=0)
    labels = set(np.unique(frame.fields["label"]).tolist())
    assert 10 not in labels and 20 in labels
    with pytest.raises(IndexError):
        S.without_object(removed, 9)
