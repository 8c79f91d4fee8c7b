"""`clear predicates FRAME`: the symbolic state of a frame; `clear domain`: the PDDL domain.

--json prints one document, schema ``clear.predicates`` (version in the envelope):

    {"schema": "clear.predicates", "version": 1,
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
        "push": {"dir1": {"length_m": float, "start_poses": [[4x4], [4x4]]}, ...}}, ...],
     "facts": ["(on o1 o0)", ...],       # PDDL atoms, sorted
     "skipped": [{"segment_index": int, "reason": str}, ...],
     "push_costs": {"o0 dir1": int, ...}, # only with [predicates] clearance_cost
     "timings_s": {"models": float, ...}}
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Optional

import typer

from clearcli.commands import batchopts as bo
from clearcli.commands.common import stderr, stdout

PredicateOutputs = bo.outputs_option(("problem", "png"))


def _matrix(a: Any) -> list:
    import numpy as np

    return np.round(np.asarray(a, dtype=float), 6).tolist()


def predicates_payload(state: Any) -> dict[str, Any]:
    from clearcli.planning.pddl import fact_to_pddl

    objects = []
    for o in state.objects:
        objects.append(
            {
                "name": o.name,
                "segment_index": int(o.segment_index),
                "centroid": _matrix(o.centroid),
                "extents_m": _matrix(o.extents_m),
                "principal_axes": _matrix(o.principal_axes),
                "height_m": round(float(o.height_m), 6),
                "grasp_width_m": round(float(o.grasp_width_m), 6),
                "directions": {d: _matrix(p.unit_vector) for d, p in o.pushes.items()},
                "grasp_poses": [_matrix(c[1]) for c in o.grasp_candidates],
                "push": {
                    d: {"length_m": round(float(p.push_length_m), 6), "start_poses": [_matrix(c[1]) for c in p.candidates]}
                    for d, p in o.pushes.items()
                },
            }
        )
    return {
        "source": state.source,
        "frame": "sensor (optical)",
        "table": {
            "normal": _matrix(state.table.normal),
            "offset": round(float(state.table.offset), 6),
            "polygon": _matrix(state.table_polygon),
        },
        "objects": objects,
        "facts": sorted(fact_to_pddl(f) for f in state.facts),
        "skipped": [{"segment_index": int(i), "reason": r} for i, r in state.skipped],
        "push_costs": {f"{o} {d}": int(c) for (o, d), c in sorted(state.push_costs.items())},
        "timings_s": {k: round(float(v), 6) for k, v in state.timings_s.items()},
    }


def print_state(state: Any) -> None:
    """Rich tables: the objects, then the facts grouped by kind."""
    from rich.table import Table

    from clearcli.planning.pddl import fact_to_pddl

    t = Table(title=f"objects ({state.source})" if state.source else "objects")
    for col in ("name", "segment", "centroid (m)", "size (m)", "height (m)", "grasp width (m)"):
        t.add_column(col)
    for o in state.objects:
        c, e = o.centroid, o.extents_m
        t.add_row(
            o.name,
            str(o.segment_index),
            f"{c[0]:+.3f} {c[1]:+.3f} {c[2]:+.3f}",
            f"{e[0]:.3f} x {e[1]:.3f}",
            f"{o.height_m:.3f}",
            f"{o.grasp_width_m:.3f}",
        )
    stdout.print(t)
    kinds = ("on", "block_grasp", "block_dir", "ungraspable", "push_off_table")
    f = Table(title=f"facts ({len(state.facts)})")
    f.add_column("predicate")
    f.add_column("n", justify="right")
    f.add_column("atoms")
    for kind in kinds:
        atoms = sorted(fact_to_pddl(x) for x in state.facts if x[0] == kind)
        f.add_row(kind, str(len(atoms)), " ".join(atoms) if atoms else "-")
    stdout.print(f)
    # left-out segments were already reported on stderr by the stage's logger warning
    total = state.timings_s.get("total")
    if total is not None:
        stderr.print(f"predicates: {1000 * total:.1f} ms", markup=False)


def predicates_cmd(
    inputs: bo.Inputs,
    output: Annotated[
        Optional[Path], typer.Option("-o", "--output", help="Write the PDDL problem to this file.")
    ] = None,
    json_out: Annotated[bool, typer.Option("--json", help="Machine-readable output (schema clear.predicates).")] = False,
    png: Annotated[Optional[Path], typer.Option("--png", help="Draw the top view with hulls, pushes, grasps, blocks.")] = None,
    settings: Annotated[Optional[Path], typer.Option("--settings", help="TOML settings file (see `clear settings`).")] = None,
    force: Annotated[bool, typer.Option("--force", help="Overwrite existing output files.")] = False,
    topic: Annotated[Optional[str], typer.Option("--topic", help="MCAP topic with the point clouds.")] = None,
    frame_index: Annotated[int, typer.Option("--frame", help="Frame index in an MCAP log.", min=0)] = 0,
    ground_truth: Annotated[
        bool,
        typer.Option(
            "--ground-truth",
            help="Use the frame's 'label' field (mOSD ground truth) instead of running segmentation.",
        ),
    ] = False,
    every: bo.Every = None,
    out_dir: bo.OutDir = None,
    outputs_kinds: PredicateOutputs = None,
    resume: bo.Resume = False,
    jobs: bo.Jobs = None,
    ray: bo.Ray = None,
    fail_fast: bo.FailFast = False,
) -> None:
    """Objects and symbolic facts of FRAME (on, block_grasp, block_dir, ungraspable,
    push_off_table): runs segmentation, models each object, computes the predicates; -o
    writes the PDDL problem for the domain `clear domain` prints."""
    from clearcli.commands.common import atomic_output, atomic_path, check_output_path
    from clearcli.errors import InputError
    from clearcli.io.read import read_frame
    from clearcli.planning.pddl import write_problem
    from clearcli.predicates.state_builder import compute_state
    from clearcli.settings import load_settings


    if bo.is_batch(inputs, every, out_dir, ray):
        from clearcli.batch.run import run_command_batch

        bo.single_only(**{"-o": output, "--png": png})
        raise typer.Exit(run_command_batch(
            "predicates", inputs,
            {"settings": None if settings is None else str(settings), "ground_truth": ground_truth},
            outputs=outputs_kinds, jobs=jobs, frame=frame_index, every=every, topic=topic, out_dir=out_dir,
            force=force, resume=resume, ray=ray, fail_fast=fail_fast, json_out=json_out,
        ))
    frame = inputs[0]
    cfg = load_settings(settings)
    for out in (output, png):
        if out is not None:
            check_output_path(out, force, (frame,))
    if output is not None and png is not None and Path(output).resolve() == Path(png).resolve():
        raise InputError(f"{output}: -o and --png name the same file")
    frm = read_frame(frame, topic, frame_index)
    if ground_truth:
        seg = ground_truth_segmentation(frm, frame)
    else:
        from clearcli.perception.segment import segment

        seg = segment(frm, cfg.segment)
    state = compute_state(frm, seg, cfg)
    if output is not None:
        text = write_problem(state)
        with atomic_output(output, "w") as handle:
            handle.write(text)
    if png is not None:
        from clearcli.render.predicates_png import render_predicates_png

        with atomic_path(png) as tmp:
            render_predicates_png(state, tmp, title=str(frame))
    if json_out:
        from clearcli.commands.common import print_json

        print_json("predicates", predicates_payload(state))
    else:
        print_state(state)


def ground_truth_segmentation(frm: Any, path: Path) -> Any:
    """The segmentation the frame's own 'label' field gives (mOSD ground truth)."""
    from clearcli.errors import InputError
    from clearcli.predicates.synthetic import segmentation_from_labels

    if "label" not in frm.fields:
        raise InputError(f"{path}: --ground-truth needs a 'label' field, and this frame has none")
    return segmentation_from_labels(frm)


def domain_cmd(
    clearance_cost: Annotated[
        bool,
        typer.Option("--clearance-cost", help="The variant with per-push costs (push-cost ?o ?d)."),
    ] = False,
) -> None:
    """Print the PDDL domain (types obj/direction; actions grasp and push)."""
    from clearcli.planning.pddl import domain_text

    typer.echo(domain_text(clearance_costs=clearance_cost), nl=False)
