"""`clear evaluate ...`: scores against ground truth.

`clear evaluate segmentation PRED TRUTH [--json]`; JSON envelope
{"schema": "clear.evaluate.segmentation", "version": 1, ...} with the fields of
`clearcli.evaluate.segmentation.SegmentationScore` (n_true, n_pred, true_positives,
precision, recall, f1, mean_best_iou, over_segmented, under_segmented, matched_iou,
true_ids, pred_ids) plus "pred" and "truth" (the paths).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

evaluate_app = typer.Typer(
    name="evaluate",
    help="Score results against ground truth.",
    no_args_is_help=True,
    add_completion=False,
    rich_markup_mode=None,
)


def _labels_of(path: Path, what: str) -> "object":
    from clearcli.errors import InputError
    from clearcli.io.read import read_frame

    frame = read_frame(path)
    if "label" not in frame.fields:
        raise InputError(f"{path}: the {what} has no `label` field (fields: {', '.join(frame.fields) or 'none'})")
    return frame.fields["label"]


@evaluate_app.command("segmentation")
def segmentation_cmd(
    pred: Annotated[Path, typer.Argument(help="Predicted labels: a PCD written by `clear segment -o`.")],
    truth: Annotated[Path, typer.Argument(help="Ground truth: an mOSD-labelled PCD of the same frame.")],
    json_out: Annotated[bool, typer.Option("--json", help="Machine-readable output.")] = False,
) -> None:
    """Object-level scores of a labelled segmentation against ground truth: one-to-one
    matching by IoU (Hungarian), precision/recall/F1 at IoU >= 0.5, mean best IoU,
    over- and under-segmentation counts."""
    import numpy as np

    from clearcli.commands.common import print_json, stdout
    from clearcli.errors import InputError
    from clearcli.evaluate.segmentation import score

    p = np.asarray(_labels_of(pred, "prediction")).ravel()
    t = np.asarray(_labels_of(truth, "ground truth")).ravel()
    if p.shape != t.shape:
        raise InputError(
            f"{pred}: {p.size} points but {truth} has {t.size}; both must be the same frame"
        )
    result = score(p, t)
    if json_out:
        print_json("evaluate.segmentation", {"pred": str(pred), "truth": str(truth), **result.as_dict()})
        return
    stdout.print(
        f"objects: {result.n_true} true, {result.n_pred} predicted, {result.true_positives} matched at IoU >= 0.5\n"
        f"precision {result.precision:.3f}  recall {result.recall:.3f}  F1 {result.f1:.3f}  "
        f"mean best IoU {result.mean_best_iou:.3f}\n"
        f"over-segmented true objects {result.over_segmented}, under-segmenting predictions {result.under_segmented}"
    )
