"""A first plan from Python: segment a frame, look at its objects, plan to clear it.

Run it as `python docs/examples/first_plan.py [FRAME]` (default: the 10-object fixture);
it prints what `clear plan FRAME --json` says of the same frame (tests/docs/ checks so).
"""

import sys

from clearcli import api

frame = sys.argv[1] if len(sys.argv) > 1 else "fixtures/clutter10.pcd"
settings = api.Settings.default()  # e.g. .with_(**{"segment.voxel_m": 0.004}) or Settings.default(robot="panda")

seg = api.segment(frame, settings=settings)
print(f"{len(seg.objects)} objects on a table of {seg.table_indices.size} points")
for obj in seg.objects:
    x, y, z = obj.centroid_m
    print(f"  object {obj.id}: {obj.indices.size} points, centroid ({x:+.3f}, {y:+.3f}, {z:+.3f}) m")

plan = api.plan(frame, settings=settings)
print(f"plan: {plan.status}, {len(plan.steps)} actions")
for k, step in enumerate(plan.steps, 1):
    print(f"  {k}. {step.action}")
for name in plan.left:
    print(f"  left: {name}")
print(f"the robot's base from the camera, T_base_camera:\n{plan.T_base_camera.round(3)}")
