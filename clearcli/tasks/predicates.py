"""`predicates`: object models, grasp and push poses and the symbolic facts of a frame."""

from __future__ import annotations

from dataclasses import dataclass

from clearcli import pipeline
from clearcli.files import atomic_output, atomic_path
from clearcli.planning.payload import predicates_payload
from clearcli.planning.pddl import write_problem
from clearcli.planning.versions import PREDICATES_SCHEMA, PREDICATES_VERSION
from clearcli.render.predicates_png import render_predicates_png
from clearcli.settings import Settings
from clearcli.tasks.base import NO_OUTPUTS, Outcome, Outputs, Source

SCHEMA, VERSION = PREDICATES_SCHEMA, PREDICATES_VERSION  # the planner's (clearcli/planning/versions.py)
OUTPUTS = ("problem", "png")


@dataclass(frozen=True)
class Request:
    settings: Settings
    ground_truth: bool = False  # the frame's own 'label' field instead of segmentation
    outputs: Outputs = NO_OUTPUTS
    keep: bool = False  # the outcome keeps the frame, the segmentation and the state (the Python API)


def run(request: Request, source: Source) -> Outcome:
    frame = pipeline.read(source.path, source.topic, source.index, request.settings, source.color)
    if request.ground_truth:
        seg = pipeline.truth_segmentation(frame, source.path)
    else:
        seg = pipeline.segmented(frame, request.settings)
    state = pipeline.stated(frame, seg, request.settings)
    problem = request.outputs.get("problem")
    if problem is not None:
        text = write_problem(state)
        with atomic_output(problem, "w") as handle:
            handle.write(text)
    png = request.outputs.get("png")
    if png is not None:
        with atomic_path(png) as tmp:
            render_predicates_png(state, tmp, title=str(source.path))
    payload = predicates_payload(state)
    kept = {"frame": frame, "segmentation": seg, "state": state} if request.keep else {}
    return Outcome(SCHEMA, VERSION, payload, 0, request.outputs.all(), kept)
