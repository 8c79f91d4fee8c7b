"""`simulate`: a self-made clearing session (plan, act in a noisy world, render again),
written as an MCAP log; its summary as the payload of schema ``clear.simulate``.

A task, but of a session that makes its own frames, not of one frame: ``run(request,
out)`` writes the log to ``out`` and gives back the summary payload. There is no input,
so no `Source`, and it is never batched; ``check`` refuses a bad request before
anything is written.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from clearcli.errors import SettingsError
from clearcli.settings import Settings
from clearcli.sim import scene as scenes
from clearcli.sim.families import FAMILIES
from clearcli.sim.record import record_session

SCHEMA, VERSION = "simulate", 1
SCENES = ("clutter", "dense", "isolated_box", "two_touching_boxes", "box_on_box", "deadlock_row", "suction_mix")


@dataclass(frozen=True)
class Request:
    settings: Settings
    scene: str = "clutter"
    objects: int = 6  # clutter and dense scenes
    seed: int = 0  # seeds the scene, the world's noise and the camera
    max_actions: int = 40
    push_memory: bool = True
    truth_segmentation: bool = False


def check(request: Request) -> None:
    if request.scene not in SCENES:
        raise SettingsError(f"--scene {request.scene!r}: unknown; choose one of {', '.join(SCENES)}")


def run(request: Request, out: Path) -> dict[str, Any]:
    """Simulate and write the log to ``out``; the summary payload."""
    check(request)
    try:
        if request.scene in ("clutter", "dense"):
            world = getattr(scenes, request.scene)(request.objects, request.seed)
        elif request.scene in FAMILIES:  # a family of clearcli/sim/families.py, from --seed
            world = FAMILIES[request.scene](request.seed)
        else:
            world = getattr(scenes, request.scene)()
    except ValueError as exc:
        raise SettingsError(f"--scene {request.scene}: {exc}") from None
    count, result = record_session(
        out,
        world,
        request.settings,
        seed=request.seed,
        max_actions=request.max_actions,
        push_memory=request.push_memory,
        truth_segmentation=request.truth_segmentation,
    )
    return {
        "out": str(out),
        "frames": count,
        "scene": world.name,
        "seed": request.seed,
        "objects": result.n_objects,
        "end": result.end,
        "cleared_reachable": result.cleared_reachable,
        "cleared_truly": result.cleared_truly,
        "remaining": list(result.remaining),
        "unreachable": list(result.unreachable),
        "actions": result.actions,
        "max_actions": request.max_actions,
        "actions_per_object": {str(k): v for k, v in sorted(result.actions_per_object.items())},
        "back_and_forth": result.back_and_forth,
        "steps": [
            {"frame": s.frame_index, "status": s.status, "action": s.action or None, "outcome": s.outcome or None}
            for s in result.steps
        ],
    }
