"""A gap across the support with a step at it: another surface behind (issue 37).

A desk or a second table standing behind the table at nearly its level (a few millimetres
lower or higher, a centimetre or two away) is one plane to RANSAC: its points lie within
the plane's distance of the table's. The support then takes in the desk, its hull grows
over it, and what stands on the desk stands "on the support": no rule about the
outline sees it (exclude.py), and a plan reaches for it.

The camera sees where one surface ends and the other begins. Across the support, along a
line, it sees almost none of the support's points (the gap: the rays there pass down
between the two, or end on the desk's front edge), with the support's points on both
sides; and the two sides do not meet at one level: each side's own heights, fitted near
the gap, are a step apart where the gap runs. A table's shadows behind the objects on it
leave no line across the whole table, and where a long thing's shadow does, the table
goes on at its level on the far side (no step); a sensor's warping of a flat table bends
it slowly, with no step at a line. What stands beyond such a gap, on the far side from
the camera, stands on the surface behind.

`gap_behind` looks for the gap across the camera's line of sight over the support (a
surface "behind" lies beyond the table as the camera looks) and along each of the
support's outline's `_EDGES` longest sides (a desk behind, turned, has its front
parallel to its own far edge, which the outline takes in; a gap 2 cm wide is lost to a
direction a few degrees off it over a metre of table, so the directions are the
outline's own, not a sweep of angles). Along each, in `_BIN_M` strips: a run of strips
no wider than `_GAP_MAX_M` holding at most `_GAP_SHARE` of what the strips on either
side hold (their median over `_SIDE_M`), both sides at least `_SIDE_MIN_SHARE` of the
support's points, the far side reaching `_FAR_MIN_M` beyond the gap. Each side's
heights are fitted by a line across the strips within `_SIDE_M` of the gap; their
levels at the gap differ by `_STEP_MIN_M` or more.

Measured: the self-made desk_level_behind frames whose desk RANSAC takes into the
table's plane (choose seeds 19, 20, 24: a desk 6-9 mm lower, 2-2.5 cm behind) show a gap
0.5-1.5 cm wide with a step of 7.0-9.5 mm, and only their desk's objects lie beyond it.
Elsewhere a gap is rare and has no step: four of the 50 mOSD frames show one (a single
5 mm strip) with steps of 0.01-0.69 mm, one of the families' 1600 choose frames 0.48 mm;
the foreign choose part and the fixtures none.
`_STEP_MIN_M` lies 4 times above those and 2.3 times below the desks': two tables side
by side at one level (a gap, no step) stay one support.
A thin board covering the table's whole width in front, a few millimetres thick, would
look the same as a desk behind (the table behind its far edge is hidden by its
thickness); no frame here has one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# strips across the support (m): a 2 cm gap is two to four of them, a Kinect's rows at
# 1.3 m and 35 degrees lie 3-4 mm apart along the table
_BIN_M = 0.005
# directions tried besides the line of sight: across the outline's longest sides
_EDGES = 4
# two directions within this angle are one (rad)
_SAME_DIRECTION_RAD = 0.01
# ... and none turned more than this from the line of sight (rad): an object's shadow is
# a band along the rays, which a direction across the rays sees as a gap the length of
# the table (mOSD test55, 85 degrees off: a band with a 3.1 mm tilt across it); the
# rays over a Kinect's or a RealSense's view are at most 28-35 degrees off its middle
_MAX_TURN_RAD = float(np.radians(30.0))
# a gap: strips holding at most this share of the median of the strips beside it
_GAP_SHARE = 0.15
# ... at most this wide (a gap between two pieces of furniture, not a missing half)
_GAP_MAX_M = 0.05
# the strips beside the gap whose median it is judged by, and whose heights give each
# side's level at the gap
_SIDE_M = 0.1
# each side holds at least this share of the support's points
_SIDE_MIN_SHARE = 0.1
# the far side goes on at least this far beyond the gap (a surface, not a lip)
_FAR_MIN_M = 0.1
# the two sides' levels at the gap differ by at least this (m): the desks 7.0-9.5 mm,
# gaps elsewhere at most 0.69 mm (module doc)
_STEP_MIN_M = 0.003
# the support's points looked at: an even sample of at most this many (the desks'
# frames: 70-100 in a strip beside the gap, 0-7 in its emptiest strips)
_MAX_POINTS = 25000
# an object stands behind the gap when this share of its points lie beyond its middle
_BEYOND_SHARE = 0.8


@dataclass(frozen=True)
class Gap:
    """A gap across the support: ``direction`` (2,) unit, in the support's plane
    coordinates, pointing away from the camera; the gap's middle at ``at_m`` along it
    (``direction`` @ xy); ``width_m``; ``step_m``, the near side's level at the gap minus
    the far side's (> 0: the surface behind is lower)."""

    direction: np.ndarray
    at_m: float
    width_m: float
    step_m: float

    def beyond(self, xy: np.ndarray) -> np.ndarray:
        """(N,) bool: in-plane points beyond the gap's middle, on the far side."""
        return xy @ self.direction > self.at_m

    def why(self) -> str:
        side = "lower" if self.step_m > 0 else "higher"
        return (
            f"stands on another surface behind the support: a gap {self.width_m * 100:.1f} cm wide runs across "
            f"the support, and beyond it the surface lies {abs(self.step_m) * 1000:.1f} mm {side}: a desk or a "
            "table behind"
        )


def _level_at(t: np.ndarray, h: np.ndarray, at: float) -> float:
    """The least-squares line of heights ``h`` over positions ``t``, at ``at``."""
    tc = t - at
    a = np.column_stack([np.ones_like(tc), tc])
    coef, *_ = np.linalg.lstsq(a, h, rcond=None)
    return float(coef[0])


def _gap_along(direction: np.ndarray, t: np.ndarray, h: np.ndarray) -> Gap | None:
    """The gap across the strips of positions ``t`` along ``direction`` (heights ``h``)
    with the largest step, or None."""
    lo = float(t.min())
    strip = np.floor((t - lo) / _BIN_M).astype(np.int64)
    counts = np.bincount(strip)
    n = counts.size
    n_side = int(round(_SIDE_M / _BIN_M))
    n_max = int(round(_GAP_MAX_M / _BIN_M))
    if n < 2 * n_side + 1:
        return None
    # each window of n_side strips' median: the near side of strip i is window i - n_side,
    # the far side of a run ending before strip j is window j
    window_median = np.median(np.lib.stride_tricks.sliding_window_view(counts, n_side), axis=1)
    ref = np.zeros(n)
    ref[n_side:] = window_median[: n - n_side]
    low = counts <= _GAP_SHARE * ref
    low[:n_side] = False
    # a run starts where a low strip follows one that is not (all strips at once; the few
    # runs, none on most frames, one by one)
    starts = np.flatnonzero(low & ~np.concatenate([[False], low[:-1]]))
    if not starts.size:
        return None
    total = t.size
    cum = np.concatenate([[0], np.cumsum(counts)])
    best: Gap | None = None
    for i in starts.tolist():
        limit = _GAP_SHARE * ref[i]
        j = i
        while j < n and j - i <= n_max and counts[j] <= limit:
            j += 1
        if j - i > n_max or j + n_side > n or window_median[j] * _GAP_SHARE < counts[i:j].max():
            continue
        near_share, far_share = cum[i] / total, (total - cum[j]) / total
        if near_share < _SIDE_MIN_SHARE or far_share < _SIDE_MIN_SHARE or (n - j) * _BIN_M < _FAR_MIN_M:
            continue
        at = lo + 0.5 * (i + j) * _BIN_M
        near_sel = (strip >= i - n_side) & (strip < i)
        far_sel = (strip >= j) & (strip < j + n_side)
        step = _level_at(t[near_sel], h[near_sel], at) - _level_at(t[far_sel], h[far_sel], at)
        if best is None or abs(step) > abs(best.step_m):
            best = Gap(direction, at, (j - i) * _BIN_M, step)
    return best


def _directions(polygon_2d: np.ndarray, sight: np.ndarray) -> list[np.ndarray]:
    """Unit directions (2,) to look along, each pointing away from the camera: the line
    of sight ``sight``, then across each of the outline's `_EDGES` longest sides."""
    out = [sight / float(np.hypot(*sight))]
    if polygon_2d.shape[0] >= 3:
        sides = np.roll(polygon_2d, -1, axis=0) - polygon_2d
        lengths = np.hypot(sides[:, 0], sides[:, 1])
        for k in np.argsort(-lengths, kind="stable")[:_EDGES].tolist():
            if lengths[k] <= 0:
                continue
            across = np.array([-sides[k, 1], sides[k, 0]]) / lengths[k]
            if float(across @ out[0]) < 0:
                across = -across
            if float(across @ out[0]) < np.cos(_MAX_TURN_RAD) or any(
                float(across @ d) > np.cos(_SAME_DIRECTION_RAD) for d in out
            ):
                continue  # a side along the line of sight (module doc), or one tried already
            out.append(across)
    return out


def gap_behind(
    support_xy: np.ndarray, support_h: np.ndarray, camera_xy: np.ndarray, polygon_2d: np.ndarray
) -> Gap | None:
    """The gap across the support (module doc) beyond which another surface lies, or
    None. ``support_xy`` (N, 2): the support's points in its plane's coordinates (an even
    sample of them will do), ``support_h`` (N,) their heights above it; ``camera_xy``
    (2,): the camera's foot on the plane in the same coordinates; ``polygon_2d`` (K, 2):
    the support's outline in them."""
    if support_xy.shape[0] < 1000:
        return None
    # an even sample: the strips beside the desks' gaps still hold 70-100 points
    every = max(1, -(-support_xy.shape[0] // _MAX_POINTS))
    xy, h = support_xy[::every], support_h[::every]
    sight = xy.mean(axis=0) - camera_xy
    if float(np.hypot(*sight)) < 1e-6:
        return None  # a camera straight above the support's middle: no "behind"
    directions = _directions(polygon_2d, sight)
    along = xy @ np.stack(directions, axis=1)  # every direction's positions in one product
    best: Gap | None = None
    for k, u in enumerate(directions):
        found = _gap_along(u, np.ascontiguousarray(along[:, k]), h)
        if (
            found is not None
            and abs(found.step_m) >= _STEP_MIN_M
            and (best is None or abs(found.step_m) > abs(best.step_m))
        ):
            best = found
    return best


def behind_the_gap(gap: Gap, objects_xy: list[np.ndarray]) -> list[int]:
    """The objects (each its points' in-plane (M, 2)) standing beyond ``gap``."""
    return [k for k, xy in enumerate(objects_xy) if xy.shape[0] and float(np.mean(gap.beyond(xy))) >= _BEYOND_SHARE]
