"""`clear segment`: the table and the objects on it.

JSON (`--json`), envelope {"schema": "clear.segmentation", "version": 3, ...} (version 1
had no ``rim``/``rim_why`` per object and no ``table.edges``; version 2 no ``support``
and no ``excluded``):

    source        str     the file (and frame/topic) read
    frame_id      str     sensor frame name ("" when unknown)
    stamp_s       float   time stamp (0.0 when unknown)
    n_points      int     points in the frame, NaN rows included
    table         {normal: [3] unit, pointing up (towards the camera side),
                   offset: float d of n . p + d = 0 (m),
                   polygon: [[x, y, z], ...] convex hull on the plane, in order,
                   n_points: int table inlier points,
                   planes: [{normal: [3], offset: float, area_m2: float (its largest
                             connected piece), standing_points: int (points standing
                             on it inside its hull, minus those below it), chosen: bool,
                             why: str}] every plane RANSAC found, the chosen one first
                             (README "Which plane is the table"),
                   beyond_edge_m2: float area (m^2) the hull lost when pieces of the
                             plane seen beyond the table's edge were dropped (0: none),
                   edges: [{start: [3], end: [3], seen: bool, why: str}] the polygon's
                             sides (nearly straight runs joined) and whether the camera
                             sees the table end there ("a drop beyond it"), or why not
                             ("the view ends there", "the table goes on beyond it",
                             "something stands beyond it", ...): a flat object is slid
                             only to a seen side (clearcli/perception/openings.py)}
    support       {chosen: null | {normal: [3], offset: float, area_m2: float,
                   standing_points: int}, why: str (why the objects stand on it: the
                   most points standing on it, a mat just above the table, a raised
                   surface held up from the floor), rejected: [{normal, offset, area_m2,
                   standing_points, why}] every other candidate plane and why not}
                   (clearcli/perception/support.py)
    excluded      [{points: int, centroid: [3], reason: str}] segments above the
                   support that are no objects: they reach in from beyond its outline
                   (an arm, a hand, a cable), are one with furniture beyond its edge
                   (a desk or shelf behind), hang above it, or stand on such a thing
                   (clearcli/perception/exclude.py); an empty object list with these
                   is still exit 0
    objects       [{id: int (k, from 0), label: int (10 (k + 1), as in -o),
                    n_points: int, centroid: [3],
                    obb: {center: [3], axes: [[3] x 3] rows, the third the table normal,
                          extents: [3] full side lengths (m) along the axes},
                    principal_axes: [[3] x 3] rows, largest variance first,
                    rim: null | {center: [3] the rim circle's centre, radius_m: to the
                          middle of the wall, height_m: above the table, wall_m: its
                          thickness where seen, inside_depth_m: how deep the inside is
                          seen below the rim, arc_deg: how much of the circle is seen}
                          (an open container: a bowl, a mug, a cup),
                    rim_why: str why it has no rim ("" when it has one)}]
    color         {used: bool, note: str} whether colour was read (by the flat-object
                   search, by the containers' walls, by the supervoxels when
                   color_importance > 0), and else why
                   not: no colour, a colour image of another size, all black, all
                   saturated (segmentation then runs on geometry alone)
    timings_s     {stage: seconds} (filter, table, supervoxels, lccp, merge,
                   flat, objects, total, and each refinement by name)

All coordinates in metres in the sensor frame of the input.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from clearcli.commands import options as bo
from clearcli.commands.common import check_output_path, print_json, print_table, stderr, stdout
from clearcli.errors import InputError
from clearcli.tasks.base import Outputs, Source


@bo.batch_options(("labels", "png"))
def segment_cmd(
    inputs: bo.Inputs,
    json_out: Annotated[bool, typer.Option("--json", help="Machine-readable output (schema in the docs).")] = False,
    labels_out: Annotated[
        Path | None, typer.Option("-o", "--output", help="Write a PCD of the frame with a `label` field.")
    ] = None,
    png: Annotated[Path | None, typer.Option("--png", help="Write a picture of the segmentation.")] = None,
    settings_file: bo.SettingsFile = None,
    sets: bo.Set = None,
    force: bo.Force = False,
    topic: bo.Topic = None,
    frame_index: bo.FrameIndex = 0,
    voxel_m: Annotated[float | None, typer.Option("--voxel-m", help="Supervoxel voxel size (m).")] = None,
    seed_m: Annotated[float | None, typer.Option("--seed-m", help="Supervoxel seed spacing (m).")] = None,
    concavity_deg: Annotated[
        float | None, typer.Option("--concavity-deg", help="LCCP concavity tolerance (degrees).")
    ] = None,
    plane_distance_m: Annotated[
        float | None, typer.Option("--plane-distance-m", help="RANSAC table inlier distance (m).")
    ] = None,
    min_object_area_m2: Annotated[
        float | None, typer.Option("--min-object-area-m2", help="Smallest object kept (visible area, m^2).")
    ] = None,
    outlier_method: Annotated[
        str | None, typer.Option("--outlier-method", help="depth_radius, statistical or none.")
    ] = None,
    occlusion_merge: Annotated[
        bool | None,
        typer.Option("--occlusion-merge/--no-occlusion-merge", help="Join pieces of an object cut by a nearer one."),
    ] = None,
    intrinsics: bo.Intrinsics = None,
    color: bo.Color = None,
    depth_scale: bo.DepthScale = None,
    batch: bo.Batch = bo.Batch(),
) -> None:
    """Find the table and segment the objects on it (thesis 4.1): a summary table, or
    --json; -o writes the labels (0 none, 1 table, 10(k+1) object k) as a PCD."""
    from clearcli.tasks import segment as task  # noqa: PLC0415  (the task, ~1.1 s: not for `clear --help`)
    from clearcli.tasks import sources  # noqa: PLC0415  (~170 ms: not for `clear --help`)

    settings = bo.with_images(
        bo.resolve_settings(
            settings_file,
            sets,
            "segment",
            voxel_m=voxel_m,
            seed_m=seed_m,
            concavity_tolerance_deg=concavity_deg,
            plane_distance_m=plane_distance_m,
            min_object_area_m2=min_object_area_m2,
            outlier_method=outlier_method,
            occlusion_merge=occlusion_merge,
        ),
        intrinsics,
        depth_scale,
    )
    if batch.wanted(inputs):
        bo.no_color_in_batch(color)
        bo.single_only(**{"-o": labels_out, "--png": png})
        request = task.Request(settings)
        raise typer.Exit(
            batch.run(
                "segment",
                inputs,
                request,
                frame=frame_index,
                topic=topic,
                force=force,
                json_out=json_out,
                reads=(settings_file,),
            )
        )
    frame_path = inputs[0]
    for out in (labels_out, png):
        if out is not None:
            check_output_path(out, force, sources.files_read(frame_path, settings, color, also=(settings_file,)))
    if labels_out is not None and png is not None and Path(labels_out).resolve() == Path(png).resolve():
        raise InputError(f"{labels_out}: -o and --png name the same file; give each its own")
    outcome = task.run(
        task.Request(settings, Outputs.of(labels=labels_out, png=png)),
        Source(str(frame_path), frame_index, topic, color=str(color) if color else None),
    )
    doc = outcome.payload
    if json_out:
        print_json(outcome.schema, outcome.version, doc, settings, "segment")
        return
    n = doc["table"]["normal"]
    stdout.print(
        f"[bold]{doc['source']}[/bold]: table normal ({n[0]:.3f}, {n[1]:.3f}, {n[2]:.3f}), "
        f"camera {doc['table']['offset']:.3f} m above it, {doc['table']['n_points']} table points, "
        f"{len(doc['objects'])} object(s)" + (f", {len(doc['excluded'])} thing(s) excluded" if doc["excluded"] else "")
    )
    for thing in doc["excluded"]:
        stdout.print(f"  excluded ({thing['points']} points): {thing['reason']}")
    if doc["objects"]:
        rows = []
        for obj in doc["objects"]:
            c, e = obj["centroid"], obj["obb"]["extents"]
            rows.append(
                [
                    str(obj["id"]),
                    str(obj["label"]),
                    str(obj["n_points"]),
                    f"{c[0]:+.3f} {c[1]:+.3f} {c[2]:+.3f}",
                    f"{e[0]:.3f} x {e[1]:.3f} x {e[2]:.3f}",
                ]
            )
        # rich's table; on a pipe or a file drawn without importing rich (clearcli/console.py)
        print_table(stdout, ["id", "label", "points", "centroid (m)", "box extents (m)"], rows)
    times = ", ".join(f"{k} {v * 1000:.0f} ms" for k, v in doc["timings_s"].items())
    stdout.print(f"timings: {times}")
    for out, what in ((labels_out, "labels"), (png, "picture")):
        if out is not None:
            stderr.print(f"wrote {what} to {out}")
