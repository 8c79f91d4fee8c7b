"""Only what stands on the support is an object (issue 37): the segments that do not are
set aside with the reason, for --json to list as ``excluded``.

- reaches in from beyond the support's outline: a robot arm, a hand, a cable. The prism
  ends at the support's hull (grown by ``hull_margin_m``); a segment that touches that
  side of the prism and goes on beyond it, above the support's plane, is part of
  something standing elsewhere. An object cut by the image's border does not go on.
- hangs above the support: its lowest point well above it (more than `_HANG_M` plus the
  range's noise) and the support seen beneath it (in at least `_SEEN_UNDER_SHARE` of the
  cells it covers, the camera sees the support's own points), so nothing it could stand
  on is hidden there: a shelf board, a lamp, the arm's gripper seen apart. Unless an
  object lies beneath its outline, reaching up to within `_HANG_M` of its bottom: it
  stands on that object where the contact is hidden (a box laid across two others).
- stands on something excluded: its bottom within `_TOUCH_M` of an excluded segment's
  points, and above the support (a box on the shelf board, on the arm).

A stacked object is not excluded: it stands on an object, and the support under it is
hidden by that object, not seen. Every threshold keeps a margin of millimetres or tens
of points, far from what rounding-sized changes of the points can move.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

_BORDER_M = 0.02  # a segment's points this near the prism's side touch it
_GOES_ON_M = 0.02  # points beyond the side within this of those continue the segment
_GOES_ON_MIN = 15  # at least this many such points
_HANG_M = 0.03
# an arm crosses the outline at least this high above the support (an object standing
# at a side the hull cuts reaches the side lower down)
_REACH_ABOVE_M = 0.10
_SEEN_UNDER_SHARE = 0.3
_CELL_M = 0.01
_TOUCH_M = 0.015


def _near_box(points: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The rows of ``points`` inside the box [lo, hi] (as many columns as ``lo``): only they
    can be within the box's margin of what it was grown around, so a nearest-neighbour
    search against them alone gives the same answer as against all the points."""
    return points[((points[:, : lo.size] >= lo) & (points[:, : lo.size] <= hi)).all(axis=1)]


def _rests_on_another(
    k: int, p: np.ndarray, height: Callable[[np.ndarray], np.ndarray], low: float, objects: list[np.ndarray]
) -> bool:
    """Does the bottom of object ``k`` touch another object (it leans on it, stands on it)?"""
    from scipy.spatial import cKDTree

    bottom = p[height(p) <= low + _TOUCH_M]
    if not bottom.shape[0]:
        return False
    lo, hi = bottom.min(axis=0) - _TOUCH_M, bottom.max(axis=0) + _TOUCH_M
    others = [_near_box(o, lo, hi) for j, o in enumerate(objects) if j != k]
    near = np.vstack(others) if others else np.zeros((0, 3))
    if not near.shape[0]:
        return False
    d, _ = cKDTree(near).query(bottom, distance_upper_bound=_TOUCH_M)
    return bool(np.isfinite(d).sum() >= 5)


def _on_what_is_beneath(
    p: np.ndarray,
    low: float,
    others: list[np.ndarray],
    height: Callable[[np.ndarray], np.ndarray],
    to_2d: Callable[[np.ndarray], np.ndarray],
) -> bool:
    """Does another object lie beneath the outline of the object ``p`` (in-plane, within `_CELL_M`
    of its points), reaching up to within `_HANG_M` of its lowest point? Then it stands on
    that object where the camera cannot see the contact: a box laid across two others
    (mOSD test47: its bottom 1 to 1.5 cm above their tops, their tops hidden under it),
    though the support is seen between them. The same `_HANG_M` that tells hanging from
    resting on the support tells it from resting on an object."""
    from scipy.spatial import cKDTree

    if not others:
        return False
    q = np.vstack(others)
    q = q[height(q) >= low - _HANG_M]
    if not q.shape[0]:
        return False
    p2 = to_2d(p)
    q2 = _near_box(to_2d(q), p2.min(axis=0) - _CELL_M, p2.max(axis=0) + _CELL_M)
    if not q2.shape[0]:
        return False
    d, _ = cKDTree(p2).query(q2, distance_upper_bound=_CELL_M)
    return bool(np.isfinite(d).sum() >= _GOES_ON_MIN)


@dataclass(frozen=True)
class Verdict:
    index: int  # into the objects
    reason: str


def _cells(xy: np.ndarray) -> np.ndarray:
    """The `_CELL_M` cells ``xy`` falls in, as sorted unique packed keys: column and row in
    one int64 (a 1-D unique sorts several times faster than rows of two)."""
    c = np.floor(xy / _CELL_M).astype(np.int64)
    return np.unique(c[:, 0] * (1 << 32) + (c[:, 1] + (1 << 31)))


def not_standing(
    objects: list[np.ndarray],
    outside: np.ndarray,
    outside_below: np.ndarray,
    support_pts: np.ndarray,
    height: Callable[[np.ndarray], np.ndarray],
    to_2d: Callable[[np.ndarray], np.ndarray],
    inside_side: Callable[[np.ndarray], np.ndarray],
    rests_m: Callable[[np.ndarray], float],
) -> list[Verdict]:
    """Which of ``objects`` (each an (M, 3) array of its points) do not stand on the
    support, and why.

    ``outside``: points above the support's plane beyond the prism's side,
    ``outside_below``: those below it; ``support_pts``:
    the support's own points; ``height``: height above its plane; ``to_2d``: in-plane
    coordinates; ``inside_side``: (N,) bool, the points farther than `_BORDER_M` inside
    the prism's side; ``rests_m``: for an object's points, the height below which it
    rests on the support (grows with range).
    """
    from scipy.spatial import cKDTree

    out_tree = cKDTree(outside) if outside.shape[0] else None
    low_tree = cKDTree(outside_below) if outside_below.shape[0] else None
    support_cells = _cells(to_2d(support_pts)) if support_pts.shape[0] else np.zeros(0, dtype=np.int64)
    verdicts: dict[int, str] = {}
    lows = []
    # the side test once for all objects' points (it is per point), split back per object
    inside_all = inside_side(np.vstack(objects)) if objects else np.zeros(0, dtype=bool)
    inside_each = np.split(inside_all, np.cumsum([p.shape[0] for p in objects])[:-1])
    for k, p in enumerate(objects):
        lows.append(float(height(p).min()))
        edge = p[~inside_each[k]]
        if out_tree is not None and edge.shape[0]:
            near = np.asarray(out_tree.query_ball_point(edge, _GOES_ON_M, return_length=True)) > 0
            goes_on = int(near.sum())
            # it crosses the side above the support: an object standing at the side (cut
            # by the hull where the table behind it is hidden) crosses it from the bottom
            if goes_on >= _GOES_ON_MIN and float(height(edge[near]).min()) > rests_m(p) + _REACH_ABOVE_M:
                verdicts[k] = (
                    f"reaches in from beyond the support's outline ({goes_on} of its points "
                    "touch points above the support outside it): an arm, a hand, a cable"
                )
                continue
        if low_tree is not None and edge.shape[0]:
            down = int((np.asarray(low_tree.query_ball_point(edge, _GOES_ON_M, return_length=True)) > 0).sum())
            if down >= _GOES_ON_MIN:
                verdicts[k] = (
                    f"stands beyond the support's edge: it goes on below the support's level outside its "
                    f"outline ({down} of its points touch such points): a desk, a shelf, furniture behind"
                )
    # hangs: decided after the two rules above, so what lies beneath counts only when it
    # is itself an object (not an arm's or a shelf's part), whatever the objects' order
    standing = [k for k in range(len(objects)) if k not in verdicts]
    for k in standing:
        p, low = objects[k], lows[k]
        if low <= rests_m(p) + _HANG_M or not support_cells.size or _rests_on_another(k, p, height, low, objects):
            continue
        if _on_what_is_beneath(p, low, [objects[j] for j in standing if j != k], height, to_2d):
            continue
        own = _cells(to_2d(p))
        seen = int(np.isin(own, support_cells, assume_unique=True).sum()) / max(1, own.size)
        if seen >= _SEEN_UNDER_SHARE:
            verdicts[k] = (
                f"hangs above the support: its lowest point {low:.3f} m above it, the support seen "
                f"beneath {100 * seen:.0f} % of it"
            )
    # what stands on an excluded thing, until nothing more is found
    changed = True
    while changed:
        changed = False
        gone = [k for k in verdicts]
        if not gone:
            break
        tree = cKDTree(np.vstack([objects[k] for k in gone]))
        owner = np.concatenate([np.full(objects[k].shape[0], k) for k in gone])
        for k, p in enumerate(objects):
            if k in verdicts or lows[k] <= rests_m(p) + _HANG_M:
                continue
            h = height(p)
            bottom = p[h <= lows[k] + _TOUCH_M]
            d, j = tree.query(bottom, distance_upper_bound=_TOUCH_M)
            hit = np.isfinite(d)
            if hit.sum() >= 5:
                under = int(np.bincount(owner[j[hit]]).argmax())
                what = verdicts[under].split(":")[0].split(" (")[0]
                verdicts[k] = f"stands on something excluded (what {what}), {lows[k]:.3f} m above the support"
                changed = True
    return [Verdict(k, why) for k, why in sorted(verdicts.items())]
