"""Closed-loop settings: sections [replay], [tracking] and [memory] (`clear replay`,
`clear simulate`)."""

from __future__ import annotations

from dataclasses import dataclass

from clearcli.settings.fields import Section, param


@dataclass(frozen=True)
class ReplaySettings(Section):
    NAME = "replay"

    # False: plan every frame afresh, as the thesis did (pushes may be undone);
    # `--no-push-memory` sets it
    push_memory: bool = param(True)
    # a frame with an empty table ends the session
    stop_when_cleared: bool = param(True)


@dataclass(frozen=True)
class TrackingParams(Section):
    NAME = "tracking"

    # Weight of the size difference (m per m). Single-view boxes wobble by a centimetre
    # or two between frames, and grow by several when a neighbour in front is taken
    # away; half weight keeps such an object's id (on six simulated sessions with the
    # real segmenter: 2 new ids for known objects in 195 observations, 4 at weight 1).
    shape_weight: float = param(0.5, ge=0, le=10)
    # Largest cost still matched. Objects here are 3-15 cm apart in clutter and do not
    # move unless an action moves them; 7 cm leaves room for segmentation jitter and a
    # neighbour nudged by a push, without letting an object take its neighbour's id.
    gate_m: float = param(0.07, gt=0, le=1)
    # A pushed object may land up to this far from the push segment (turning, sliding).
    push_slack_m: float = param(0.04, ge=0, le=1)
    # Extra cost to keep the id of an object that was just grasped: only an object still
    # in place (a failed grasp) should take it.
    grasped_penalty_m: float = param(0.03, ge=0, le=1)
    # A track unseen for this many frames is forgotten (bounded state); until then an
    # object that reappears (briefly occluded or missed by segmentation) keeps its id.
    max_missing_frames: int = param(3, ge=0, le=1000)
    # A push counts as done when the object moved along the push direction by at least
    # this fraction of the push length (real pushes stop short at contacts).
    push_done_fraction: float = param(0.5, gt=0, le=1)
    # Second chance for what the first pass leaves: an object that moved although no
    # action was expected to move it (shoved by a neighbour's push, or a recorded action
    # other than the replayed plan's) keeps its id when it is within this distance and
    # its size matches within `rematch_shape_m`; a push is ~5-15 cm here.
    rematch_distance_m: float = param(0.15, ge=0, le=2)
    rematch_shape_m: float = param(0.015, ge=0, le=1)


@dataclass(frozen=True)
class MemoryParams(Section):
    NAME = "memory"

    # Pushes remembered per object: the last one is what a loop undoes; three also catch
    # a square dance (push, sideways, back, sideways back).
    per_object: int = param(3, ge=1, le=100)
    # Objects remembered at most (bounded state over a long log); the oldest go first.
    max_objects: int = param(64, ge=1, le=10000)
    # Pushes older than this many frames are forgotten: by then the scene has changed.
    horizon_frames: int = param(30, ge=1, le=100000)
    # A push undoes a remembered one when its direction is within this angle of the
    # reverse: push directions come from PCA and wobble between frames, and a push
    # 45 degrees off the reverse still brings the object mostly back.
    reverse_angle_deg: float = param(60.0, ge=0, le=180)
    # Added cost per remembered push a candidate would undo. Costs without memory are 1
    # per action (up to ~150 with the clearance cost), so a whole plan of other actions
    # for a cluttered table stays cheaper than one undoing push.
    reverse_penalty: int = param(200, ge=0, le=100000)
