"""A simulated clearing session written as a log: the episode's frames as a ROS 2
PointCloud2 MCAP, with the robot's place on /tf_static (`clear simulate`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from clearcli.io.mcap_write import StaticTransform, write_pointcloud2_mcap
from clearcli.pipeline import Pipeline
from clearcli.replay.session import ReplayOptions, Session
from clearcli.robot.arm import resolve_arm
from clearcli.settings import Settings
from clearcli.sim.episode import Episode, EpisodeResult
from clearcli.sim.scene import Scene
from clearcli.sim.truth import truth_segment


def static_transforms(T_base_camera: np.ndarray, frame_id: str, base_frame: str | None = None) -> list[Any]:
    """/tf_static's one transform: the points' frame in the robot's base, named
    ``base_frame`` (None: as the default profile's logs name it, the WAM's "wam_base")."""
    if base_frame is None:
        base_frame = resolve_arm(Settings()).profile.tf_base_frame
    return [StaticTransform(parent_frame=base_frame, child_frame=frame_id, T_parent_child=np.asarray(T_base_camera))]


def record_session(
    path: Any,
    world: Scene,
    settings: Any,
    *,
    seed: int,
    max_actions: int = 40,
    push_memory: bool = True,
    truth_segmentation: bool = False,
) -> tuple[int, EpisodeResult]:
    """Run a closed-loop episode on ``world`` and write its frames, with the robot base
    on /tf_static, to the MCAP at ``path``; returns (frames written, the episode's result)."""
    pipeline = Pipeline(settings, segment_fn=truth_segment if truth_segmentation else None)
    options = ReplayOptions(
        push_memory=push_memory, stop_when_cleared=True, tracking=settings.tracking, memory=settings.memory
    )
    session = Session(pipeline, options)
    episode = Episode(world, session, seed=seed, max_actions=max_actions, params=settings.world)
    first = episode.render(0)
    T_base_camera = episode.robot_placement(first)
    # the base frame as the arm's profile names it on a log (the WAM's as the thesis's logs do)
    base = pipeline.robot.profile.tf_base_frame
    count = write_pointcloud2_mcap(path, episode, tf_static=static_transforms(T_base_camera, first.frame_id, base))
    assert episode.result is not None
    return count, episode.result
