"""`clear plan --png`: a top view of the table in the robot base frame with the plan.

Objects are drawn as their hulls seen from above, coloured by role (in the goal,
unreachable, cannot be freed, ungraspable), numbered by the step that removes or pushes
them; pushes are arrows; the robot's shoulder is at the origin, its reach circle dashed.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from clearcli.predicates.grasps import kind as grasp_kind
from clearcli.render.camera import draw_camera_view, has_camera_picture
from clearcli.robot.arm import Arm, resolve_arm
from clearcli.settings import Settings


def render_plan(path: Path, frame: Any, state: Any, plan: Any, seg: Any = None, robot: Arm | None = None) -> None:
    """Write the plan picture at ``path``: the objects from above in the robot's base
    frame, coloured by what the plan does with them, pushes as arrows; beside it, when
    the frame has colour and ``seg`` is given, the camera's picture with the same
    objects outlined in the same colours and named with their plan steps."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle
    from scipy.spatial import ConvexHull

    if robot is None:  # the default settings' arm
        robot = resolve_arm(Settings())
    arm = robot.profile

    T = plan.T_base_camera if plan.T_base_camera is not None else np.eye(4)
    R, t = T[:3, :3], T[:3, 3]
    with_camera = seg is not None and has_camera_picture(frame)
    if with_camera:
        fig, (ax_cam, ax) = plt.subplots(1, 2, figsize=(14, 7), dpi=110)
    else:
        fig, ax = plt.subplots(figsize=(7, 7), dpi=110)
    poly = np.asarray(state.table_polygon, dtype=float).reshape(-1, 3) @ R.T + t
    if len(poly) >= 3:
        ax.fill(poly[:, 0], poly[:, 1], color="#e8e2d0", zorder=0, label="table")
    colours = {}
    for o in plan.goal:
        colours[o] = "#4c9a2a"
    for o in plan.stuck:
        colours[o] = "#e08a1e"
    for o in plan.ungraspable:
        colours[o] = "#8d8d8d"
    for o in plan.unreachable:
        colours[o] = "#c0392b"
    steps: dict[str, list[str]] = {}
    for i, a in enumerate(plan.actions, 1):
        # each step named: "2 push", "3 pinch", "4 rim", "5 slide" (the grasp kind)
        steps.setdefault(a.obj, []).append(f"{i} {a.grasp_kind if a.kind == 'grasp' else 'push'}")
    for obj in state.objects:
        v = np.asarray(obj.hull_vertices, dtype=float)
        if len(v) < 3:
            continue
        vb = v @ R.T + t
        xy = vb[:, :2]
        try:
            hull = ConvexHull(xy)
            ring = xy[hull.vertices]
        except Exception:  # degenerate outline: draw the points
            ring = xy
        ax.fill(ring[:, 0], ring[:, 1], color=colours.get(obj.name, "#3a6ea5"), alpha=0.75, zorder=2)
        c = xy.mean(axis=0)
        label = obj.name + (f" [{','.join(steps[obj.name])}]" if obj.name in steps else "")
        ax.text(c[0], c[1], label, ha="center", va="center", fontsize=8, zorder=4)
    if with_camera:
        from matplotlib.colors import to_rgb

        objs = [o for o in state.objects if 0 <= o.segment_index < len(seg.objects)]
        draw_camera_view(
            ax_cam,
            frame,
            [seg.objects[o.segment_index].indices for o in objs],
            [to_rgb(colours.get(o.name, "#3a6ea5")) for o in objs],
            [o.name + (f" [{','.join(steps[o.name])}]" if o.name in steps else "") for o in objs],
        )
        ax_cam.set_title("camera view (colour; objects outlined, [plan steps])", fontsize=9)
    for a in plan.actions:
        if a.kind == "grasp":
            # a grasp that first moves the object (a slide to the table's edge): a dashed
            # arrow to where it is grasped (its kind says, clearcli/predicates/grasps)
            obj = state.by_name(a.obj)
            contact = obj.kind_details.get(str(a.grasp_kind), {})
            if "point" in contact and "normal" in contact:
                # a suction cup's contact: the cup's disc and the face's normal
                p = R @ np.asarray(contact["point"], dtype=float) + t
                n = R @ np.asarray(contact["normal"], dtype=float)
                r = float(contact.get("cup_diameter_m", 0.03)) / 2.0
                ax.add_patch(Circle((p[0], p[1]), r, fill=False, color="k", lw=1.2, zorder=6))
                ax.plot([p[0]], [p[1]], marker="+", color="k", ms=5, zorder=6)
                if float(np.hypot(n[0], n[1])) > 0.3:  # a side's normal shows in the plan view
                    ax.annotate(
                        "",
                        xy=(p[0] + 0.05 * n[0], p[1] + 0.05 * n[1]),
                        xytext=(p[0], p[1]),
                        arrowprops=dict(arrowstyle="->", color="k", lw=1.0),
                        zorder=6,
                    )
            moved = grasp_kind(a.grasp_kind).moved_before(obj)
            if moved is not None:
                c = R @ np.asarray(obj.centroid, dtype=float) + t
                u = R @ np.asarray(moved, dtype=float)
                ax.annotate(
                    "",
                    xy=(c[0] + u[0], c[1] + u[1]),
                    xytext=(c[0], c[1]),
                    arrowprops=dict(arrowstyle="->", color="k", lw=1.5, ls="--"),
                    zorder=5,
                )
            continue
        if a.kind != "push":
            continue
        obj = state.by_name(a.obj)
        push = obj.pushes.get(a.direction)
        if push is None:
            continue
        c = R @ np.asarray(obj.centroid, dtype=float) + t
        u = R @ np.asarray(push.unit_vector, dtype=float) * max(push.push_length_m, 0.05)
        ax.annotate(
            "",
            xy=(c[0] + u[0], c[1] + u[1]),
            xytext=(c[0], c[1]),
            arrowprops=dict(arrowstyle="->", color="k", lw=1.5),
            zorder=5,
        )
    # the gripper's closing point at full stretch, round the shoulder's vertical axis
    reach = robot.reach_of_tcp_m
    sx, sy = arm.shoulder_base[0], arm.shoulder_base[1]
    ax.add_patch(Circle((sx, sy), reach, fill=False, ls="--", color="#555555", zorder=1))
    ax.plot([0], [0], marker="o", color="k", zorder=5)
    ax.text(0, -0.04, arm.picture_label, ha="center", va="top", fontsize=8)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m, robot base)")
    ax.set_ylabel("y (m, robot base)")
    status = "optimal" if plan.optimal else "not proven optimal"
    outcome = {
        "complete": "every object removed",
        "partial": f"{len(plan.left)} left",
        "no_plan": "nothing can be done",
    }
    checked = "every action IK-checked" if plan.check == "whole" else "first action IK-checked"
    ax.set_title(
        f"{plan.status}: {outcome.get(plan.status, '')}; {len(plan.actions)} actions, cost {plan.cost} ({status}); {checked}",
        fontsize=9,
    )
    from matplotlib.patches import Patch

    ax.legend(
        handles=[
            Patch(color="#4c9a2a", label="in the goal"),
            Patch(color="#c0392b", label="unreachable"),
            Patch(color="#e08a1e", label="cannot be freed"),
            Patch(color="#8d8d8d", label="ungraspable"),
        ],
        loc="upper right",
        fontsize=7,
    )
    fig.tight_layout()
    fig.savefig(str(path), format="png")
    plt.close(fig)
