"""The unseen-object segmentation literature's metrics: Overlap and Boundary precision,
recall and F-measure, and the share of objects found with F >= 0.75.

These are what the OSD and OCID results are reported in (Richtsfeld et al. 2012's OSD;
Suchi et al. 2019's OCID; Xie et al., "Unseen Object Instance Segmentation for Robotic
Environments", 2020/2021, whose evaluation code defined the form most papers use), so a
user can put `clear` in one table beside learned methods. Definitions, over the objects
of both label sets (our object ids: table and unlabelled points are background):

- For true object i and predicted object j: precision P_ij = |i ∩ j| / |j|, recall
  R_ij = |i ∩ j| / |i|, F_ij = 2 P R / (P + R) (0 when they do not meet).
- Each true object is matched to at most one predicted object, maximising the summed
  F (Hungarian).
- **Overlap**: P = Σ_matched |i ∩ j| / Σ_j |j| (all predicted object points), R =
  Σ_matched |i ∩ j| / Σ_i |i| (all true object points), F = 2PR / (P + R). Points, so it
  is defined for unorganized clouds too.
- **Boundary** (organized frames only: it needs the image grid): an object's boundary is
  its pixels with a 4-neighbour outside it; a boundary pixel of j counts for precision
  when a boundary pixel of its matched i lies within a disc of radius
  ceil(0.003 × image diagonal) pixels (3 px at 640 × 480, the DAVIS tolerance), and the
  other way round for recall: P = Σ_matched (j's boundary near i's) / Σ_j |boundary of
  j|, R = Σ_matched (i's boundary near j's) / Σ_i |boundary of i|, F as above.
- **objects_f75**: the share of true objects whose match has F_ij >= 0.75.

Both sides without objects: every value 1; one side without: 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from clearcli.evaluate.segmentation import overlaps
from clearcli.render.camera import mask_edge

BOUNDARY_TOLERANCE = 0.003  # of the image diagonal (DAVIS, and the OSD/OCID evaluations)
DETECTED_F = 0.75


@dataclass(frozen=True)
class OsdScore:
    overlap_precision: float
    overlap_recall: float
    overlap_f: float
    boundary_precision: float | None  # None: not an organized frame
    boundary_recall: float | None
    boundary_f: float | None
    objects_f75: float

    def as_dict(self) -> dict[str, float | None]:
        def r(v: float | None) -> float | None:
            return None if v is None else round(float(v), 6)

        return {k: r(getattr(self, k)) for k in OSD_KEYS}


# The metrics' names, in the order of the JSON documents and the CSV columns.
OSD_KEYS = tuple(f.name for f in fields(OsdScore))


def _f(p: float, r: float) -> float:
    return 0.0 if p + r <= 0 else 2 * p * r / (p + r)


def _near(boundary: np.ndarray, radius: int) -> np.ndarray:
    """Pixels within ``radius`` (a disc) of the boundary pixels."""
    from scipy.ndimage import binary_dilation

    y, x = np.ogrid[-radius : radius + 1, -radius : radius + 1]
    return binary_dilation(boundary, structure=(x * x + y * y) <= radius * radius)


def osd_metrics(pred_labels: np.ndarray, true_labels: np.ndarray, shape: tuple[int, int] | None = None) -> OsdScore:
    """The metrics of the module doc for per-point labels of one frame (our convention,
    mOSD's too); ``shape`` (height, width) when the frame is organized, for Boundary."""
    from scipy.optimize import linear_sum_assignment

    ov = overlaps(pred_labels, true_labels)
    pred, true = ov.pred, ov.true
    organized = shape is not None and shape[0] > 1 and shape[0] * shape[1] == pred.size
    inter, p_size, t_size = ov.shared, ov.pred_size, ov.true_size  # [P, T], (P,), (T,)
    n_pred, n_true = inter.shape
    if n_pred == 0 or n_true == 0:
        v = 1.0 if n_pred == n_true else 0.0
        b = v if organized else None
        return OsdScore(v, v, v, b, b, b, v if n_true == 0 else 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        prec = inter / p_size[:, None]
        rec = inter / t_size[None, :]
        f = np.where(inter > 0, 2 * prec * rec / (prec + rec), 0.0)
    rows, cols = linear_sum_assignment(f, maximize=True)  # rows: predicted, cols: true
    matched = f[rows, cols] > 0
    rows, cols = rows[matched], cols[matched]
    tp = float(inter[rows, cols].sum())
    op, orec = tp / float(p_size.sum()), tp / float(t_size.sum())
    objects_f75 = float((f[rows, cols] >= DETECTED_F).sum()) / n_true
    bp = brec = bf = None
    if organized:
        assert shape is not None
        h, w = shape
        radius = max(1, math.ceil(BOUNDARY_TOLERANCE * math.hypot(h, w)))
        pred_grid, true_grid = pred.reshape(h, w), true.reshape(h, w)
        p_obj, t_obj = ov.pred_ids, ov.true_ids
        p_edges = {int(j): mask_edge(pred_grid == p_obj[j]) for j in range(n_pred)}
        t_edges = {int(i): mask_edge(true_grid == t_obj[i]) for i in range(n_true)}
        p_total = sum(int(e.sum()) for e in p_edges.values())
        t_total = sum(int(e.sum()) for e in t_edges.values())
        hit_p = hit_t = 0
        for j, i in zip(rows, cols):
            pe, te = p_edges[int(j)], t_edges[int(i)]
            # only the pair's box (grown by the tolerance) can hold hits: dilate that, not the image
            ys, xs = np.nonzero(pe | te)
            y0, y1 = max(int(ys.min()) - radius, 0), min(int(ys.max()) + radius + 1, h)
            x0, x1 = max(int(xs.min()) - radius, 0), min(int(xs.max()) + radius + 1, w)
            pe, te = pe[y0:y1, x0:x1], te[y0:y1, x0:x1]
            hit_p += int((pe & _near(te, radius)).sum())
            hit_t += int((te & _near(pe, radius)).sum())
        bp, brec = hit_p / max(p_total, 1), hit_t / max(t_total, 1)
        bf = _f(bp, brec)
    return OsdScore(op, orec, _f(op, orec), bp, brec, bf, objects_f75)
