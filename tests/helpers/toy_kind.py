"""A toy grasp kind for tests/predicates/test_toy_kind.py: a magnet set straight
down on the middle of an object's top, for what no kind before it takes.

It is all a new kind needs: one object implementing
`clearcli.predicates.grasps.base.GraspKind` (this module) and one registry entry
(clearcli/settings/kinds.py; the test adds it with monkeypatch). Nothing else in clear
names it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from clearcli.predicates.grasps.base import UP, KindFacts, KindModule, Offer, Scene, SimWorld

SUCTION_MIN_TOP_M = 0.05  # the cup needs a top at least this wide (either way)
SUCTION_COLUMN_M = 0.03  # what stands within this of the cup's axis, above the top, blocks it


class SuctionGrasp(KindModule):
    name = "magnet"
    label = "magnet grasp"
    facts = KindFacts("magnet_grasp", "magnet_graspable", "block_magnet", "ik_unfeasible_magnet", 4)
    instead = "it is sucked up instead"

    def offers(self, scene: Scene, gripper: Any, settings: Any) -> list[Offer]:
        from clearcli.geometry.poses import _pose

        out = []
        boxes = [np.asarray(o.aabb, dtype=float) for o in scene.objects]
        for i, obj in enumerate(scene.objects):
            taken = next((k.instead for k, offered in scene.offered_before if i in offered), "")
            if taken:
                out.append(Offer(why_not=taken))
                continue
            lo, hi = boxes[i]
            if min(hi[:2] - lo[:2]) < SUCTION_MIN_TOP_M:
                out.append(Offer(why_not=f"its top is narrower than {SUCTION_MIN_TOP_M:.2f} m"))
                continue
            centre = np.asarray(obj.center, dtype=float)
            point = np.array(
                [centre[0], centre[1], float(obj.top_height_m) + gripper.settings.closing_region_height_m / 2]
            )
            T = _pose(np.array([1.0, 0.0, 0.0]), -UP, point)
            pre, lift = T.copy(), T.copy()
            pre[:3, 3] += settings.push.approach_m * UP
            lift[:3, 3] += settings.push.approach_m * UP
            blockers = frozenset(
                a
                for a, (alo, ahi) in enumerate(boxes)
                if a != i
                and (a, i) not in scene.exclude
                and ahi[2] > obj.top_height_m
                and np.all(alo[:2] <= point[:2] + SUCTION_COLUMN_M)
                and np.all(ahi[:2] >= point[:2] - SUCTION_COLUMN_M)
            )
            out.append(Offer(candidates=((pre, T, lift),), blockers=blockers, detail={"center": point.tolist()}))
        return out

    def world_holds(self, obj: Any, gripper: Any, rules: Any) -> bool:
        """The world's rule: a closed top at least SUCTION_MIN_TOP_M wide."""
        return not rules.open_container(obj) and rules.grasp_width_m(obj) >= SUCTION_MIN_TOP_M

    def simulate(self, world: SimWorld) -> str:
        """The cup holds when the arm set it down over the object's true top."""
        obj = world.scene.objects[world.k]
        T_camera = world.chosen_pose(world.model.kind_candidates.get(self.name, ()))
        if T_camera is None:
            return "missed: no magnet pose"
        xy = (world.T_table_camera @ T_camera)[:2, 3]
        if not self.world_holds(obj, world.gripper, world.rules):
            return "the cup found no flat top"
        if float(np.hypot(xy[0] - obj.x_m, xy[1] - obj.y_m)) > world.rules.grasp_width_m(obj) / 2:
            return "the cup came down beside it"
        world.take()
        return "removed"


KIND = SuctionGrasp()
