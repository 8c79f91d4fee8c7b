"""Top view of a `SymbolicState`: hulls, push directions, grasp grippers, blocking arrows.

Drawn in the table frame (`clearcli.geometry.models.TableFrame`: x away from the camera,
drawn upwards; y drawn to the left, so the picture looks like the camera's view from
above). matplotlib (Agg) is imported inside the function.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from clearcli.geometry.gripper import gripper_model
from clearcli.geometry.models import TableFrame
from clearcli.predicates.state import SymbolicState

_DIR_COLOURS = {"dir1": "tab:red", "dir2": "tab:orange", "dir3": "tab:blue", "dir4": "tab:cyan"}


def render_predicates_png(state: SymbolicState, path: Path, title: str = "") -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import FancyArrowPatch, Polygon
    from scipy.spatial import ConvexHull

    tf = TableFrame.from_plane(state.table)
    gripper = gripper_model()

    def view(xy: np.ndarray) -> np.ndarray:  # table (x, y) -> picture (right = -y, up = x)
        xy = np.atleast_2d(xy)
        return np.column_stack([-xy[:, 1], xy[:, 0]])

    fig, ax = plt.subplots(figsize=(9, 9), dpi=100)
    if len(state.table_polygon) >= 3:
        t = tf.to_table(state.table_polygon)[:, :2]
        ax.add_patch(Polygon(view(t), closed=True, facecolor="0.93", edgecolor="0.6", lw=1))
    centres: dict[str, np.ndarray] = {}
    ungraspable = {f[1] for f in state.facts if f[0] == "ungraspable"}
    supports: dict[str, list[str]] = {}
    for f in sorted(state.facts):
        if f[0] == "on":
            supports.setdefault(f[1], []).append(f[2])
    supported = {f[2] for f in state.facts if f[0] == "on"}
    for obj in state.objects:
        v = tf.to_table(obj.hull_vertices)
        xy = v[:, :2]
        try:
            ring = xy[ConvexHull(xy).vertices]
        except Exception:  # a sliver: draw its points
            ring = xy
        face = "tab:gray" if obj.name in ungraspable else "tab:green"
        ax.add_patch(Polygon(view(ring), closed=True, facecolor=face, alpha=0.35, edgecolor="k", lw=1))
        c = ring.mean(axis=0)
        centres[obj.name] = c
        label = f"{obj.name}\n{obj.height_m * 100:.0f} cm"
        if obj.name in supports:  # a stack's centres coincide: say it in words too
            label += "\non " + ",".join(supports[obj.name])
        at = view(c)[0]
        if obj.name in supports:  # labels of a stack apart: upper one above, lower below
            at = at + [0.0, 0.03]
        elif obj.name in supported:
            at = at - [0.0, 0.03]
        ax.annotate(label, at, ha="center", va="center", fontsize=8)
        for d, push in obj.pushes.items():
            u = (tf.T_table_camera[:3, :3] @ push.unit_vector)[:2]
            tip = c + u * min(0.05, push.push_length_m)
            ax.annotate(
                "",
                view(tip)[0],
                view(c)[0],
                arrowprops={"arrowstyle": "->", "color": _DIR_COLOURS[d], "lw": 1.2},
            )
        if obj.grasp_candidates:
            T = tf.T_table_camera @ obj.grasp_candidates[0][1]
            corners = gripper.boxes(False).transformed_corners(T)
            for part in corners[:2]:  # the two fingers' footprints
                pxy = part[:, :2]
                try:
                    pxy = pxy[ConvexHull(pxy).vertices]
                except Exception:
                    continue
                ax.add_patch(Polygon(view(pxy), closed=True, facecolor="tab:purple", alpha=0.6, lw=0))
    styles = {"block_grasp": ("tab:purple", "-"), "block_dir": ("tab:red", "--"), "on": ("k", "-")}
    drawn: set[tuple[str, str, str]] = set()
    for fact in sorted(state.facts):
        kind = fact[0]
        if kind not in styles or (kind, fact[1], fact[2]) in drawn:
            continue
        drawn.add((kind, fact[1], fact[2]))
        colour, ls = styles[kind]
        a, b = view(centres[fact[1]])[0], view(centres[fact[2]])[0]
        ax.add_patch(
            FancyArrowPatch(
                a,
                b,
                arrowstyle="-|>",
                mutation_scale=12,
                color=colour,
                ls=ls,
                lw=2.0 if kind == "on" else 0.9,
                alpha=0.8,
                connectionstyle="arc3,rad=0.15",
                shrinkA=8,
                shrinkB=8,
            )
        )
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("table -y (m)")
    ax.set_ylabel("table x, away from the camera (m)")
    ax.set_title(
        (title + "\n" if title else "")
        + "arrows a->b: black on(a,b), purple block_grasp(a,b), red dashed block_dir(a,b,*); "
        "grey = ungraspable; purple bars = open fingers at the grasp\n"
        "push directions: dir1 red, dir2 orange, dir3 blue, dir4 cyan",
        fontsize=8,
    )
    fig.tight_layout()
    fig.savefig(path, format="png")
    plt.close(fig)
