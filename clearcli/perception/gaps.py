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

`gap_behind` looks for the gap along directions within `_TURN_DEG` of the camera's line
of sight across the support (a surface "behind" lies beyond the table as the camera looks),
in `_BIN_M` strips: a run of strips no wider than `_GAP_MAX_M` holding at most
`_GAP_SHARE` of what the strips on either side hold (their median over `_SIDE_M`), both
sides at least `_SIDE_MIN_SHARE` of the support's points, the far side reaching
`_FAR_MIN_M` beyond the gap. Each side's heights are fitted by a line across the strips
within `_SIDE_M` of the gap; their levels at the gap differ by `_STEP_MIN_M` or more.

Measured: the self-made desk_level_behind frames whose desk RANSAC takes into the
table's plane (choose seeds 19, 20, 24: a desk 6-9 mm lower, 2-2.5 cm behind) show a gap
0.5-1.5 cm wide with a step of 6.7-9.3 mm, and only their desk's objects lie beyond it;
the 50 mOSD frames, the foreign choose part, the fixtures and the other families' choose
frames show no gap at all (a step of 0 allowed), so `_STEP_MIN_M` decides only where a
gap is seen: two tables side by side at one level (a gap, no step) stay one support.
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
# directions tried: the camera's line of sight across the support, turned by up to this
# much either way in `_TURN_STEP_DEG` steps (a desk behind faces the camera roughly)
_TURN_DEG = 30
_TURN_STEP_DEG = 5
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
# the two sides' levels at the gap differ by at least this (m): the desks 6.7-9.3 mm
# (module doc); half of the least, and ten times a median's spread over the thousands
# of points on either side
_STEP_MIN_M = 0.003
# an object stands behind the gap when this share of its points lie beyond its middle
_BEYOND_SHARE = 0.8
# the support's points looked at: an even sample of at most this many
MAX_POINTS = 60000


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


def _gap_along(t: np.ndarray, h: np.ndarray) -> Gap | None:
    """The gap across the strips of positions ``t`` (heights ``h``) with the largest
    step, or None; ``direction`` left empty for the caller."""
    lo = float(t.min())
    strip = np.floor((t - lo) / _BIN_M).astype(np.int64)
    counts = np.bincount(strip)
    n_side = int(round(_SIDE_M / _BIN_M))
    n_max = int(round(_GAP_MAX_M / _BIN_M))
    total = t.size
    cum = np.concatenate([[0], np.cumsum(counts)])
    best: Gap | None = None
    i = 0
    n = counts.size
    while i < n:
        near = counts[max(0, i - n_side) : i]
        ref = float(np.median(near)) if near.size >= n_side // 2 else 0.0
        if ref <= 0 or counts[i] > _GAP_SHARE * ref:
            i += 1
            continue
        j = i
        while j < n and j - i <= n_max and counts[j] <= _GAP_SHARE * ref:
            j += 1
        far = counts[j : j + n_side]
        if j - i > n_max or far.size < n_side or float(np.median(far)) * _GAP_SHARE < counts[i:j].max():
            i = j + 1
            continue
        near_share, far_share = cum[i] / total, (total - cum[j]) / total
        far_reach = (n - j) * _BIN_M
        if near_share >= _SIDE_MIN_SHARE and far_share >= _SIDE_MIN_SHARE and far_reach >= _FAR_MIN_M:
            at = lo + 0.5 * (i + j) * _BIN_M
            near_sel = (strip >= i - n_side) & (strip < i)
            far_sel = (strip >= j) & (strip < j + n_side)
            step = _level_at(t[near_sel], h[near_sel], at) - _level_at(t[far_sel], h[far_sel], at)
            if best is None or abs(step) > abs(best.step_m):
                best = Gap(np.zeros(2), at, (j - i) * _BIN_M, step)
        i = j + 1
    return best


def gap_behind(support_xy: np.ndarray, support_h: np.ndarray, camera_xy: np.ndarray) -> Gap | None:
    """The gap across the support (module doc) beyond which another surface lies, or
    None. ``support_xy`` (N, 2): the support's points in its plane's coordinates,
    ``support_h`` (N,) their heights above it; ``camera_xy`` (2,): the camera's foot on
    the plane in the same coordinates."""
    if support_xy.shape[0] < 1000:
        return None
    step = max(1, -(-support_xy.shape[0] // MAX_POINTS))
    xy, h = support_xy[::step], support_h[::step]
    sight = xy.mean(axis=0) - camera_xy
    norm = float(np.hypot(*sight))
    if norm < 1e-6:
        return None  # a camera straight above the support's middle: no "behind"
    base = float(np.arctan2(sight[1], sight[0]))
    best: Gap | None = None
    for deg in range(-_TURN_DEG, _TURN_DEG + 1, _TURN_STEP_DEG):
        angle = base + np.radians(deg)
        u = np.array([np.cos(angle), np.sin(angle)])
        found = _gap_along(xy @ u, h)
        if (
            found is not None
            and abs(found.step_m) >= _STEP_MIN_M
            and (best is None or abs(found.step_m) > abs(best.step_m))
        ):
            best = Gap(u, found.at_m, found.width_m, found.step_m)
    return best


def behind_the_gap(gap: Gap, objects_xy: list[np.ndarray]) -> list[int]:
    """The objects (each its points' in-plane (M, 2)) standing beyond ``gap``."""
    return [k for k, xy in enumerate(objects_xy) if xy.shape[0] and float(np.mean(gap.beyond(xy))) >= _BEYOND_SHARE]
