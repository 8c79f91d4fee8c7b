"""`segment`: the table and one point set per object, optionally a labels PCD and a picture."""

from __future__ import annotations

from dataclasses import dataclass

from clearcli import pipeline
from clearcli.files import atomic_path
from clearcli.io.pcd import write_pcd
from clearcli.perception.payload import SCHEMA as SCHEMA  # the schema's one home
from clearcli.perception.payload import VERSION as VERSION
from clearcli.perception.payload import segmentation_payload
from clearcli.render.segment_png import render_segmentation
from clearcli.settings import Settings
from clearcli.tasks.base import NO_OUTPUTS, Outcome, Outputs, Source

OUTPUTS = ("labels", "png")


@dataclass(frozen=True)
class Request:
    settings: Settings
    outputs: Outputs = NO_OUTPUTS
    keep: bool = False  # the outcome keeps the frame and the segmentation (the Python API)


def run(request: Request, source: Source) -> Outcome:
    frame = pipeline.read(source.path, source.topic, source.index, request.settings, source.color)
    seg = pipeline.segmented(frame, request.settings)
    labels = request.outputs.get("labels")
    if labels is not None:
        write_pcd(labels, frame, seg.labels())
    png = request.outputs.get("png")
    if png is not None:
        with atomic_path(png) as tmp:
            render_segmentation(tmp, frame, seg)
    kept = {"frame": frame, "segmentation": seg} if request.keep else {}
    return Outcome(SCHEMA, VERSION, segmentation_payload(seg), 0, request.outputs.all(), kept)
