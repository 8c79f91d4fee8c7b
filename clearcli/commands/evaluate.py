"""`clear evaluate ...`: scores against ground truth.

`clear evaluate dataset INPUTS... [--pred DIR] [--groups FILE|mosd] [--json] [--csv F] [--png F]`:
each labelled frame segmented and scored against its own labels, on every core or on
Ray (clearcli/batch/run.py). With --json, one `clear.batch` line per frame whose
document is `clear.evaluate.frame` (source, name, group, n_true, n_pred,
true_positives, precision, recall, f1, mean_best_iou, over_segmented, under_segmented,
the OSD/OCID metrics overlap_precision, overlap_recall, overlap_f, boundary_precision,
boundary_recall, boundary_f (null for unorganized frames) and objects_f75 (definitions:
clearcli/evaluate/osd.py), exact: {objects, right, merged, split, missed, spurious,
verdicts: [per true object]} (clearcli/evaluate/exact.py), time_s), then the summary line with "evaluation": {"all":
{frames, mean_precision, mean_recall, mean_f1, mean_best_iou, mean_<each OSD metric>
(Boundary over organized frames; null when none), exact: {the counts summed},
over_segmented, under_segmented, median_time_s}, "groups": {name: the same}}.

`clear evaluate segmentation PRED TRUTH [--json]`; JSON envelope
{"schema": "clear.evaluate.segmentation", "version": 1, ...} with the fields of
`clearcli.evaluate.segmentation.SegmentationScore` (n_true, n_pred, true_positives,
precision, recall, f1, mean_best_iou, over_segmented, under_segmented, matched_iou,
true_ids, pred_ids), the OSD/OCID metrics as above, plus "pred" and "truth" (the paths).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from clearcli.commands import options as bo
from clearcli.commands.common import check_output_path, print_json, stdout
from clearcli.errors import InputError

evaluate_app = typer.Typer(
    name="evaluate",
    help="Score results against ground truth.",
    no_args_is_help=True,
    add_completion=False,
    rich_markup_mode=None,
)


@evaluate_app.command("segmentation")
def segmentation_cmd(
    pred: Annotated[Path, typer.Argument(help="Predicted labels: a PCD written by `clear segment -o`.")],
    truth: Annotated[Path, typer.Argument(help="Ground truth: an mOSD-labelled PCD of the same frame.")],
    json_out: Annotated[bool, typer.Option("--json", help="Machine-readable output.")] = False,
) -> None:
    """Object-level scores of a labelled segmentation against ground truth: one-to-one
    matching by IoU (Hungarian), precision/recall/F1 at IoU >= 0.5, mean best IoU,
    over- and under-segmentation counts."""
    from clearcli.tasks import evaluate as task  # noqa: PLC0415  (the task, ~1.1 s: not for `clear --help`)

    doc = task.score_files(pred, truth)
    if json_out:
        print_json("evaluate.segmentation", 1, doc, None, "evaluate")
        return
    stdout.print(
        f"objects: {doc['n_true']} true, {doc['n_pred']} predicted, {doc['true_positives']} matched at IoU >= 0.5\n"
        f"precision {doc['precision']:.3f}  recall {doc['recall']:.3f}  F1 {doc['f1']:.3f}  "
        f"mean best IoU {doc['mean_best_iou']:.3f}\n"
        f"over-segmented true objects {doc['over_segmented']}, under-segmenting predictions {doc['under_segmented']}\n"
        f"OSD/OCID: Overlap P/R/F {doc['overlap_precision']:.3f}/{doc['overlap_recall']:.3f}/{doc['overlap_f']:.3f}  "
        + (
            f"Boundary P/R/F {doc['boundary_precision']:.3f}/{doc['boundary_recall']:.3f}/{doc['boundary_f']:.3f}  "
            if doc["boundary_f"] is not None
            else "Boundary - (not an organized frame)  "
        )
        + f"objects with F >= 0.75: {doc['objects_f75']:.3f}"
    )


@evaluate_app.command("dataset")
@bo.batch_options(("labels",))
def dataset_cmd(
    inputs: Annotated[
        list[Path],
        typer.Argument(help="Labelled frames (mOSD `label` field): files, and folders to search for them."),
    ],
    pred: Annotated[
        Path | None,
        typer.Option(
            "--pred", help="Score the label files in this folder (as `--out-dir` names them) instead of segmenting."
        ),
    ] = None,
    groups: Annotated[
        str | None,
        typer.Option(
            "--groups", help="Per-group means: a TOML file of [groups] name = [patterns], or 'mosd' (shipped)."
        ),
    ] = None,
    json_out: Annotated[bool, typer.Option("--json", help="JSON lines: one per frame, then the summary.")] = False,
    csv_out: Annotated[Path | None, typer.Option("--csv", help="Write the per-frame table as CSV.")] = None,
    png: Annotated[Path | None, typer.Option("--png", help="Draw the per-frame F1 as a bar chart.")] = None,
    force: bo.Force = False,
    settings: bo.SettingsFile = None,
    sets: bo.Set = None,
    topic: bo.Topic = None,
    frame_index: bo.FrameIndex = 0,
    batch: bo.Batch = bo.Batch(),
) -> None:
    """Segment each labelled frame and score it against its own labels (or score the
    label files in --pred): a per-frame table (objects true/predicted, precision,
    recall, F1 at IoU >= 0.5, mean best IoU, over/under-segmentation, time), the means,
    and per-group means with --groups. Runs on every core, or on Ray, like every batch."""
    from clearcli.tasks import evaluate as task  # noqa: PLC0415  (the task, ~1.1 s: not for `clear --help`)

    cfg = bo.resolve_settings(settings, sets)

    # --groups stays the text given (the refusal names an input as given); check_output_path
    # reads any path (Path() and str() of each), though its annotation says Path
    read = (*inputs, *(p for p in (settings, groups) if p and Path(str(p)).is_file()))
    for out in (csv_out, png):
        if out is not None:
            check_output_path(out, force, read)  # type: ignore[arg-type]  # files.py's annotation: Path only
    group_map = {name: tuple(patterns) for name, patterns in task.load_groups(groups).items()}
    if pred is not None and not pred.is_dir():
        raise InputError(f"--pred {pred}: not a folder")

    def docs_of(lines: Any) -> list[dict[str, Any]]:
        return [ln["document"] for ln in lines if "document" in ln]

    def extra(lines: Any) -> dict[str, Any]:
        return {"evaluation": task.summarise(docs_of(lines), group_map)}

    def render(rows: Any, summary: Any) -> None:
        from rich.table import Table  # noqa: PLC0415  (~6 ms: not for `clear --help`)

        def num(v: Any) -> str:
            return "-" if v is None else f"{v:.3f}"

        table = Table(
            "frame", "group", "true", "pred", "P", "R", "F1", "IoU", "Ov F", "Bd F", "F>=.75", "over", "under", "ms"
        )
        for ln in rows:
            d = ln.get("document")
            if d is None:
                table.add_row(str(ln["source"]), *[""] * 12, ln["error"]["message"])
                continue
            table.add_row(
                Path(d["source"]).name,
                d.get("group") or "",
                str(d["n_true"]),
                str(d["n_pred"]),
                f"{d['precision']:.3f}",
                f"{d['recall']:.3f}",
                f"{d['f1']:.3f}",
                f"{d['mean_best_iou']:.3f}",
                num(d.get("overlap_f")),
                num(d.get("boundary_f")),
                num(d.get("objects_f75")),
                str(d["over_segmented"]),
                str(d["under_segmented"]),
                f"{1000 * d['time_s']:.0f}",
            )
        stdout.print(table)
        ev = summary["evaluation"]
        means = Table(
            "frames",
            "n",
            "mean F1",
            "mean IoU",
            "mean P",
            "mean R",
            "Overlap P/R/F",
            "Boundary P/R/F",
            "F>=.75",
            "over",
            "under",
            "median ms",
        )
        for label, m in [("all", ev["all"])] + list(ev.get("groups", {}).items()):
            if m["frames"]:
                means.add_row(
                    label,
                    str(m["frames"]),
                    f"{m['mean_f1']:.3f}",
                    f"{m['mean_best_iou']:.3f}",
                    f"{m['mean_precision']:.3f}",
                    f"{m['mean_recall']:.3f}",
                    "/".join(num(m.get(f"mean_overlap_{k}")) for k in ("precision", "recall", "f")),
                    "/".join(num(m.get(f"mean_boundary_{k}")) for k in ("precision", "recall", "f")),
                    num(m.get("mean_objects_f75")),
                    str(m["over_segmented"]),
                    str(m["under_segmented"]),
                    f"{1000 * m['median_time_s']:.0f}",
                )
        stdout.print(means)
        stdout.print(
            f"{summary['frames']} frames, {summary['failed']} failed; {summary['backend']}, {summary['wall_s']:.1f} s",
            markup=False,
            highlight=False,
        )

    collected: list[dict[str, Any]] = []
    code = batch.run(
        "evaluate",
        inputs,
        task.Request(cfg, pred=pred, groups=group_map),
        frame=frame_index,
        topic=topic,
        force=force,
        json_out=json_out,
        on_line=collected.append,
        extra_summary=extra,
        render=render,
        reads=(settings, groups if groups and Path(groups).is_file() else None),
    )
    docs = docs_of(collected)
    if csv_out is not None:
        task.write_csv(csv_out, docs)
    if png is not None:
        task.write_png(png, docs)
    raise typer.Exit(code)
