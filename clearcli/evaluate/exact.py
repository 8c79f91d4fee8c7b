"""Objects "exactly right", and what went wrong with the others, per frame.

The measure a user feels: an object is **right** when one predicted segment covers it
(IoU >= 0.5 with it), that segment holds no other labelled object, and no other segment
has a tenth of it (a mug's handle apart from its mug is a second object to a planner).
Each other labelled object is exactly one of:

- **merged**: a segment holds it together with another labelled object ("holds": has at
  least half of that object's points);
- **split**: not merged, and two or more segments each cover at least a tenth of it;
- **missed**: neither (nothing, or only scraps, of it found).

A predicted segment is **spurious** when at most half of its points belong to labelled
objects (a chair, the table's edge, a shadow taken for an object).

Labels are per point, our convention (object = label // 10 for labels >= 10; the table
and unlabelled points are background), on both sides.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clearcli.evaluate.segmentation import overlaps

RIGHT_IOU = 0.5
HOLDS = 0.5  # a segment holds an object when it has at least this share of its points
PIECE = 0.1  # a piece of a split object: at least this share of its points
SPURIOUS = 0.5  # a segment is spurious when at most this share of it is labelled objects


@dataclass(frozen=True)
class ExactReport:
    n_objects: int
    right: int
    merged: int
    split: int
    missed: int
    spurious: int
    verdicts: tuple[str, ...]  # per labelled object, in id order: right | merged | split | missed

    def as_dict(self) -> dict[str, object]:
        return {
            "objects": self.n_objects,
            "right": self.right,
            "merged": self.merged,
            "split": self.split,
            "missed": self.missed,
            "spurious": self.spurious,
            "verdicts": list(self.verdicts),
        }


def exact_report(pred_labels: np.ndarray, true_labels: np.ndarray) -> ExactReport:
    """The verdict on every labelled object, and the spurious segments (module doc)."""
    ov = overlaps(pred_labels, true_labels)
    inter, seg_size, obj_size = ov.shared, ov.pred_size, ov.true_size  # [segments, objects]
    n_seg, n_obj = inter.shape
    if n_obj == 0:
        return ExactReport(0, 0, 0, 0, 0, n_seg, ())
    cover = inter / obj_size[None, :]  # share of each object in each segment
    iou = inter / np.maximum(seg_size[:, None] + obj_size[None, :] - inter, 1)
    holds = cover >= HOLDS
    n_held = holds.sum(axis=1)  # objects each segment holds
    verdicts = []
    for o in range(n_obj):
        candidates = np.nonzero(iou[:, o] >= RIGHT_IOU)[0]
        pieces = int((cover[:, o] >= PIECE).sum())
        if pieces == 1 and any(not (holds[s].sum() - holds[s, o]) for s in candidates):
            verdicts.append("right")
        elif np.any(holds[:, o] & (n_held >= 2)):
            verdicts.append("merged")
        elif int((cover[:, o] >= PIECE).sum()) >= 2:
            verdicts.append("split")
        else:
            verdicts.append("missed")
    labelled_share = inter.sum(axis=1) / np.maximum(seg_size, 1)
    spurious = int((labelled_share <= SPURIOUS).sum())
    return ExactReport(
        n_obj,
        verdicts.count("right"),
        verdicts.count("merged"),
        verdicts.count("split"),
        verdicts.count("missed"),
        spurious,
        tuple(verdicts),
    )
