"""A simulated clearing session written as a log: the episode's frames as a ROS 2
PointCloud2 MCAP, with the robot's place on /tf_static (`clear simulate`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from clearcli.sim.episode import Episode, EpisodeResult
from clearcli.sim.scene import Scene
from clearcli.sim.truth import truth_segment

# the WAM's base as the thesis's logs name it; another arm's is its profile's base frame
BASE_FRAME = "wam_base"


def static_transforms(T_base_camera: np.ndarray, frame_id: str, base_frame: str = BASE_FRAME) -> list[Any]:
    from clearcli.io.mcap_write import StaticTransform

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
) -> tuple[int, "EpisodeResult"]:
    """Run a closed-loop episode on ``world`` and write its frames, with the robot base
    on /tf_static, to the MCAP at ``path``; returns (frames written, the episode's result)."""
    from clearcli.io.mcap_write import write_pointcloud2_mcap
    from clearcli.pipeline import Pipeline
    from clearcli.replay.session import ReplayOptions, Session

    pipeline = Pipeline(settings, segment_fn=truth_segment if truth_segmentation else None)
    options = ReplayOptions(
        push_memory=push_memory, stop_when_cleared=True, tracking=settings.tracking, memory=settings.memory
    )
    session = Session(pipeline, options)
    episode = Episode(world, session, seed=seed, max_actions=max_actions, params=settings.world)
    first = episode.render(0)
    T_base_camera = episode.robot_placement(first)
    from clearcli.robot.profiles import profile_of

    arm = profile_of(settings.robot)
    base = BASE_FRAME if arm.name == "wam" else arm.base_frame
    count = write_pointcloud2_mcap(path, episode, tf_static=static_transforms(T_base_camera, first.frame_id, base))
    assert episode.result is not None
    return count, episode.result
