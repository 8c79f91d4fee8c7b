"""`clear simulate OUT.mcap`: a self-made clearing session, written as a log to replay."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from clearcli.commands import options as bo
from clearcli.commands.common import check_output_path, print_json, stderr, stdout

SCENES = (
    "clutter",
    "dense",
    "isolated_box",
    "two_touching_boxes",
    "box_on_box",
    "deadlock_row",
    "suction_mix",
)  # tasks/simulate.py


def simulate_cmd(
    out: Annotated[Path, typer.Argument(help="The MCAP log to write (ROS 2 sensor_msgs/PointCloud2).")],
    seed: Annotated[int, typer.Option("--seed", help="Seeds the scene, the world's noise and the camera.")] = 0,
    objects: Annotated[int, typer.Option("--objects", min=1, max=20, help="Objects of a clutter scene.")] = 6,
    scene: Annotated[
        str,
        typer.Option(
            "--scene", help=f"Scene: {', '.join(SCENES)} (clutter and dense use --objects, --seed; suction_mix --seed)."
        ),
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
    settings: bo.SettingsFile = None,
    sets: bo.Set = None,
    robot: bo.Robot = None,
    grasps: bo.Grasps = None,
) -> None:
    """Simulate a clearing session: plan on a rendered frame, carry out the first action
    in a world that slides, turns and slips, render again, until the table is clear, no
    plan exists or the budget runs out. The frames go to OUT for `clear replay`."""
    from clearcli.tasks import simulate as task  # noqa: PLC0415  (the task, ~1.3 s: not for `clear --help`)

    config = bo.resolve_settings(
        settings, sets, "replay", robot=robot, grasps=grasps, push_memory=False if no_push_memory else None
    )
    request = task.Request(
        config,
        scene=scene,
        objects=objects,
        seed=seed,
        max_actions=max_actions,
        push_memory=config.replay.push_memory,
        truth_segmentation=truth_segmentation,
    )
    task.check(request)
    from clearcli.tasks import sources  # noqa: PLC0415  (~170 ms: not for `clear --help`)

    check_output_path(out, force, sources.run_files(config, also=(settings,)))
    with stderr.status("simulating", spinner="dots") if not json_out else _nothing():
        payload = task.run(request, out)
    if json_out:
        print_json(task.SCHEMA, task.VERSION, payload, config, "simulate")
        return
    for s in payload["steps"]:
        if s["action"]:
            stdout.print(f"frame {s['frame']}: {s['action']} -> {s['outcome']}")
        else:
            stdout.print(f"frame {s['frame']}: {s['status']}")
    stdout.print(
        f"{out}: {payload['frames']} frames, {payload['objects']} objects, end: {payload['end']}, "
        f"{payload['actions']} actions, left: {', '.join(map(str, payload['remaining'])) or 'none'}"
        + (f" (unreachable: {', '.join(map(str, payload['unreachable']))})" if payload["unreachable"] else "")
    )


class _nothing:
    def __enter__(self) -> None:
        return None

    def __exit__(self, *args: Any) -> None:
        return None
