"""`clear predicates FRAME`: the symbolic state of a frame; `clear domain`: the PDDL domain.

--json prints one document, schema ``clear.predicates`` (version in the envelope):

    {"schema": "clear.predicates", "version": 2,   # 1: no grasp_kinds / not_offered
     "source": str,                      # the frame's file (and topic/frame for MCAP)
     "frame": "sensor (optical)",        # every vector/pose below is in the sensor frame, m
     "table": {"normal": [3], "offset": float, "polygon": [[3], ...]},
     "objects": [{
        "name": "o0",                    # o0..oN-1 by position (see write_problem)
        "segment_index": int,            # index into the segmentation's objects
        "centroid": [3], "extents_m": [3], # extents along principal_axes rows
        "principal_axes": [[3],[3],[3]], # rows: 1st, 2nd direction on the table, normal
        "height_m": float, "grasp_width_m": float,
        "directions": {"dir1": [3], ...},  # unit push directions (compare by vector)
        "grasp_poses": [[4x4], ...],     # T_camera_gripper: the grasp's two half-turns, then the IK fallbacks (other yaw, off-centre)
        "push": {"dir1": {"length_m": float, "start_poses": [[4x4], [4x4]]}, ...},
        "grasp_kinds": {                 # the grasp kinds beyond the pinch offered for it
          "rim": {"center": [3], "radius_m", "height_m", "wall_m", "inside_depth_m",
                  "opening_m", "grasp_poses": [[4x4], ...]},
          "slide": {"direction": [3] (unit), "slide_m", "overhang_m", "thickness_m",
                    "tilt_deg" (the pinch's approach below the horizontal: 45, or as
                    steep as the opening allows a thicker slab, at least 20),
                    "grasp_poses": [[4x4]] (the pinch at the edge, after the slide)}},
        "not_offered": {"rim": why, "slide": why}}, ...],
     "facts": ["(on o1 o0)", ...],       # PDDL atoms, sorted; with the kinds' facts
                                         # (rim_graspable o), (block_rim x o), (slidable o),
                                         # (block_slide x o)
     "skipped": [{"segment_index": int, "reason": str}, ...],
     "push_costs": {"o0 dir1": int, ...}, # only with [predicates] clearance_cost
     "timings_s": {"models": float, ...}}
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Any

import typer

from clearcli.commands import options as bo
from clearcli.commands.common import check_output_path, print_json, stderr, stdout
from clearcli.errors import InputError
from clearcli.settings import kinds as grasp_kinds
from clearcli.tasks.base import Outputs, Source


def print_state(doc: Mapping[str, Any]) -> None:
    """Rich tables: the objects, then the facts grouped by kind."""
    from rich.table import Table  # noqa: PLC0415  (~6 ms: not for `clear --help`)

    t = Table(title=f"objects ({doc['source']})" if doc["source"] else "objects")
    for col in ("name", "segment", "centroid (m)", "size (m)", "height (m)", "grasp width (m)"):
        t.add_column(col)
    for o in doc["objects"]:
        c, e = o["centroid"], o["extents_m"]
        t.add_row(
            o["name"],
            str(o["segment_index"]),
            f"{c[0]:+.3f} {c[1]:+.3f} {c[2]:+.3f}",
            f"{e[0]:.3f} x {e[1]:.3f}",
            f"{o['height_m']:.3f}",
            f"{o['grasp_width_m']:.3f}",
        )
    stdout.print(t)
    kinds = (
        "on",
        "block_grasp",
        "block_dir",
        "ungraspable",
        "push_off_table",
        "rim_graspable",
        "block_rim",
        "slidable",
        "block_slide",
    )
    f = Table(title=f"facts ({len(doc['facts'])})")
    f.add_column("predicate")
    f.add_column("n", justify="right")
    f.add_column("atoms")
    for kind in kinds:
        atoms = sorted(x for x in doc["facts"] if x.startswith(f"({kind} ") or x == f"({kind})")
        f.add_row(kind, str(len(atoms)), " ".join(atoms) if atoms else "-")
    stdout.print(f)
    # left-out segments were already reported on stderr by the stage's logger warning
    total = doc["timings_s"].get("total")
    if total is not None:
        stderr.print(f"predicates: {1000 * total:.1f} ms", markup=False)


@bo.batch_options(("problem", "png"))
def predicates_cmd(
    inputs: bo.Inputs,
    output: Annotated[Path | None, typer.Option("-o", "--output", help="Write the PDDL problem to this file.")] = None,
    json_out: Annotated[
        bool, typer.Option("--json", help="Machine-readable output (schema clear.predicates).")
    ] = False,
    png: Annotated[
        Path | None, typer.Option("--png", help="Draw the top view with hulls, pushes, grasps, blocks.")
    ] = None,
    settings: bo.SettingsFile = None,
    sets: bo.Set = None,
    robot: bo.Robot = None,
    force: bo.Force = False,
    topic: bo.Topic = None,
    frame_index: bo.FrameIndex = 0,
    ground_truth: Annotated[
        bool,
        typer.Option(
            "--ground-truth",
            help="Use the frame's 'label' field (mOSD ground truth) instead of running segmentation.",
        ),
    ] = False,
    intrinsics: bo.Intrinsics = None,
    color: bo.Color = None,
    depth_scale: bo.DepthScale = None,
    batch: bo.Batch = bo.Batch(),
) -> None:
    """Objects and symbolic facts of FRAME (on, block_grasp, block_dir, ungraspable,
    push_off_table): runs segmentation, models each object, computes the predicates; -o
    writes the PDDL problem for the domain `clear domain` prints."""
    from clearcli.tasks import predicates as task  # noqa: PLC0415  (the task, ~0.7 s: not for `clear --help`)
    from clearcli.tasks import sources  # noqa: PLC0415  (~170 ms: not for `clear --help`)

    cfg = bo.with_images(bo.resolve_settings(settings, sets, robot=robot), intrinsics, depth_scale)
    if batch.wanted(inputs):
        bo.no_color_in_batch(color)
        bo.single_only(**{"-o": output, "--png": png})
        request = task.Request(cfg, ground_truth=ground_truth)
        raise typer.Exit(
            batch.run(
                "predicates",
                inputs,
                request,
                frame=frame_index,
                topic=topic,
                force=force,
                json_out=json_out,
                reads=(settings,),
            )
        )
    frame = inputs[0]
    for out in (output, png):
        if out is not None:
            check_output_path(out, force, sources.files_read(frame, cfg, color, also=(settings,)))
    if output is not None and png is not None and Path(output).resolve() == Path(png).resolve():
        raise InputError(f"{output}: -o and --png name the same file")
    request = task.Request(cfg, ground_truth=ground_truth, outputs=Outputs.of(problem=output, png=png))
    outcome = task.run(request, Source(str(frame), frame_index, topic, color=str(color) if color else None))
    if json_out:
        print_json(outcome.schema, outcome.version, outcome.payload, cfg, "predicates")
    else:
        print_state(outcome.payload)


def domain_cmd(
    clearance_cost: Annotated[
        bool,
        typer.Option("--clearance-cost", help="The variant with per-push costs (push-cost ?o ?d)."),
    ] = False,
    grasps: Annotated[
        str,
        typer.Option(
            "--grasps",
            help=f"Grasp kinds whose actions it has: {grasp_kinds.help_text()}; "
            f"{grasp_kinds.REQUIRED_KINDS[0]} is the thesis's grasp (pddl/domain.pddl).",
            metavar="KINDS",
        ),
    ] = grasp_kinds.default_kinds(),
) -> None:
    """Print the PDDL domain (types obj/direction; actions grasp, push, and one per other
    grasp kind, grasp_rim and slide_grasp among them, unless --grasps leaves them out)."""
    from clearcli.tasks.domain import domain_text  # noqa: PLC0415  (the task, ~260 ms: not for `clear --help`)

    typer.echo(domain_text(clearance_costs=clearance_cost, grasps=grasps), nl=False)
