"""Only what stands on the support is an object (issue 37): the segments that do not are
set aside with the reason, for --json to list as ``excluded``.

- reaches in from beyond the support's outline: a robot arm, a hand, a cable. The prism
  ends at the support's hull (grown by ``hull_margin_m``); a segment that touches that
  side of the prism and goes on beyond it, above the support's plane, is part of
  something standing elsewhere. An object cut by the image's border does not go on.
- enters from beyond the image's border, above the support: where the support's outline
  runs out of the view (a robot's arms over the near part of the table, a table wider
  than the view), what reaches in is cut by the image's border instead. It is cut there
  above the support (most of its points at the border more than `_HANG_M` above resting
  height), and apart from where it comes down to the support: the median in-plane
  distance from those points to its own resting points is more than `_APART_M`, or it
  rests nowhere. An object standing on the table whose top the border cuts has its side
  walls rising from its base to the cut, so its cut part stands over its base (mOSD has
  no such cut; uois_image_0002's tall box: 0.8 cm); an object lying at the border is cut
  at its resting height. An arm the sensor's inpainting joins to the table meets it only
  along its silhouette, centimetres off (gqcnn's YuMi arms: 4.8 to 6.8 cm). An
  unorganized cloud has no image border: its edge is where it was cropped or the
  sensor's view ended, the sides of its footprint's convex hull (`at_cloud_border`), and
  the same rule reads it (``exclude_cloud_border``).
- a sliver mostly out of view (`_sliver`): `_SLIVER_SHARE` of its points or more at that
  border (the image's or the cloud's): a few pixels or centimetres of something beyond
  the view, too little of it seen to model or grasp.
- stands beyond the support's edge, on or as part of furniture: it touches a thing
  outside the support's outline (above its plane) that goes on `_FAR_BEYOND_M` or more
  beyond the outline, farther than any object the hull cuts can reach (a second desk
  behind the table, its face rising at the table's far edge and its top going back; a
  shelf). Or it goes on below the support's level beyond its outline (a desk's face).
  The thing's extent is taken along the frame's pixel grid (neighbouring pixels within
  `_LINK_M` of each other are one surface), not as the crow flies, so a wall or a
  cupboard behind an object at the edge is not the object's own. An unorganized cloud
  has no pixel grid: there only the points touched count, and the rule rarely fires.
- comes down to the support's level only beyond its outline (`_FOOT_INSIDE_SHARE`): of its
  points at resting height (at least `_GOES_ON_MIN`), fewer than that share lie within the
  prism's side (the outline grown by ``hull_margin_m`` less `_BORDER_M`): it stands beyond
  the support's edge, on the floor or on furniture, and only rises into the prism (a
  chair's back or a box standing just behind the table, its top above the table's level).
  An object standing on the support rests on it inside the outline, where the support is
  seen: at least 94 % of its resting points on the choose part and mOSD, the table hidden
  behind it or not (the hull cut short at its foot).
- the support seen nowhere around it (`support_around`; organized frames): in the ring
  `_RING_PX` pixels round its silhouette, of at least `_RING_MIN_PX` pixels seen at about
  the support's level and in no segment, under `_RING_SUPPORT_SHARE` are the support's:
  another surface at nearly its height (a bench behind a foam board). Not said of a
  segment all of whose points lie `DEEP_INSIDE_M` or more inside the support's outline:
  the support goes on all round it there, and what surrounds it is a container's floor
  (objects standing in a large bowl).
- goes on below the support's level beneath itself (`_beneath_below`): an upright face (its
  footprint a line, `_FACE_THIN_M` across, at least `_BELOW_UPRIGHT` times as tall as
  thick) over at least `_BENEATH_SHARE` of whose footprint cells the camera sees points
  between `_BELOW_M` and `_BELOW_DEEP_M` below the support's level: its surface goes on
  down past the level of the support it seems to stand on (a chair's back, a board, a
  cupboard's front standing on the floor at the support's edge, its strip at the
  support's level taken for support). An object standing on the support has the support
  beneath it, not its own face going on (the choose part, mOSD, the fixtures: no upright
  face of an object has any such cell; the floor under the table, seen past its near
  edge, lies far deeper).
- its foot goes on below the support's level (`_foot_below`): of the cells of its points
  at resting height, `_FOOT_BELOW_SHARE` hold points between `_BELOW_M` and
  `_BELOW_DEEP_M` below the support's level: what it stands on goes on down past the
  support (a shelf's side boards on the floor just beyond the table's ends, inside the
  prism's margin, one segment with the board they hold). An object standing on the
  support has the support beneath its foot; one at the table's edge, the table's side
  face beneath part of it.
- hangs above the support: its lowest point well above it (more than `_HANG_M` plus the
  range's noise) and the support seen beneath it (in at least `_SEEN_UNDER_SHARE` of the
  cells it covers, the camera sees the support's own points), so nothing it could stand
  on is hidden there: a shelf board, a lamp, the arm's gripper seen apart. Unless an
  object lies beneath its outline, reaching up to within `_HANG_M` of its bottom: it
  stands on that object where the contact is hidden (a box laid across two others).
  And only when what holds it up is seen (`_held_from`): within `_HOLD_M` of what lies
  outside the support's outline or of a segment already excluded (an arm, a wall; what
  the image's border cuts above the support was excluded before). Nothing hangs in
  the air: held by nothing seen, it is the top of an object whose body the sensor does
  not see, standing on the support (a clear bottle's neck and shoulders, its glass body
  giving no depth: cleargrasp_000000080, 13 cm up), and stays an object.
- part of what reaches in: it rests nowhere on the support (its lowest point above
  resting height) and is joined, more than `_REACH_ABOVE_M` above the support, to a
  segment excluded as reaching in (an arm's forearm cut from its upper arm).
- stands on something excluded: its bottom within `_TOUCH_M` of an excluded segment's
  points, and above the support (a box on the shelf board, on the arm).
- a veil of mixed pixels (`_veil`): where a near edge meets the far background the
  sensor returns depths between the two along each pixel's ray, a thin sheet lying along
  the camera's line of sight (PCL's ShadowPoints filter: normals perpendicular to the
  viewing ray). Its depth span along the rays is at least `_VEIL_ALONG` times its narrow
  extent across them in the image, and its height falls from its near end to its far end
  as the rays do (`_VEIL_FALLS` of their fall, at least `_VEIL_RISE_M`): a thing lying
  along the rays (a bottle pointing away from a low camera) keeps its height.
  Decided last, so a veil neither holds up nor carries anything in the rules above.
- a fringe of the support's colour against an object (`_fringe`; frames with colour): where
  the depth image is registered a few pixels off the colour image, or a stereo sensor
  fattens a near edge over what lies behind it, an object's depth spreads over the
  support beside it, and the colour split cuts that piece off: a segment whose pixels all
  show the support's colour (at most `_FRINGE_OFF_SHARE` differ from it, flat.py's test),
  low (its top, 95th percentile of heights, `_FRINGE_BELOW_M` or more under the median
  height of an object it touches: at least `_GOES_ON_MIN` of that object's points within
  `_TOUCH_M` of its own). An object of the table's own colour standing alone, or as tall
  as what it touches, stays.

A stacked object is not excluded: it stands on an object, and the support under it is
hidden by that object, not seen. Every threshold keeps a margin of millimetres or tens
of points, far from what rounding-sized changes of the points can move.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from clearcli.perception.graph import components
from clearcli.perception.raster import dilate_square
from clearcli.perception.table import hull_vertices, inside_convex

_BORDER_M = 0.02  # a segment's points this near the prism's side touch it
_GOES_ON_M = 0.02  # points beyond the side within this of those continue the segment
_GOES_ON_MIN = 15  # at least this many such points
_HANG_M = 0.03
# an arm crosses the outline at least this high above the support (an object standing
# at a side the hull cuts reaches the side lower down)
_REACH_ABOVE_M = 0.10
_SEEN_UNDER_SHARE = 0.3
# what hangs is held by something seen this near it (the gap a dark wrist leaves between an
# arm and its gripper, a lamp's shade and its post); measured on the choose part, the clear
# bottles' tops lie 0.36 m and more from any excluded thing, nothing outside or at the border
_HOLD_M = 0.10
# an object rests on the support inside its outline: of its points at resting height, fewer
# than this share within the prism's side and it rests beyond the outline (on the choose part
# and mOSD the objects' shares are 0.94 and more; the bench behind gqcnn_primesense_0's board,
# excluded by the support seen around it, 0.51)
_FOOT_INSIDE_SHARE = 0.2
_CELL_M = 0.01
# what goes on below the support's level beneath an upright face: points this far below it
# (twice the plane's inlier distance; the table's own noise reaches 9 mm on 1 % of its points)
# and not deeper than `_BELOW_DEEP_M` (the floor under the table, seen past its near edge,
# lies some 70 cm down beneath every object near that edge: no face's continuation)
_BELOW_M = 0.02
_BELOW_DEEP_M = 0.15
# a face this many times as tall as it is thick stands upright (a lying pen or strip does not:
# 0.6 times); rendered boards standing at the table's edge: 3.4 to 6.5 times
_BELOW_UPRIGHT = 2.0
# the share of its footprint's cells (`_CELL_M`, at least `_GOES_ON_MIN` of them) with such
# points beneath: rendered boards at the table's edge 0.33 to 0.67; every upright face of an
# object on the choose part, mOSD and the fixtures 0 (the walls at cleargrasp's tables 0.05)
_BENEATH_SHARE = 0.25
# the share of a segment's foot cells (its points at resting height, `_CELL_M`, at least
# `_GOES_ON_MIN` of them) with such points beneath, from which its foot goes on below the
# support's level: a shelf's side boards standing on the floor 1-3 cm beyond the table's
# ends, in the prism's margin and one segment with the board they hold, 0.85-1.0 (the
# choose seeds; 0.27-0.47 where the segment holds more than the boards' feet, kept);
# objects standing at the table's edge over its side face at most 0.39 (uois_image_0003;
# 0.29 uois_image_0006's bag), every other object of the choose part, mOSD, the fixtures
# and the families' choose seeds 0
_FOOT_BELOW_SHARE = 0.6
# a height band grown by this share of its width, so that the rounding of heights cannot
# leave out a point the exact distance keeps (a speed-up that changes no answer)
_BAND_SLACK = 2.0
_TOUCH_M = 0.015
# a thing outside the outline reaching this far beyond it is furniture (a desk 40 cm
# deep); an object the hull cuts (the table behind it hidden) reaches its own depth
# beyond the outline, at most about the 30 cm of the widest objects cleared
_FAR_BEYOND_M = 0.25
_LINK_M = 0.02  # neighbouring pixels this near in space are one surface
# a part cut by the image's border this far (median, in-plane) from where its segment rests
# on the support is not held up by it: an object's cut top stands over its base, within its
# walls' lean and the depth's fattening (uois_image_0002's tall box: 0.8 cm); an inpainted
# arm's silhouette meets the support centimetres off (gqcnn's YuMi arms: 4.8 to 6.8 cm; a
# PhoXi bin's wall, cut by the border along its rim: 3.2 cm). Measured on the choose part:
# 1.7 cm of margin below, 0.7 cm and more above (a median of hundreds of points: rounding
# moves it by micrometres).
_APART_M = 0.025
# a segment with this share of its points or more at the view's border (the image's, within
# `_BORDER_PX`; an unorganized cloud's edge, within a centimetre or two) is a sliver of
# something mostly beyond the view: at most a few pixels or a couple of centimetres of it
# seen, too little to model or grasp (the rest of it may be an object, a board's rim, the
# table's own edge curling up). Measured on the choose part, mOSD and the fixtures: every
# segment but three holds less than 30 % of its points there; the three are industrial_table's
# strips of noise along the cloud's edge (not labelled), 72, 89 and 91 %; a point more or
# less moves a share by under 2 % (at least `_GOES_ON_MIN` points at the border)
_SLIVER_SHARE = 0.8
# a wall, a cupboard's side, a bin's wall: one flat face standing on the support (its
# footprint a line: `_FACE_THIN_M` across, between the 5th and 95th percentiles) larger
# than any object cleared: the diagonal of its length along the support (2nd to 98th
# percentile) and its height at least `_WALL_FACE_M`, the tallest an object standing on
# the support may be (support.py's 0.4 m; the widest is some 30 cm). Measured on the
# choose part: the walls at cleargrasp's table edges 0.48 and 1.18 m; the largest face
# of an object, uois_image_0002's tall box seen front on (its top cut by the border),
# 0.26 m; footprints 0.6 to 1.3 cm across (a box's front face 1.8 cm) against 3 cm.
_FACE_THIN_M = 0.03
# a face stands upright when it is this many times taller than thick (the walls: 10 and 50
# times; a long strip lying flat, less than once)
_UPRIGHT = 4.0
_WALL_FACE_M = 0.4
# a piece lying in a wall's face need not be upright when its top (98th percentile of its
# heights) is this high or more: a camera lower (30-35 degrees down) sees a wall face-on
# and the segmentation cuts it into strips 2-6 cm high, each less than `_UPRIGHT` times its
# 1-1.5 cm across (self-made walls and desks seen 32 degrees down: the strips' tops 4 cm
# and more); a thin thing lying at a wall's foot (a pen, a marker: its top 1-2 cm up)
# stays an object
_PIECE_TOP_M = 0.03
# or a smaller face rising at the support's edge along most of it: a bin's wall is only as
# long as the bin's floor. Its length along its line at least `_WALL_SPAN` of the support's
# extent along that line (2nd to 98th percentile of the support's points), and the support
# not going on beyond it: fewer than `_WALL_BEYOND_SHARE` of the support's points over its
# length lie more than `_FACE_THIN_M` beyond its line (away from the support's middle).
# Measured on the choose part: gqcnn_phoxi_dexnet4_0's far bin wall 0.37 m long (0.38 m
# with its height, under `_WALL_FACE_M`), 74 % of the bin floor's extent, none of the floor
# beyond it; the faces of objects 8 to 30 % (uois_image_0002's tall box 18 %, the table
# hidden behind it: none beyond), the walls at cleargrasp's tables 49 and 127 %.
_WALL_SPAN = 0.5
_WALL_BEYOND_SHARE = 0.01
# the support seen around a segment: in the ring `_RING_PX` pixels wide around its
# silhouette (a square grown around each pixel), among the pixels seen (a point kept) and in no segment, the share that are
# the support's. An object standing on the support has it seen at its foot on some side
# (on the choose part at least 17 % of such pixels, uois_image_0006's tin among others
# 19 %); a stretch of another surface at nearly the support's height beyond its edge
# (gqcnn's bench behind the foam board, 1.5 cm above its plane, cut by the image's top)
# has none (0 %). Decided only on `_RING_MIN_PX` pixels or more (an object inside a heap
# has the others around it, not the support or anything else).
_RING_PX = 4
# only the ring's pixels at about the support's level count (within this of its plane, the
# hang height: where the support would be seen if it went on there); what is higher is an
# object's part the prism left out (mOSD test57: a heap's pieces beyond the hull, 6-9 cm up)
AROUND_LEVEL_M = 0.03
_RING_MIN_PX = 100
_RING_SUPPORT_SHARE = 0.05
# ... and only of a segment some of whose points lie within this of the support's outline
# (its convex hull) or beyond it: one farther inside has the support going on all round
# it, so it stands on something else there, a container's floor (large_bowl's objects
# in the bowl: 21-24 cm inside, the bowl's floor round them 1.5-2.5 cm up, within
# `AROUND_LEVEL_M`). What stood beyond the edge on the choose part and seeds: at most
# 1.2 cm inside (gqcnn's bench behind the foam board); 5 cm lies between, near their
# geometric mean, and is the prism's own margin beyond the outline
DEEP_INSIDE_M = 0.05
# pixels this near the image's edge are where it cuts a segment (a few, not one: a working
# grid at stride k ends up to k - 1 pixels short of the edge; a sensor's edge pixels drop out)
_BORDER_PX = 3
# a veil (mixed pixels between a near edge and the far background) lies along the camera's
# rays: its depth span along them (5th to 95th percentile of range) at least this many times
# its narrow extent across them (5th to 95th percentile in the image, at its range, across
# the edge it hangs from): a surface seen at atan(3.5) = 74 degrees or more from face-on.
# Structured light and active stereo lose a surface's depth well before that (the pattern
# smears out at grazing incidence; PCL's ShadowPoints default: 84 degrees), so such segments
# are mostly interpolated depths. Measured on the choose part: the veils beside
# gqcnn_primesense_2's and _4's robot arm and uois_image_0000's mustard cap 5.8, 5.7, 5.0;
# every labelled object's segment 2.4 or less (cleargrasp_000000130's clear bottle lying
# along the rays 2.4, its 6 mm thin piece of a clear cup 1.4): 1.4 times of margin each side.
_VEIL_ALONG = 3.5
# and its heights fall from its near end to its far end (median of the nearest and of the
# farthest tenth of its points) as the rays themselves fall towards the support: at least
# this share of the mean ray's fall over that range. A veil's points lie on the rays (the
# choose part's: 0.89 to 1.03; less where its edge is long and its rows reach different
# heights: 0.57 on the self-made veil of the tests); a thing lying flat along the rays (a
# bottle or a pen pointing away from a low camera, seen as steeply) keeps its height: 0 or
# less (its near end's face lower than its far end's top)
_VEIL_FALLS = 0.25
# and at most this share: a veil's points lie on the rays, so its heights fall as they do
# (0.89 to 1.03 on the choose part); a thin thing standing upright (a rod, a pen, a
# bottle's neck) falls from its top to its foot far faster than the rays over the same
# range: a rod 2.4 cm across and 15 cm tall seen from a table camera falls 2.7 times as
# fast, and is as deep along the rays against its width as a veil (3.7)
_VEIL_FALLS_MAX = 1.5
# and at least this much: a veil spans the height between the near edge and the background
# (the choose part's: 44 to 93 mm); the same 3 cm as `_HANG_M`, far above the range noise
_VEIL_RISE_M = 0.03
# a fringe of the support's colour: at most this share of its pixels differ from the
# support's colour (flat.py's test). Measured on the choose part: uois_image_0006's two
# fringes beside its tin and its cup 0.1 % and 0 %; every labelled object's segment
# touching another 5 % or more (gqcnn_primesense_4's grey toys 5 % and 11 %; on mOSD 36 %
# and more); segments of the table's colour alone (PCL's mug, gqcnn_primesense_2's white
# tube: 0 %) touch nothing
_FRINGE_OFF_SHARE = 0.02
# and its top this far or more under the median height of what it touches: the fringes'
# tops 35 and 37 mm against the tin's median 96 mm; gqcnn_primesense_4's toy (5 %) 83 mm
# against 48 and 69 mm
_FRINGE_BELOW_M = 0.02
# the camera is at the origin (a camera frame) when the origin lies this far or more above the
# support's plane (as table.py decides it); otherwise there are no rays to lie along
_CAMERA_ABOVE_M = 0.05


def beyond_outline(xy: np.ndarray, polygon_2d: np.ndarray) -> np.ndarray:
    """(N,) how far each in-plane point ``xy`` lies beyond the convex counter-clockwise
    ``polygon_2d`` (m; negative inside): its farthest distance outside an edge's line
    (the distance itself off the corners, a little less beyond them)."""
    edges = np.roll(polygon_2d, -1, axis=0) - polygon_2d
    out = np.stack([edges[:, 1], -edges[:, 0]], axis=1)
    out /= np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-12)
    limits = np.einsum("ij,ij->i", out, polygon_2d)
    far = np.full(xy.shape[0], -np.inf)
    for k in range(polygon_2d.shape[0]):  # hull edges: tens
        far = np.maximum(far, xy @ out[k] - limits[k])
    return far


def row_mean(points: np.ndarray) -> np.ndarray:
    """``points.mean(axis=0)`` of (N, 3) float64 points, bit for bit: NumPy sums the rows
    of a C-ordered (N, 3) array one after another, and einsum's "ij->j" makes the same
    additions in the same order in a third of the time (a cluttered table's objects:
    100k points; per segment, the footprints and rays `_faces` and `_veil` average). Other layouts (columns contiguous: NumPy sums each pairwise) and
    dtypes take the mean itself."""
    if points.dtype != np.float64 or points.ndim != 2 or points.shape[0] == 0 or not points.flags.c_contiguous:
        return np.asarray(points.mean(axis=0))
    return np.einsum("ij->j", points) / points.shape[0]


def reach_beyond(points: np.ndarray, pixel: np.ndarray | None, width: int, beyond: np.ndarray) -> np.ndarray:
    """(N,) for each of ``points`` (outside the support's outline), the farthest its part
    reaches beyond the outline: the largest ``beyond`` over the points joined to it
    through neighbouring pixels (``pixel``: each point's index in a frame ``width``
    pixels wide) within `_LINK_M` of each other. Without a pixel grid, each point's own."""
    if pixel is None or points.shape[0] < 2:
        return beyond.copy()
    order = np.argsort(pixel, kind="stable")
    pix = pixel[order]
    rows: list[np.ndarray] = []
    cols: list[np.ndarray] = []
    for step in (1, width):  # the pixel to the right, the one below
        j = np.searchsorted(pix, pix + step)
        j_ok = np.minimum(j, pix.size - 1)
        hit = (j < pix.size) & (pix[j_ok] == pix + step)
        if step == 1:
            hit &= (pix % width) != width - 1
        a, b = order[hit], order[j_ok[hit]]
        near = np.einsum("ij,ij->i", points[a] - points[b], points[a] - points[b]) < _LINK_M**2
        rows.append(a[near])
        cols.append(b[near])
    r, c = np.concatenate(rows), np.concatenate(cols)
    n = points.shape[0]
    part = components(n, np.stack([r, c], axis=1))
    far = np.full(int(part.max()) + 1, -np.inf)
    np.maximum.at(far, part, beyond)
    return far[part]


def _near_box(points: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The rows of ``points`` inside the box [lo, hi] (as many columns as ``lo``): only they
    can be within the box's margin of what it was grown around, so a nearest-neighbour
    search against them alone gives the same answer as against all the points."""
    # rows by a mask: np.compress, several times faster than boolean indexing of rows (this
    # runs for every pair of nearby objects); the mask column by column, the same mask an
    # order of magnitude faster than comparing (N, 3) rows and reducing them along axis 1
    keep = (points[:, 0] >= lo[0]) & (points[:, 0] <= hi[0])
    for j in range(1, points.shape[1]):
        keep &= (points[:, j] >= lo[j]) & (points[:, j] <= hi[j])
    return np.compress(keep, points, axis=0)


def near_the_objects(points: np.ndarray, every: np.ndarray) -> np.ndarray:
    """The rows of ``points`` (N, 3) that `not_standing` can find touching an object, given
    every object's points ``every`` (M, 3, not empty): those within twice `_GOES_ON_M` of
    their box. It looks for the points below the support beyond its outline only within
    that of its objects' edge points' box, which lies inside theirs: so these alone give
    the same answers, and only they need testing against the outline (a far floor's
    hundred thousand points cost a tenth of a RealSense frame's exclusion to project).
    Fewer points than a quarter of the objects' (mOSD's: none to a few): all of them, the
    box would cost more than the test it saves."""
    if points.shape[0] <= every.shape[0] // 4:
        return points
    lo, hi = _lo_hi(every)
    return _near_box(points, lo - 2 * _GOES_ON_M, hi + 2 * _GOES_ON_M)


def _lo_hi(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(points.min(axis=0), points.max(axis=0))`` of non-empty (N, 2) or (N, 3) ``points``,
    column by column: the same values (a minimum does no arithmetic), an order of magnitude
    faster than NumPy's reduction along the rows of a few columns (per object and pair)."""
    cols = range(points.shape[1])
    return np.array([points[:, j].min() for j in cols]), np.array([points[:, j].max() for j in cols])


@dataclass(frozen=True)
class _Boxes:
    """Every object's box (``lo``, ``hi``: (n, 3) corners) and in-plane box (``lo_2d``,
    ``hi_2d``), and its highest point above the support (``top``): an object whose box
    misses a search box has no point in it, and is not searched (a heap's far objects)."""

    lo: np.ndarray
    hi: np.ndarray
    lo_2d: np.ndarray
    hi_2d: np.ndarray
    top: np.ndarray

    def meet(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        return np.flatnonzero((self.lo <= hi).all(axis=1) & (self.hi >= lo).all(axis=1))

    def meet_2d(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        return np.flatnonzero((self.lo_2d <= hi).all(axis=1) & (self.hi_2d >= lo).all(axis=1))


def _rests_on_another(k: int, objects: list[np.ndarray], h_each: list[np.ndarray], low: float, boxes: _Boxes) -> bool:
    """Does the bottom of object ``k`` (the lowest of its points' heights ``h_each[k]``:
    ``low``) touch another object (it leans on it, stands on it)?"""
    from scipy.spatial import cKDTree

    bottom = np.compress(h_each[k] <= low + _TOUCH_M, objects[k], axis=0)  # rows by a mask: compress is faster
    if not bottom.shape[0]:
        return False
    lo, hi = _lo_hi(bottom)
    lo, hi = lo - _TOUCH_M, hi + _TOUCH_M
    # only the others' points within `_TOUCH_M` of the bottom's heights can touch it (a
    # height differs by at most the distance; `_BAND_SLACK` for its rounding): the same
    # answer from a smaller tree
    band_lo, band_hi = low - _TOUCH_M * _BAND_SLACK, low + _TOUCH_M * (1.0 + _BAND_SLACK)
    others = [
        _near_box(np.compress((h_each[j] >= band_lo) & (h_each[j] <= band_hi), objects[j], axis=0), lo, hi)
        for j in boxes.meet(lo, hi).tolist()
        if j != k
    ]
    near = np.vstack(others) if others else np.zeros((0, 3))
    if not near.shape[0]:
        return False
    # only the bottom's points within the others' box (grown) can touch them
    near_lo, near_hi = _lo_hi(near)
    bottom = _near_box(bottom, near_lo - _TOUCH_M, near_hi + _TOUCH_M)
    if bottom.shape[0] < 5:  # too few to touch: no tree to build
        return False
    # a tree for one query: neither balanced nor compacted (several times faster to build;
    # the nearest distance found is the same)
    return _reached(cKDTree(near, balanced_tree=False, compact_nodes=False), bottom, _TOUCH_M, 5)


# _reached(): the points are queried this many at a time
_QUERY_CHUNK = 512
_HULL_MAX_SIDES = 256  # at_cloud_border's footprint: more sides are read through fewer corners


def _reached(tree: object, points: np.ndarray, reach_m: float, need: int) -> bool:
    """Do at least ``need`` of ``points`` have a point of ``tree`` (a cKDTree) within
    ``reach_m`` (a nearest-neighbour query's distance finite)? Queried in chunks that
    stop once ``need`` are found: each point's answer is its own, so the count so far is
    the whole query's count of those rows (the query was most of the time of the tests
    of stacked objects, and they mostly touch early).

    A chunk takes every n-th point (n chunks: each point in one of them), not a run of
    them: the points come in the pixels' order, and where they touch is one patch of
    the image, which a run may reach only in its last chunk (mOSD test57: a bottom of
    9519 points queried to nearly its end, ten times the time) while every chunk of a
    stride samples all of it. The count, and so the answer, is the same."""
    from scipy.spatial import cKDTree

    assert isinstance(tree, cKDTree)
    found = 0
    n_chunks = -(-points.shape[0] // _QUERY_CHUNK)
    for start in range(n_chunks):
        d, _ = tree.query(points[start::n_chunks], distance_upper_bound=reach_m)
        found += int(np.isfinite(d).sum())
        if found >= need:
            return True
    return False


def _on_what_is_beneath(
    xy: np.ndarray, low: float, standing: list[int], xy_each: list[np.ndarray], h_each: list[np.ndarray], boxes: _Boxes
) -> bool:
    """Does another object of ``standing`` lie beneath the outline of an object (its in-plane
    points ``xy``, within `_CELL_M` of them), reaching up to within `_HANG_M` of its lowest
    point ``low``? Then it stands on that object where the camera cannot see the contact:
    a box laid across two others (mOSD test47: its bottom 1 to 1.5 cm above their tops,
    their tops hidden under it), though the support is seen between them. The same
    `_HANG_M` that tells hanging from resting on the support tells it from resting on an
    object. ``xy_each``, ``h_each``: every object's points in-plane and their heights."""
    from scipy.spatial import cKDTree

    lo, hi = _lo_hi(xy)
    lo, hi = lo - _CELL_M, hi + _CELL_M
    meet = set(boxes.meet_2d(lo, hi).tolist())
    q2 = [
        _near_box(np.compress(h_each[j] >= low - _HANG_M, xy_each[j], axis=0), lo, hi)
        for j in standing
        if j in meet and boxes.top[j] >= low - _HANG_M
    ]
    near = np.vstack(q2) if q2 else np.zeros((0, 2))
    if not near.shape[0]:
        return False
    # only its points within `_CELL_M` of the others' box can be that near them (twice, for
    # the rounding): the same answer from a smaller tree
    near_lo, near_hi = _lo_hi(near)
    own = _near_box(xy, near_lo - 2 * _CELL_M, near_hi + 2 * _CELL_M)
    if not own.shape[0] or near.shape[0] < _GOES_ON_MIN:  # nothing near, or too little to reach it
        return False
    # (a tree for one query: see _rests_on_another)
    return _reached(cKDTree(own, balanced_tree=False, compact_nodes=False), near, _CELL_M, _GOES_ON_MIN)


def _held_from(p: np.ndarray, out_tree: object, excluded: list[np.ndarray]) -> str:
    """What seen holds up the object ``p`` that hangs above the support, or "" for nothing:
    what lies outside the support's outline (``out_tree``) or one of the segments
    ``excluded``, within `_HOLD_M`. (Cut by the image's border above the support, it was
    excluded as entering from beyond it before.)"""
    from scipy.spatial import cKDTree

    if out_tree is not None:
        assert isinstance(out_tree, cKDTree)
        d, _ = out_tree.query(p, distance_upper_bound=_HOLD_M)
        if np.isfinite(d).any():
            return f"what lies outside the support's outline, {float(d.min()):.3f} m from it"
    lo, hi = _lo_hi(p)
    lo, hi = lo - _HOLD_M, hi + _HOLD_M
    near = [q for q in (_near_box(e, lo, hi) for e in excluded) if q.shape[0]]
    if near:
        tree = cKDTree(np.vstack(near), balanced_tree=False, compact_nodes=False)  # one query: see _rests_on_another
        d, _ = tree.query(p, distance_upper_bound=_HOLD_M)
        if np.isfinite(d).any():
            return f"something excluded {float(d.min()):.3f} m from it"
    return ""


def _far_touched(nearest: np.ndarray, outside_reach: np.ndarray) -> float:
    """How far beyond the outline the part outside it that an object's points touch
    reaches: each touching point counts the part of its ``nearest`` outside point, and the
    reach is the one `_GOES_ON_MIN` of them attain."""
    if nearest.size < _GOES_ON_MIN:
        return float("-inf")
    return float(np.sort(outside_reach[nearest])[-_GOES_ON_MIN])


def at_image_border(indices: list[np.ndarray], shape: tuple[int, int] | None) -> list[np.ndarray] | None:
    """Per object (its points' pixel ``indices`` in a frame of ``shape``), which of them lie
    within `_BORDER_PX` of the image's border; None without a pixel grid."""
    if shape is None:
        return None
    rows, cols = shape
    if not indices:
        return []
    # every object's pixels at once (integers: the same answer per pixel), split back
    every = np.concatenate(indices)
    r, c = np.divmod(every, cols)
    border = (r < _BORDER_PX) | (r >= rows - _BORDER_PX) | (c < _BORDER_PX) | (c >= cols - _BORDER_PX)
    return np.split(border, np.cumsum([idx.size for idx in indices])[:-1])


def at_cloud_border(object_xy: list[np.ndarray], cloud_xy: np.ndarray, border_m: float) -> list[np.ndarray]:
    """Per object (its points in the support's plane, ``object_xy``), which of them lie
    within ``border_m`` of the edge of the cloud's footprint (``cloud_xy``: every point,
    in-plane): an unorganized cloud's `at_image_border`. The footprint's edge is its
    convex hull's (`table.hull_vertices`, tested as the support's own outline is,
    `table.inside_convex` shrunk by ``border_m``): a cloud cropped to a box, or a sensor's
    view, ends in straight lines, while the shadows objects cast (holes in the footprint,
    some open to its edge) lie inside the hull and cut no object off (the footprint's own
    outline, holes filled, took a tall box's back edge, where its shadow reached the
    cloud's far end, for a cut)."""
    from scipy.spatial import QhullError

    if not object_xy:
        return []
    try:
        corners = hull_vertices(cloud_xy)  # counter-clockwise
    except (QhullError, ValueError):  # all points on a line: no footprint to speak of
        return [np.zeros(xy.shape[0], dtype=bool) for xy in object_xy]
    # a footprint of many sides (a round one: thousands) is read through every k-th of
    # its corners, an inscribed polygon: the test's cost stays (points x 256), and what
    # lies between the two is within the arc's sagitta of the edge
    polygon = cloud_xy[corners[:: -(-corners.size // _HULL_MAX_SIDES)]]
    return [~inside_convex(xy, polygon, -border_m) for xy in object_xy]


def support_around(
    indices: list[np.ndarray],
    shape: tuple[int, int],
    state: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
) -> list[tuple[int, int]]:
    """Per segment (its pixel ``indices`` in a frame of ``shape``): (how many pixels of the
    ring around it (the square `_RING_PX` pixels out) in no segment count, how many of
    those are the support's). ``state``: for pixel indices, (do they count: seen, at about
    the support's level (`AROUND_LEVEL_M`); are they the support's)."""
    rows, cols = shape
    in_any = np.zeros(rows * cols, dtype=bool)
    for idx in indices:
        in_any[idx] = True
    in_any_2d = in_any.reshape(rows, cols)
    rings = []
    for idx in indices:
        # the same window and ring as from each pixel's row and column (np.divmod), without
        # them (issue 39: support_around 3.2 -> 2.5 ms on test55 and test57): a pixel's row grows
        # with its index, so the first and last rows are those of the least and greatest
        # index; the columns are those the segment's rows set in a strip of whole rows
        r0 = max(int(idx.min()) // cols - _RING_PX, 0)
        r1 = min(int(idx.max()) // cols + _RING_PX + 1, rows)
        strip = np.zeros((r1 - r0) * cols, dtype=bool)
        strip[idx - r0 * cols] = True
        strip_2d = strip.reshape(r1 - r0, cols)
        used = np.flatnonzero(strip_2d.any(axis=0))
        c0, c1 = max(int(used[0]) - _RING_PX, 0), min(int(used[-1]) + _RING_PX + 1, cols)
        # dilated and in no segment: greater, of bools, is "and not"
        ring = np.greater(dilate_square(strip_2d[:, c0:c1], _RING_PX), in_any_2d[r0:r1, c0:c1])
        # the ring's pixels in the window's row-major order (np.nonzero's), as frame indices
        k = np.flatnonzero(ring)
        width = c1 - c0
        rings.append(k + (k // width) * (cols - width) + (r0 * cols + c0))
    # every ring's pixels in one call of ``state`` (elementwise: the same answer per pixel)
    if not rings:
        return []
    counts, support = state(np.concatenate(rings))
    ends = np.cumsum([ring.size for ring in rings])[:-1]
    return [
        (int(n.sum()), int((n & s).sum())) for n, s in zip(np.split(counts, ends), np.split(support, ends), strict=True)
    ]


def _enters_over_border(border: np.ndarray, h: np.ndarray, rests: float, xy: np.ndarray, edge: str) -> str:
    """Why an object (its points' heights ``h``, in-plane ``xy``, which are at the image's
    border ``border``; ``edge``: what that border is) enters from beyond it above the support,
    or "" when it does not."""
    from scipy.spatial import cKDTree

    n_border = int(border.sum())
    high = border & (h > rests + _HANG_M)
    n_high = int(high.sum())
    # cut above the support: at least `_GOES_ON_MIN` points, and most of its cut
    if n_high < _GOES_ON_MIN or 2 * n_high < n_border:
        return ""
    resting = h <= rests
    if resting.any():
        # (a tree for one query: see _rests_on_another)
        d, _ = cKDTree(xy[resting], balanced_tree=False, compact_nodes=False).query(xy[high])
        apart = float(np.median(d))
        if apart <= _APART_M:
            return ""
        where = f"{apart:.3f} m from where it comes down to the support"
    else:
        where = "resting nowhere on the support"
    return (
        f"reaches in from beyond {edge} above the support ({n_high} of its points at the border "
        f"more than {_HANG_M:.2f} m above it, {where}): an arm, a hand, a cable"
    )


def _sliver(border: np.ndarray, edge: str) -> str:
    """Why a segment (which of its points are at the view's border ``border``; ``edge``:
    what that border is) is a sliver of something mostly out of view (`_SLIVER_SHARE`),
    or "" when it is not."""
    n, n_border = border.size, int(np.count_nonzero(border))
    if n_border < _GOES_ON_MIN or n_border < _SLIVER_SHARE * n:
        return ""
    return (
        f"mostly out of view: {n_border} of its {n} points lie at {edge}: a sliver of something beyond the view, "
        "too little of it seen to stand for an object"
    )


def _percentiles(values: np.ndarray, percents: tuple[float, ...]) -> list[float]:
    """``np.percentile(values, percents)`` of finite 1-D ``values``: its linear rule, the
    same arithmetic on the same order statistics (the same floats), from one partition
    instead of its general machinery (most of its time on a segment's few thousand
    points, and it runs several times for every segment)."""
    n = values.shape[0]
    virtual = [(n - 1) * (p / 100) for p in percents]  # NumPy's virtual index, in float64 as there
    kth = sorted({i for v in virtual if v < n - 1 for i in (math.floor(v), math.floor(v) + 1)})
    part = np.partition(values, kth) if kth else values
    out = []
    for v in virtual:
        if v >= n - 1:
            out.append(float(values.max()))
            continue
        below = math.floor(v)
        lo, hi = float(part[below]), float(part[below + 1])
        g = v - below
        step = hi - lo
        # NumPy's _lerp: from the lower value below the middle, from the upper one above
        out.append(hi - step * (1 - g) if g >= 0.5 else lo + step * g)
    return out


def _median(values: np.ndarray) -> float:
    """``np.median`` of finite 1-D ``values`` (not empty): the middle order statistic, or
    the mean of the two middle ones, as NumPy takes them, from one partition."""
    n = values.shape[0]
    half = n // 2
    if n % 2:
        return float(np.partition(values, half)[half])
    part = np.partition(values, (half - 1, half))
    return float((part[half - 1] + part[half]) / 2)


def _faces(
    xy_each: list[np.ndarray], h_each: list[np.ndarray], ks: list[int]
) -> dict[int, tuple[np.ndarray, np.ndarray, float, float, float]]:
    """The in-plane footprints ``xy_each[k]`` of the segments ``ks`` (heights ``h_each[k]``)
    that are faces, by segment: (its middle, the unit normal of its footprint's line, its
    thickness across that line, its length along it, its height); percentiles, not
    extremes, so a few stray points do not count. A segment thicker than a face
    (`_FACE_THIN_M`) is none: neither a wall nor a piece of one.

    The footprints' (2, 2) scatter matrices are decomposed in one call for all segments:
    NumPy's eigh runs LAPACK on each matrix of a stack in turn, so each one's vectors are
    those of a call of its own (a call's overhead was most of the time, per segment)."""
    if not ks:
        return {}
    mids = [row_mean(xy_each[k]) for k in ks]
    cs = [xy_each[k] - mid for k, mid in zip(ks, mids, strict=True)]
    _, vecs_each = np.linalg.eigh(np.stack([c.T @ c for c in cs]))
    faces = {}
    for k, mid, c, vecs in zip(ks, mids, cs, vecs_each, strict=True):
        across = c @ vecs[:, 0]
        if _surely_wider(across, _FACE_THIN_M):
            continue  # no face: the percentiles' partition is not needed to tell
        across_5, across_95 = _percentiles(across, (5, 95))
        thick = float(across_95 - across_5)
        if thick > _FACE_THIN_M:
            continue
        along_2, along_98 = _percentiles(c @ vecs[:, 1], (2, 98))
        h_2, h_98 = _percentiles(h_each[k], (2, 98))
        faces[k] = (mid, vecs[:, 0], thick, float(along_98 - along_2), float(h_98 - h_2))
    return faces


# `_surely_wider`: a margin far above the rounding of a percentile's interpolation and of
# its difference (the values are metres, under one: ulps of 1e-16)
_WIDER_SLACK_M = 1e-6


def _surely_wider(values: np.ndarray, width: float) -> bool:
    """Is the spread of the 5th to the 95th percentile of centred ``values`` (`_percentiles`,
    at least two) more than ``width``, told by two counts: at least the two order statistics
    the 5th percentile lies between at or below -(``width`` / 2 + `_WIDER_SLACK_M`), and the
    two of the 95th at or above +that. False says nothing (the partition must tell). Most
    segments are no face, thicker than one on either side of their middle: their
    percentiles were most of `_faces`' time (issue 39: _faces 2.3 -> 2.0 ms on test55 and
    test57)."""
    n = values.shape[0]
    half = width / 2 + _WIDER_SLACK_M
    low = math.floor((n - 1) * (5 / 100))  # the virtual indices as `_percentiles` takes them
    high = math.floor((n - 1) * (95 / 100))
    if high + 1 >= n:
        return False
    return int(np.count_nonzero(values <= -half)) >= low + 2 and int(np.count_nonzero(values >= half)) >= n - high


def _along_the_edge(mid: np.ndarray, normal: np.ndarray, length: float, support_xy: np.ndarray) -> float:
    """How much of the support's extent along a face's line (its middle ``mid``, the unit
    ``normal`` of its line, its ``length``) the face spans, where the support (its in-plane
    points ``support_xy``) does not go on beyond the line (`_WALL_BEYOND_SHARE`); 0 where it does."""
    if not support_xy.shape[0]:
        return 0.0
    c = support_xy - mid
    out = c @ normal
    if float(np.mean(out)) > 0:  # the normal away from the support's middle
        # (negated: the same bits as the product with the negated normal, whose sums
        # round alike either side of zero)
        normal = -normal
        out = -out
    along = c @ np.array([-normal[1], normal[0]])
    over = np.abs(along) <= length / 2
    beyond = int(np.count_nonzero(over & (out > _FACE_THIN_M)))
    if beyond >= _WALL_BEYOND_SHARE * max(1, int(np.count_nonzero(over))):
        return 0.0  # decided before the extent, whose percentiles are most of the time
    # np.percentile's values at 2 and 98 from one partition (`_percentiles`)
    along_2, along_98 = _percentiles(along, (2, 98))
    extent = float(along_98 - along_2)
    if extent <= 0:
        return 0.0
    return length / extent


def _walls(
    xy_each: list[np.ndarray], h_each: list[np.ndarray], verdicts: dict[int, str], support_xy: np.ndarray
) -> dict[int, tuple[np.ndarray, np.ndarray, float, float, float]]:
    """Add to ``verdicts`` the walls among the objects (each one's in-plane points
    ``xy_each``, heights ``h_each``; `_WALL_FACE_M`, `_WALL_SPAN`: ``support_xy``, the
    support's in-plane points), and the flat pieces lying in a wall's face (the
    segmentation cut a wall's foot or its trim apart from it: thin, and all within
    `_FACE_THIN_M` of the wall's line). Returns the faces found (`_faces`), by object."""
    faces = _faces(
        xy_each, h_each, [k for k, xy in enumerate(xy_each) if k not in verdicts and xy.shape[0] >= _GOES_ON_MIN]
    )
    walls = []
    for k, (mid, normal, thick, length, tall) in faces.items():
        size = float(np.hypot(length, tall))
        # upright: taller than `_UPRIGHT` times its thickness (a strip lying flat is not)
        if tall < _UPRIGHT * thick:
            continue
        if size >= _WALL_FACE_M:
            verdicts[k] = (
                f"a wall: one flat face {length:.2f} m long and {tall:.2f} m high on the support ({thick * 100:.1f} cm "
                f"across), larger than any object ({_WALL_FACE_M:.2f} m): a wall, a cupboard's side, a bin's wall"
            )
            walls.append((mid, normal))
            continue
        span = _along_the_edge(mid, normal, length, support_xy)
        if span >= _WALL_SPAN:
            verdicts[k] = (
                f"a wall: one flat face {length:.2f} m long and {tall:.2f} m high ({thick * 100:.1f} cm across) rising "
                f"at the support's edge along {100 * span:.0f} % of it, no support seen beyond it: a bin's wall, a "
                "wall, a cupboard's side"
            )
            walls.append((mid, normal))
    for k, (_, _, thick, _, tall) in faces.items():
        if k in verdicts:
            continue
        # upright, or a strip of the face standing clear of the support's level (what lies
        # at a wall's foot, a pen, a marker, is lower)
        if tall < _UPRIGHT * thick and _percentiles(h_each[k], (98,))[0] < _PIECE_TOP_M:
            continue
        for mid, normal in walls:
            off = float(np.percentile(np.abs((xy_each[k] - mid) @ normal), 95))
            if off <= _FACE_THIN_M:
                verdicts[k] = (
                    f"part of a wall: a flat piece lying in a wall's face (95 % of it within {off * 100:.1f} cm of "
                    "its line)"
                )
                break
    return faces


def _veil(
    p: np.ndarray,
    h: np.ndarray,
    camera_h: float,
    height: Callable[[np.ndarray], np.ndarray],
    rng: np.ndarray | None = None,
) -> str:
    """Why a segment (its points ``p`` in the camera's frame, heights ``h`` above the
    support; the camera ``camera_h`` above it, ``height`` as for `not_standing`; ``rng``:
    its points' ranges, when known) is a veil of mixed pixels lying along the camera's
    rays, or "" (`_VEIL_ALONG`, `_VEIL_FALLS`, `_VEIL_FALLS_MAX`, `_VEIL_RISE_M`).

    Every test must hold; the cheapest goes first (its far end `_VEIL_RISE_M` lower than
    its near end: a segment standing on the support is seen from above, its near face no
    higher than its top behind it), and most segments stop there. The order changes no
    result: each value is what it would be in any order."""
    if rng is None:
        rng = np.linalg.norm(p, axis=1)
    # its far end lower than its near end as the rays fall towards the support
    r10, r90 = _percentiles(rng, (10, 90))
    near, far = rng <= r10, rng >= r90
    drop = _median(np.compress(near, h)) - _median(np.compress(far, h))
    if drop < _VEIL_RISE_M:
        return ""
    rays = p / np.maximum(rng, 1e-12)[:, None]
    mean = row_mean(rays)
    mean /= np.linalg.norm(mean)
    falls = camera_h - float(height(mean[None, :])[0])  # the mean ray's fall per metre (sine of its elevation)
    ray_drop = (_median(np.compress(far, rng)) - _median(np.compress(near, rng))) * falls
    if drop < _VEIL_FALLS * ray_drop or drop > _VEIL_FALLS_MAX * ray_drop:
        return ""
    # two directions across the mean ray: where the points are in the image, at their range
    seed = np.eye(3)[int(np.argmin(np.abs(mean)))]
    u = np.cross(mean, seed)
    u /= np.linalg.norm(u)
    across = np.column_stack([rays @ u, rays @ np.cross(mean, u)]) * _median(rng)
    c = across - row_mean(across)
    _, vecs = np.linalg.eigh(c.T @ c)
    lo, hi = _percentiles(c @ vecs[:, 0], (5, 95))
    narrow = float(hi - lo)
    r5, r95 = _percentiles(rng, (5, 95))
    deep = float(r95 - r5)
    if deep < _VEIL_ALONG * narrow:
        return ""
    return (
        f"a veil of mixed pixels: {1000 * deep:.0f} mm deep along the camera's rays, {1000 * narrow:.0f} mm across "
        f"them (at least {_VEIL_ALONG:g} times as deep), falling {1000 * drop:.0f} mm from its near end to its far "
        f"end as the rays do ({1000 * ray_drop:.0f} mm): depths the sensor interpolated between a near edge and the "
        "background behind it, no surface"
    )


def _beneath_below(
    faces: dict[int, tuple[np.ndarray, np.ndarray, float, float, float]],
    xy_each: list[np.ndarray],
    verdicts: dict[int, str],
    below_cells: Callable[[], np.ndarray],
) -> None:
    """Add to ``verdicts`` the upright faces (``faces``, by object; in-plane points
    ``xy_each``) whose surface goes on below the support's level beneath them:
    `_BENEATH_SHARE` of their footprint's cells hold points between `_BELOW_M` and
    `_BELOW_DEEP_M` below it (``below_cells``: those cells, `_cells`)."""
    for k, (_, _, thick, _, tall) in faces.items():
        if k in verdicts or tall < _BELOW_UPRIGHT * thick:
            continue
        share = _over_below(_cells(xy_each[k]), below_cells, _BENEATH_SHARE)
        if share is not None:
            verdicts[k] = (
                f"stands beyond the support's edge: an upright face {tall:.2f} m high that goes on below the "
                f"support's level beneath {100 * share:.0f} % of it ({1000 * _BELOW_M:.0f} to "
                f"{1000 * _BELOW_DEEP_M:.0f} mm below): a chair's back, a board, furniture standing on the floor"
            )


def _over_below(cells: np.ndarray, below_cells: Callable[[], np.ndarray], least: float) -> float | None:
    """The share of ``cells`` (`_cells` keys, at least `_GOES_ON_MIN` of them) that hold
    points below the support (``below_cells``), when it is ``least`` or more; else None."""
    if cells.size < _GOES_ON_MIN:
        return None
    under = int(np.isin(cells, below_cells(), assume_unique=True).sum())
    return under / cells.size if under >= least * cells.size else None


def _foot_below(
    xy_each: list[np.ndarray],
    h_each: list[np.ndarray],
    rests: list[float],
    verdicts: dict[int, str],
    below_cells: Callable[[], np.ndarray],
) -> None:
    """Add to ``verdicts`` the segments whose foot goes on below the support's level: of
    the cells of their points at resting height (``h_each[k]`` at most ``rests[k]``, at
    least `_GOES_ON_MIN` cells), `_FOOT_BELOW_SHARE` hold points `_BELOW_M` to
    `_BELOW_DEEP_M` below the support (``below_cells``)."""
    for k, (xy, h) in enumerate(zip(xy_each, h_each, strict=True)):
        if k in verdicts:
            continue
        share = _over_below(_cells(np.compress(h <= rests[k], xy, axis=0)), below_cells, _FOOT_BELOW_SHARE)
        if share is not None:
            verdicts[k] = (
                f"stands beyond the support's edge: its foot goes on below the support's level beneath "
                f"{100 * share:.0f} % of it ({1000 * _BELOW_M:.0f} to {1000 * _BELOW_DEEP_M:.0f} mm "
                "below): furniture standing on the floor (a shelf's side boards)"
            )


@dataclass(frozen=True)
class Verdict:
    index: int  # into the objects
    reason: str


def _cells(xy: np.ndarray) -> np.ndarray:
    """The `_CELL_M` cells ``xy`` falls in, as sorted unique packed keys: column and row in
    one int64 (a 1-D unique sorts several times faster than rows of two)."""
    c = np.floor(xy / _CELL_M).astype(np.int64)
    if c.shape[0]:
        # cells over a span not much larger than their number (the support's sample: 50k
        # points): a mark per cell of the span, read back in order, gives the same sorted
        # keys without a sort (the packing keeps the (column, row) order)
        lo0, hi0, lo1, hi1 = (int(f(c[:, j])) for j in (0, 1) for f in (np.min, np.max))
        span1 = hi1 - lo1 + 1
        if (hi0 - lo0 + 1) * span1 <= 4 * c.shape[0] + 1024 and -(1 << 31) <= lo1 and hi1 < (1 << 31):
            seen = np.zeros((hi0 - lo0 + 1) * span1, dtype=bool)
            seen[(c[:, 0] - lo0) * span1 + (c[:, 1] - lo1)] = True
            keys = np.flatnonzero(seen)
            return (keys // span1 + lo0) * (1 << 32) + (keys % span1 + lo1 + (1 << 31))
    return np.unique(c[:, 0] * (1 << 32) + (c[:, 1] + (1 << 31)))


def not_standing(
    objects: list[np.ndarray],
    outside: np.ndarray,
    outside_below: np.ndarray,
    support_xy: np.ndarray,
    height: Callable[[np.ndarray], np.ndarray],
    to_2d: Callable[[np.ndarray], np.ndarray],
    inside_side: Callable[[np.ndarray], np.ndarray],
    rests_m: Callable[[np.ndarray], float],
    outside_reach: np.ndarray | None = None,
    at_border: list[np.ndarray] | None = None,
    around: list[tuple[int, int]] | None = None,
    inside_deep: Callable[[np.ndarray], np.ndarray] | None = None,
    below: np.ndarray | None = None,
    off_colour: list[float] | None = None,
    border_edge: str = "the image's border",
) -> list[Verdict]:
    """Which of ``objects`` (each an (M, 3) array of its points) do not stand on the
    support, and why.

    ``outside``: points above the support's plane beyond the prism's side,
    ``outside_below``: those below it (only those within twice `_GOES_ON_M` of the
    objects' box are read: `near_the_objects`); ``support_xy``:
    the support's own points, in-plane (the caller has them so); ``height``: height above
    its plane; ``to_2d``: in-plane coordinates; ``inside_side``: for in-plane points (N, 2),
    (N,) bool, those farther than `_BORDER_M` inside the prism's side; ``rests_m``: for an object's points, the height below which it
    rests on the support (grows with range); ``outside_reach``: for each of ``outside``,
    how far its part reaches beyond the outline (`reach_beyond`; None: not known);
    ``at_border``: per object, (M,) bool, its points at the image's border, or at an
    unorganized cloud's edge (`at_cloud_border`), ``border_edge`` saying which (None: not
    known); ``around``: per object, `support_around`'s counts (None:
    no pixel grid); ``inside_deep``: for in-plane points (N, 2), (N,) bool, those farther
    than `DEEP_INSIDE_M` inside the support's outline (None: not known, every object may stand
    beyond the edge); ``below``: the points below the support's level, not the support's,
    inside the outline or not (None: not known, `_beneath_below` is not decided);
    ``off_colour``: per object, the share of its pixels whose colour differs from the
    support's (None: no colour, `_fringe` is not decided).
    """
    from scipy.spatial import cKDTree

    if not objects:
        return []
    # every object's points at once (``owner``: whose; ``bounds``: where each one's rows
    # start): the per-point quantities once, split back per object
    sizes = [p.shape[0] for p in objects]
    bounds = np.concatenate([[0], np.cumsum(sizes)])
    every = np.vstack(objects)
    h_all, xy_all = height(every), to_2d(every)
    h_each, xy_each = np.split(h_all, bounds[1:-1]), np.split(xy_all, bounds[1:-1])
    lows = [float(h.min()) for h in h_each]
    rests = [rests_m(p) for p in objects]
    # the points on the prism's side (not farther than `_BORDER_M` inside it), and for
    # each, whether it touches what lies outside above the support, below it
    edge_rows = np.flatnonzero(~inside_side(xy_all))  # in-plane: projected once, above
    edge_bounds = np.searchsorted(edge_rows, bounds)
    edge = np.take(every, edge_rows, axis=0)  # take: faster than a[idx]
    out_tree = cKDTree(outside) if outside.shape[0] else None
    # the nearest outside point within `_GOES_ON_M` (-1: none): a nearest-neighbour query
    # stops at the first point in reach, where counting every point in reach (dense
    # outside points) costs ten times more
    nearest_out = np.full(edge_rows.size, -1, dtype=np.int64)
    touches_below = np.zeros(edge_rows.size, dtype=bool)
    if out_tree is not None and edge_rows.size:
        d, j = out_tree.query(edge, distance_upper_bound=_GOES_ON_M)
        nearest_out = np.where(np.isfinite(d), j, -1)
    if outside_below.shape[0] and edge_rows.size:
        # (only a flat object's points come this near: a segment of the prism lies more than
        # the prism's floor above the plane, these more than as far below it, 2 cm apart at
        # least; what goes on below beneath a face is `_beneath_below`'s)
        # A tree of only the points below within the edge points' box grown by twice the
        # reach (`_near_box`): the same answers as one of them all, which cost a third of
        # a cluttered frame's exclusion to build (a far floor's hundred thousand points)
        lo, hi = _lo_hi(edge)
        near_below = _near_box(outside_below, lo - 2 * _GOES_ON_M, hi + 2 * _GOES_ON_M)
        if near_below.shape[0]:
            touches_below = np.isfinite(cKDTree(near_below).query(edge, distance_upper_bound=_GOES_ON_M)[0])
    verdicts: dict[int, str] = {}
    for k in range(len(objects)):
        e0, e1 = edge_bounds[k], edge_bounds[k + 1]
        near = nearest_out[e0:e1] >= 0
        goes_on = int(near.sum())
        if out_tree is not None and goes_on >= _GOES_ON_MIN:
            # it crosses the side above the support: an object standing at the side (cut
            # by the hull where the table behind it is hidden) crosses it from the bottom
            if float(h_all[edge_rows[e0:e1][near]].min()) > rests[k] + _REACH_ABOVE_M:
                verdicts[k] = (
                    f"reaches in from beyond the support's outline ({goes_on} of its points "
                    "touch points above the support outside it): an arm, a hand, a cable"
                )
                continue
            if outside_reach is not None:
                far = _far_touched(nearest_out[e0:e1][near], outside_reach)
                if far >= _FAR_BEYOND_M:
                    verdicts[k] = (
                        f"stands beyond the support's edge: it is one with something outside the support's "
                        f"outline that goes on {far:.2f} m beyond it: a desk, a shelf, furniture behind"
                    )
                    continue
        resting = h_each[k] <= rests[k]
        n_rest = int(resting.sum())
        n_in = n_rest - int(resting[edge_rows[e0:e1] - bounds[k]].sum())
        if n_rest >= _GOES_ON_MIN and n_in < _FOOT_INSIDE_SHARE * n_rest:
            verdicts[k] = (
                f"stands beyond the support's edge: it comes down to the support's level only beyond its outline "
                f"({n_in} of its {n_rest} points at resting height within it): a chair, a box on the floor, "
                "furniture at the edge"
            )
            continue
        if at_border is not None:
            why = _enters_over_border(at_border[k], h_each[k], rests[k], xy_each[k], border_edge) or _sliver(
                at_border[k], border_edge
            )
            if why:
                verdicts[k] = why
                continue
        down = int(touches_below[e0:e1].sum())
        if down >= _GOES_ON_MIN:
            verdicts[k] = (
                f"stands beyond the support's edge: it goes on below the support's level outside its "
                f"outline ({down} of its points touch such points): a desk, a shelf, furniture behind"
            )
    faces = _walls(xy_each, h_each, verdicts, support_xy)
    if below is not None:
        below_once: list[np.ndarray] = []

        def below_cells() -> np.ndarray:
            """The cells of the points `_BELOW_M` to `_BELOW_DEEP_M` below the support, the first time."""
            if not below_once:
                assert below is not None  # checked above
                hb = height(below)
                near = np.compress((hb <= -_BELOW_M) & (hb >= -_BELOW_DEEP_M), below, axis=0)
                below_once.append(_cells(to_2d(near)) if near.shape[0] else np.zeros(0, dtype=np.int64))
            return below_once[0]

        _beneath_below(faces, xy_each, verdicts, below_cells)
        _foot_below(xy_each, h_each, rests, verdicts, below_cells)
    for k, (n_free, n_support) in enumerate(around or ()):
        if k in verdicts or n_free < _RING_MIN_PX or n_support >= _RING_SUPPORT_SHARE * n_free:
            continue
        if inside_deep is None or not bool(np.all(inside_deep(xy_each[k]))):
            verdicts[k] = (
                f"stands beyond the support's edge: the support is seen nowhere around it ({n_support} of the "
                f"{n_free} pixels seen around it): another surface at nearly the support's height, furniture behind"
            )
    # hangs: decided after the two rules above, so what lies beneath counts only when it
    # is itself an object (not an arm's or a shelf's part), whatever the objects' order
    standing = [k for k in range(len(objects)) if k not in verdicts]
    lifted = [k for k in standing if lows[k] > rests[k] + _HANG_M] if support_xy.shape[0] else []
    if lifted:
        support_cells = _cells(support_xy)
        boxes = _Boxes(
            np.minimum.reduceat(every, bounds[:-1], axis=0),
            np.maximum.reduceat(every, bounds[:-1], axis=0),
            np.minimum.reduceat(xy_all, bounds[:-1], axis=0),
            np.maximum.reduceat(xy_all, bounds[:-1], axis=0),
            np.maximum.reduceat(h_all, bounds[:-1]),
        )
    hanging: list[tuple[int, float]] = []  # (object, share of the support seen beneath it)
    for k in lifted:
        if _rests_on_another(k, objects, h_each, lows[k], boxes):
            continue
        if _on_what_is_beneath(xy_each[k], lows[k], [j for j in standing if j != k], xy_each, h_each, boxes):
            continue
        own = _cells(xy_each[k])
        seen = int(np.isin(own, support_cells, assume_unique=True).sum()) / max(1, own.size)
        if seen >= _SEEN_UNDER_SHARE:
            hanging.append((k, seen))
    # held up by what is seen, or the top of what the sensor does not see standing there;
    # until nothing more is found (a lamp's shade held by its post, held from the border)
    changed = True
    while changed:
        changed = False
        for k, seen in hanging:
            if k in verdicts:
                continue
            held = _held_from(objects[k], out_tree, [objects[j] for j in sorted(verdicts)])
            if held:
                verdicts[k] = (
                    f"hangs above the support: its lowest point {lows[k]:.3f} m above it, the support seen "
                    f"beneath {100 * seen:.0f} % of it, held by {held}"
                )
                changed = True
    # what stands on an excluded thing, until nothing more is found
    changed = True
    while changed:
        changed = False
        gone = [k for k in verdicts]
        # only what rests nowhere on the support can stand on something excluded
        if not gone or all(k in verdicts or lows[k] <= rests[k] for k in range(len(objects))):
            break
        tree = cKDTree(np.vstack([objects[k] for k in gone]))
        gone_owner = np.concatenate([np.full(objects[k].shape[0], k) for k in gone])
        reaching = [k for k in gone if verdicts[k].startswith("reaches in")]
        reach_tree = cKDTree(np.vstack([objects[k] for k in reaching])) if reaching else None
        for k, p in enumerate(objects):
            if k in verdicts or lows[k] <= rests[k]:
                continue
            h = h_each[k]
            # the rest of an arm the segmentation cut apart: it rests nowhere on the
            # support and is joined to what reaches in more than `_REACH_ABOVE_M` above
            # it (an object the arm touches stands on the support; the gripper's tip at
            # the table is lower than that)
            if reach_tree is not None:
                high = p[h > rests[k] + _REACH_ABOVE_M]
                if high.shape[0]:
                    d, _ = reach_tree.query(high, distance_upper_bound=_TOUCH_M)
                    joined = int(np.isfinite(d).sum())
                    if joined >= _GOES_ON_MIN:
                        verdicts[k] = (
                            f"part of what reaches in ({joined} of its points joined to it more than "
                            f"{_REACH_ABOVE_M:.2f} m above the support, its lowest {lows[k]:.3f} m above it)"
                        )
                        changed = True
                        continue
            if lows[k] <= rests[k] + _HANG_M:
                continue
            bottom = p[h <= lows[k] + _TOUCH_M]
            d, j = tree.query(bottom, distance_upper_bound=_TOUCH_M)
            hit = np.isfinite(d)
            if hit.sum() >= 5:
                under = int(np.bincount(gone_owner[j[hit]]).argmax())
                what = verdicts[under].split(":")[0].split(" (")[0]
                verdicts[k] = f"stands on something excluded (what {what}), {lows[k]:.3f} m above the support"
                changed = True
    # veils, last: they hold up nothing and carry nothing in the rules above
    camera_h = float(height(np.zeros((1, 3)))[0])
    if camera_h >= _CAMERA_ABOVE_M:
        # every point's range at once (row by row, as for one segment's points):
        # np.linalg.norm(every, axis=1)'s sums in its order, a fifth of its time
        x, y, z = every[:, 0], every[:, 1], every[:, 2]
        rng_each = np.split(np.sqrt((x * x + y * y) + z * z), bounds[1:-1])
        for k, p in enumerate(objects):
            if k not in verdicts and p.shape[0] >= _GOES_ON_MIN:
                why = _veil(p, h_each[k], camera_h, height, rng_each[k])
                if why:
                    verdicts[k] = why
    if off_colour is not None:
        _fringe(objects, h_each, off_colour, verdicts)
    return [Verdict(k, why) for k, why in sorted(verdicts.items())]


def _fringe(
    objects: list[np.ndarray], h_each: list[np.ndarray], off_colour: list[float], verdicts: dict[int, str]
) -> None:
    """Add to ``verdicts`` the fringes of the support's colour against an object (module
    doc; ``off_colour`` per object as for `not_standing`): decided among the objects not
    excluded before, each against those (a fringe holds up nothing)."""
    from scipy.spatial import cKDTree

    standing = [k for k in range(len(objects)) if k not in verdicts]
    # only a segment of the support's colour is judged (most frames have none): the
    # medians of the others' heights are worked out then, not for every segment first
    judged = [k for k in standing if off_colour[k] <= _FRINGE_OFF_SHARE and objects[k].shape[0] >= _GOES_ON_MIN]
    medians = {k: _median(h_each[k]) for k in standing} if judged else {}
    found: dict[int, str] = {}
    for k in judged:
        top = _percentiles(h_each[k], (95,))[0]
        taller = [j for j in standing if j != k and medians[j] >= top + _FRINGE_BELOW_M]
        if not taller:
            continue
        tree = cKDTree(objects[k])
        # only the points of the taller one within `_TOUCH_M` of this one's box can touch
        # it (twice, for the rounding): the same count from a query of those alone (a tall
        # object's every point cost most of the rule)
        lo, hi = _lo_hi(objects[k])
        lo, hi = lo - 2 * _TOUCH_M, hi + 2 * _TOUCH_M
        for j in taller:
            d, _ = tree.query(_near_box(objects[j], lo, hi), distance_upper_bound=_TOUCH_M)
            touching = int(np.isfinite(d).sum())
            if touching >= _GOES_ON_MIN:
                found[k] = (
                    f"a fringe of the support's colour: {100 * off_colour[k]:.1f} % of its pixels differ from the "
                    f"support's colour, its top {top:.3f} m above the support, and {touching} points of an object "
                    f"{medians[j]:.3f} m tall (median) touch it: that object's depth smeared over the support beside "
                    "it (the colour image shows the support there), no object"
                )
                break
    verdicts.update(found)
