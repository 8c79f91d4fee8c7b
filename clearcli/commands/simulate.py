"""`clear simulate OUT.mcap`: a self-made clearing session, written as a log to replay."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from clearcli.commands.basic import SettingsOpt

SCENES = ("clutter", "dense", "isolated_box", "two_touching_boxes", "box_on_box", "deadlock_row")


def simulate_cmd(
    out: Annotated[Path, typer.Argument(help="The MCAP log to write (ROS 2 sensor_msgs/PointCloud2).")],
    seed: Annotated[int, typer.Option("--seed", help="Seeds the scene, the world's noise and the camera.")] = 0,
    objects: Annotated[int, typer.Option("--objects", min=1, max=20, help="Objects of a clutter scene.")] = 6,
    scene: Annotated[
        str, typer.Option("--scene", help=f"Scene: {', '.join(SCENES)} (clutter and dense use --objects, --seed).")
    ] = "clutter",
    max_actions: Annotated[int, typer.Option("--max-actions", min=1, help="Action budget.")] = 40,
    no_push_memory: Annotated[
        bool, typer.Option("--no-push-memory", help="Plan every frame afresh, as the thesis did.")
    ] = False,
    truth_segmentation: Annotated[
        bool,
        typer.Option("--truth-segmentation", help="Segment with the camera's labels instead of the segmenter."),
    ] = False,
    force: Annotated[bool, typer.Option("--force", help="Overwrite OUT if it exists.")] = False,
    json_out: Annotated[bool, typer.Option("--json", help="Machine-readable summary.")] = False,
    settings: SettingsOpt = None,
) -> None:
    """Simulate a clearing session: plan on a rendered frame, carry out the first action
    in a world that slides, turns and slips, render again, until the table is clear, no
    plan exists or the budget runs out. The frames go to OUT for `clear replay`."""
    from clearcli.commands.common import check_output_path, print_json, stderr, stdout
    from clearcli.errors import SettingsError
    from clearcli.settings import load_settings
    from clearcli.sim import scene as scenes
    from clearcli.sim.episode import record_session

    config = load_settings(settings)
    if scene not in SCENES:
        raise SettingsError(f"--scene {scene!r}: unknown; choose one of {', '.join(SCENES)}")
    check_output_path(out, force)
    try:
        if scene in ("clutter", "dense"):
            world = getattr(scenes, scene)(objects, seed)
        else:
            world = getattr(scenes, scene)()
    except ValueError as exc:
        raise SettingsError(f"--scene {scene}: {exc}") from None
    with stderr.status("simulating", spinner="dots") if not json_out else _nothing():
        count, result = record_session(
            out,
            world,
            config,
            seed=seed,
            max_actions=max_actions,
            push_memory=not no_push_memory,
            truth_segmentation=truth_segmentation,
        )
    payload: dict[str, Any] = {
        "out": str(out),
        "frames": count,
        "scene": world.name,
        "seed": seed,
        "objects": result.n_objects,
        "end": result.end,
        "cleared_reachable": result.cleared_reachable,
        "cleared_truly": result.cleared_truly,
        "remaining": list(result.remaining),
        "unreachable": list(result.unreachable),
        "actions": result.actions,
        "max_actions": max_actions,
        "actions_per_object": {str(k): v for k, v in sorted(result.actions_per_object.items())},
        "back_and_forth": result.back_and_forth,
        "steps": [
            {"frame": s.frame_index, "status": s.status, "action": s.action or None, "outcome": s.outcome or None}
            for s in result.steps
        ],
    }
    if json_out:
        print_json("simulate", payload)
        return
    for s in result.steps:
        if s.action:
            stdout.print(f"frame {s.frame_index}: {s.action} -> {s.outcome}")
        else:
            stdout.print(f"frame {s.frame_index}: {s.status}")
    stdout.print(
        f"{out}: {count} frames, {result.n_objects} objects, end: {result.end}, "
        f"{result.actions} actions, left: {', '.join(map(str, result.remaining)) or 'none'}"
        + (f" (unreachable: {', '.join(map(str, result.unreachable))})" if result.unreachable else "")
    )


class _nothing:
    def __enter__(self) -> None:
        return None

    def __exit__(self, *args: Any) -> None:
        return None
