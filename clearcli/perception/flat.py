"""Stage 4' (ours, not in the thesis): objects lying flat on the table, found by colour.

A marker, a pen or a fork lying on the table stands 1-2 cm high at most; a RealSense
or a Kinect a metre away smooths it to 2-8 mm, inside the table's own noise (its
heights spread 2-3 mm, and 1 % of its points lie 9 mm off the plane). The prism's lower
bound (``prism_min_height_m``, 1 cm and more with range) cannot take it without taking
the table's noise with it. Depth alone cannot tell; colour can, where the frame has it:

1. The table's colour: the median CIELAB colour of the table's points; a pixel of the
   table (or a point above it left over by segmentation: too small to be an object on
   its own; or one under the prism's floor and above the table's band, where a
   notebook lying flat keeps much of its top) differs when its colour is more than
   ``flat_min_color_delta`` (CIE76 dE) from it, and more than three times the table's
   own median difference (a wood grain, a cloth's pattern).
2. Such pixels, joined over 8 neighbours, are a candidate when the candidate keeps
   ``_CLEARANCE_PX`` pixels away from every object found (a candidate touching an
   object is its foot, its shadow or its reflection on the table), or all but
   ``_NEAR_MAX_SHARE`` of it does: then it is judged on those pixels alone (a marker
   lying against a box); or, when it is no object's foot (5.), at most
   ``_NEAR_NOBODY_MAX_SHARE`` of it does and the table shows round at least
   ``_NOBODY_RING_TABLE_MIN`` of its ring (a notebook lying beside a box; a bowl's floor
   has the bowl's wall round it).
3. A candidate is an object when it stands above the table around it: its median height
   is at least ``flat_min_relief_m`` above the median of a ring of table pixels around
   it (3 to 8 pixels out). A print, a stain or a shadow has no relief (on the choose
   frames: -5 to +0.9 mm); a marker has (2.2 mm for a black marker a metre away, more
   for nearer or thicker ones). The table round it returns depth: where a fifth of the
   ring has none, the candidate is the table seen through a transparent thing lying on
   it (a clear cup: the sensor loses the rays it bends), its colour the glass's, its
   depth the table's: no flat object. Its visible area must lie between min_object_area_m2
   and ``flat_max_area_m2`` (a flat object, not a tablecloth's border).
4. Its points are where its depth is: the pixels within `_GROW_PX` of the candidate (none
   within `_CLEARANCE_PX` of an object) that stand ``grow_min_m`` or more above the ring,
   joined over 8 neighbours to such a pixel of the candidate. A RealSense's depth is
   registered a few pixels beside its colour; the colour's pixels off the depth are the
   table's points, and the marker's raised points lie beside its colour. When the
   raised pixels are under half or over twice the candidate's (a far marker smoothed flat;
   a larger thing's foot rising round it), the candidate keeps its colour's pixels.
   Whether it is an object at all is judged on its colour's pixels (3.).
5. A candidate too near an object (2.) that touches it, has its colour (`_FOOT_MAX_DE`
   from the median of the object's pixels beside it, or of all of them), and no other
   object's among those it touches, and stands up from the table round it (3.'s
   relief) is that object's foot (a pen's lying against a box of another colour is the
   pen's; one between two objects of its colour is neither's): the part of a box or a
   notebook a centimetre or two high that the prism's lower bound cut off. It joins the
   object, but only its points within ``flat_foot_reach_m`` (across the table) of the
   object's own (`within_reach`): the foot stands under the faces seen above it, and
   its points farther out are depth mixed at the lower edge. A foot of half the
   object's points or more, of an object lying low, joins whole (segment.py,
   `_WHOLE_FOOT_RATIO`, `_FLAT_TOP_M`): the object is then a thing lying flat whose top
   the prism kept only a speckle of, the highest of its noisy points, and that speckle
   is no outline of it.

Organized frames with colour only: the ring and the joining need the pixel grid. On
the 45 mOSD learn frames no candidate far from the objects exists; results there are
unchanged.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from clearcli.perception.raster import boxes, dilate_square, label_8

# a candidate keeps this far (pixels) from every object found
_CLEARANCE_PX = 6
# ... or is judged on its pixels beyond that when they are all but this share of it: a
# marker lying against an object (uois_image_0006's green one, 5 % of its pixels within
# reach of a container) is one, an object's foot or shadow beside it (uois_image_0000's
# bowls, gqcnn_primesense_0's clamp: 17-34 %) is not
_NEAR_MAX_SHARE = 0.1
# and it shows at least this many times the smallest object's area beyond the clearance:
# the markers 3.2 times; gqcnn_phoxi_dexnet4_0 has a patch beside an object at 0.98-1.0
# times, which a micrometre flipped
_NEAR_MIN_AREA_FACTOR = 2.0
# ... and a candidate more of which lies near an object, but that is no object's foot
# (`_foot_of`), is judged as one lying apart when at most this share of it lies near
# objects and the table (no candidate's) fills at least `_NOBODY_RING_TABLE_MIN` of its
# ring: thin_flat's notebooks and pens beside a box on a RealSense's 640 x 360 working
# grid (1280 x 720 read every other pixel, resolution.py) lie 10-44 % near and show the
# table round 64-84 % of their ring; the floor of uois_image_0002's white bowl, 30 %
# near, 15 % (its wall round it). Feet and shadows beside their object lie 17-34 % near
# too (uois_image_0000's bowls, gqcnn_primesense_0's clamp) and stay out by the ring's
# table, their relief or their area, as every other such candidate of the choose part,
# mOSD and the fixtures (their objects unchanged by the rule)
_NEAR_NOBODY_MAX_SHARE = 0.5
_NOBODY_RING_TABLE_MIN = 0.5
# a candidate touching an object (within this many pixels), of that object's colour
# (median CIELAB within this dE of its median) and of no other's it touches, and standing
# up from the table round it is that object's foot below the prism: thin_flat's
# notebooks and boxes 0-8.2 apart, a colour_split_delta (25) apart is two objects
_FOOT_TOUCH_PX = 2
_FOOT_MAX_DE = 15.0
# ... its colour judged against the object's pixels within this many of it (the face
# just above the foot, in the same light) or against all its pixels: a box's lower
# part, in the table's shade, is darker than the box (mOSD learn7's foot: 13.2 dE from
# its box's median on the table's band, 17.6 with the layer under the prism's floor,
# 2.0 from the box's pixels beside it); a foot beside a print on the box's lower edge
# has the box's colour but not the print's (test46: its box lost a foot of 903 points
# judged on the pixels beside it alone). mOSD mean IoU 0.9551 -> 0.9570 (stop 62)
_FOOT_SIDE_PX = 6
# a piece of a foot candidate of another colour (`_other_colour`): its pixels each at
# least this far from the foot's colour and their median too is no part of the foot but
# a candidate of its own. colors._PART_DE's 40: the parts of one object differ by up to
# 26.7 dE on the mOSD learn frames (light and shade on a box), two objects of a heap by
# 50-56 (thin_flat(23): a pen 98 dE from the notebook whose foot it lay against)
_SPLIT_DE = 40.0
# the ring of table pixels a candidate's relief is measured against (pixels out)
_RING_INNER_PX = 3
_RING_OUTER_PX = 8
# a candidate of fewer pixels is noise
_MIN_PIXELS = 30
# an object's raised pixels are looked for this far (pixels) round its colour: a
# RealSense's depth lies up to ~8 pixels beside its colour (uois_image_0006's markers)
_GROW_PX = 8
# the raised pixels replace the candidate's when they are at least this share of it; a
# far marker whose relief the depth smooths below grow_min_m keeps its colour's pixels
_RAISED_MIN_SHARE = 0.5
# ... and at most this many times as many: a larger thing's foot of the table's colour
# rises round a small candidate (uois_image_0000: a white bowl's side in its shadow, 3.3
# times its colour's pixels; the markers' depth 1.3 times theirs), and keeps its colour's
_RAISED_MAX_RATIO = 2.0
# a candidate with more than this share of the ring round it (`_RING_INNER_PX` to
# `_RING_OUTER_PX` out) without depth is the table seen through a transparent thing, no
# flat object (module doc, 3.): the lying clear cups of cleargrasp_000000130 0.40-0.48;
# the flat objects found on the foreign choose frames, mOSD learn and the support
# families' choose seeds (Kinect and RealSense renders) 0.00-0.03
_RING_MAX_NO_DEPTH_SHARE = 0.2


def cielab(rgb: np.ndarray) -> np.ndarray:
    """(N, 3) uint8 sRGB -> (N, 3) CIELAB (D65)."""
    c = rgb.astype(np.float64) / 255.0
    c = np.where(c > 0.04045, ((c + 0.055) / 1.055) ** 2.4, c / 12.92)
    xyz = c @ np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]).T
    xyz /= np.array([0.95047, 1.0, 1.08883])
    f = np.where(xyz > 0.008856, np.cbrt(xyz), 7.787 * xyz + 16.0 / 116.0)
    return np.stack([116.0 * f[:, 1] - 16.0, 500.0 * (f[:, 0] - f[:, 1]), 200.0 * (f[:, 1] - f[:, 2])], axis=1)


def group_lab(group_of_point: np.ndarray, colors: np.ndarray, n_groups: int) -> np.ndarray:
    """(n_groups, 3) CIELAB of each group's mean colour (``colors`` (M, 3) uint8 of the
    points, ``group_of_point`` (M,) their group: a voxel, a supervoxel)."""
    counts = np.maximum(np.bincount(group_of_point, minlength=n_groups), 1)
    mean = np.stack(
        [np.bincount(group_of_point, weights=colors[:, c].astype(np.float64), minlength=n_groups) for c in range(3)],
        axis=1,
    )
    return cielab(np.clip(mean / counts[:, None], 0, 255).round().astype(np.uint8))


@functools.cache
def _lab_table() -> np.ndarray:
    """(64^3, 3) float32 CIELAB of every colour quantized to 6 bits a channel (the
    centre of each bin): one lookup a pixel instead of the conversion, 3 MB once a
    process. The quantization moves a colour by at most ~3 dE, against thresholds of 20."""
    levels = (np.arange(64) * 4 + 2).astype(np.uint8)
    r, g, b = np.meshgrid(levels, levels, levels, indexing="ij")
    return cielab(np.stack([r.ravel(), g.ravel(), b.ravel()], axis=1)).astype(np.float32)


@functools.cache
def _lab_cache() -> tuple[np.ndarray, np.ndarray]:
    """`_lab_table`'s rows filled as colours are met, and which are filled: a frame meets
    a few thousand of the 262144, and the whole table cost a cold call ~0.1 s of CPU
    (issue 39). Each row is `cielab` of its colour, the very numbers of the whole table
    (the conversion is row by row; tests/perception/test_flat.py compares every row)."""
    return np.empty((1 << 18, 3), dtype=np.float32), np.zeros(1 << 18, dtype=bool)


def _lab_rows(keys: np.ndarray) -> np.ndarray:
    """(N, 3) float32: the rows ``keys`` of `_lab_table`, those not met before computed now."""
    table, filled = _lab_cache()
    # take: gathers several times faster than a[idx]
    new = np.unique(np.compress(~np.take(filled, keys), keys))
    if new.size:
        centres = np.stack([new >> 12, (new >> 6) & 63, new & 63], axis=1) * 4 + 2
        table[new] = cielab(centres.astype(np.uint8)).astype(np.float32)
        filled[new] = True
    return np.take(table, keys, axis=0)


def lab_of(rgb: np.ndarray) -> np.ndarray:
    """(N, 3) uint8 sRGB -> (N, 3) CIELAB, looked up (see _lab_table)."""
    return _lab_rows(_lab_keys(rgb))


def _lab_keys(rgb: np.ndarray) -> np.ndarray:
    """(N,) row of each colour in `_lab_table`."""
    # one shift of the bytes, then the key built in place: a column at a time cast and
    # shifted apart cost ten times more (strided columns, five temporaries; issue 39)
    q = rgb >> 2
    key = q[:, 0].astype(np.int32)
    key <<= 6
    key |= q[:, 1]
    key <<= 6
    key |= q[:, 2]
    return key


def _far_from(rgb: np.ndarray, centre: np.ndarray, threshold: float) -> np.ndarray:
    """(N,) bool: colours whose CIELAB (`lab_of`) is more than ``threshold`` from
    ``centre``: each distinct quantized colour judged once (a table shows a few
    thousand of the 262144), the same float32 sums as per pixel. Each colour's verdict
    is read per pixel from a table of bools (``seen``'s entries, overwritten: only the
    used ones are read), not its float32 distance compared pixel by pixel: the same
    comparison of the same numbers, a gather of bytes and a few thousand comparisons
    instead of a float per pixel (issue 39: 0.73 -> 0.63 ms a call on a table's 110k pixels)."""
    key = _lab_keys(rgb)
    seen = np.zeros(1 << 18, dtype=bool)
    seen[key] = True
    used = np.flatnonzero(seen)
    diff = _lab_rows(used) - centre.astype(np.float32)
    seen[used] = np.einsum("ij,ij->i", diff, diff) > threshold * threshold
    return np.take(seen, key)


def support_colour(
    colors: np.ndarray, shape: tuple[int, int], table_pixels: np.ndarray, min_color_delta: float
) -> tuple[np.ndarray, float]:
    """(CIELAB centre, threshold): the table's colour and how far (CIE76 dE) a pixel's
    colour must be from it to differ (module doc, 1.); ``table_pixels`` flat indices into
    the organized ``colors`` of ``shape``."""
    height, width = shape
    # the table's colour from a sample of its pixels (a few thousand fix a median): the
    # pixels on a fixed lattice of the image, so that a pixel more or less on the table
    # (a micrometre can move a point across the table's bound) leaves the others in the
    # sample; every n-th of the table's list shifted the whole sample along by one
    step = max(1, height * width // 10000)
    # the table's pixels on the lattice, by a lookup in a mask of it (the same pixels in the
    # same order as `table_pixels % step == 0`, whose integer division cost three times more)
    lattice = np.zeros(height * width, dtype=bool)
    lattice[::step] = True
    lab_table = lab_of(colors[np.compress(np.take(lattice, table_pixels), table_pixels)])
    centre = np.median(lab_table, axis=0)
    spread = float(np.median(np.linalg.norm(lab_table - centre, axis=1)))
    return centre, max(min_color_delta, 3.0 * spread)


def differs_from(rgb: np.ndarray, centre: np.ndarray, threshold: float) -> np.ndarray:
    """(N,) bool: the colours ``rgb`` (uint8) that differ from the table's (`support_colour`)."""
    return _far_from(rgb, centre, threshold)


def differing_shares(colors: np.ndarray, groups: list[np.ndarray], centre: np.ndarray, threshold: float) -> list[float]:
    """Per group of pixel indices into ``colors`` (none empty), the share of its pixels
    whose colour differs from the table's: ``differs_from(colors[g], ...).mean()`` each,
    the pixels of all groups judged in one `_far_from` (a pixel's verdict is its colour's
    alone; per group it cost two lookup tables of 2^18 entries each, issue 39)."""
    if not groups:
        return []
    differs = _far_from(np.take(colors, np.concatenate(groups), axis=0), centre, threshold)
    # counts by cumulative sums (exact integers); count / size is the mean's float64 division
    ends = np.cumsum([g.size for g in groups])
    counts = np.concatenate([[0], np.cumsum(differs, dtype=np.int64)])
    return [int(counts[e] - counts[e - g.size]) / g.size for e, g in zip(ends.tolist(), groups, strict=True)]


@dataclass(frozen=True)
class FlatFinds:
    """What `flat_objects` found: the objects lying flat (flat pixel indices each), and the
    feet of objects found before (their index in ``object_sizes`` -> the foot's pixels)."""

    objects: list[np.ndarray]
    feet: dict[int, np.ndarray]


def within_reach(object_xy: np.ndarray, foot_xy: np.ndarray, reach_m: float) -> np.ndarray:
    """(F,) bool: the foot's points (``foot_xy`` (F, 2), on the table's plane, m) within
    ``reach_m`` of one of the object's own points (``object_xy`` (M, 2)): a foot is the
    lower part of the faces seen above it, so it stands under the object's own outline;
    a point farther out is depth mixed between the object and the table in front of its
    lower edge (module doc, 5.). Any width of the object grows by at most twice the reach.

    A nearest-neighbour query's answer (its distance within the reach), worked out in two
    parts (issue 39: the tree over a large object's points along a long foot was most of
    the feet's cost): a foot point sharing a cell of side the reach over sqrt(2) (a hair
    less) with an object's point is within reach (in a cell, two points are less than its
    diagonal apart, rounding included: the hair); only the others are queried, against
    the object's points in their cell of side a hair more than the reach or the 8 around
    it (a point within reach lies there: its offset along each axis is under one cell),
    the same nearest within reach as among all the points."""
    from scipy.spatial import cKDTree

    out = np.zeros(foot_xy.shape[0], dtype=bool)
    if not foot_xy.shape[0] or not object_xy.shape[0]:
        return out
    # only the object's points within reach of the foot's box can be within reach of a
    # foot point, and a tree built unbalanced finds the same nearest for less
    pad_m = reach_m * 1.001 + 1e-9  # a hair wider than the reach: rounding keeps no point out
    lo, hi = foot_xy.min(axis=0) - pad_m, foot_xy.max(axis=0) + pad_m
    near_xy = np.compress(np.all((object_xy >= lo) & (object_xy <= hi), axis=1), object_xy, axis=0)
    if not near_xy.shape[0]:
        return out
    shared = _same_cell(near_xy, foot_xy, lo, hi, reach_m / math.sqrt(2.0) / 1.001)
    if shared is not None:
        out = shared
    rest = np.flatnonzero(~out)
    if not rest.size:
        return out
    rest_xy = np.take(foot_xy, rest, axis=0)
    around = _cells_around(rest_xy, near_xy, lo, hi, pad_m)
    if around is not None:
        near_xy = np.compress(around, near_xy, axis=0)
    if not near_xy.shape[0]:
        return out
    tree = cKDTree(near_xy, balanced_tree=False, compact_nodes=False)
    gap_m, _ = tree.query(rest_xy, k=1, distance_upper_bound=reach_m)
    out[rest] = gap_m <= reach_m
    return out


# `_cell_of` rasters a foot's box in at most this many cells (a reach near 0 would make
# the raster unbounded: then the cells are not used, every point is queried)
_CELLS_MAX = 1 << 22


def _cell_of(xy: np.ndarray, lo: np.ndarray, hi: np.ndarray, cell_m: float) -> tuple[np.ndarray, int, int] | None:
    """(each point's cell as one index, the raster's row and column counts) in a raster of cells of
    side ``cell_m`` from ``lo`` over the box to ``hi`` (the points lie in it), one cell of
    margin round it; None when the raster would be too large or a point falls off it."""
    if not cell_m > 0.0:
        return None
    n0, n1 = (int(k) + 3 for k in np.floor((hi - lo) / cell_m))
    if n0 * n1 > _CELLS_MAX:
        return None
    ij = np.floor((xy - lo) / cell_m).astype(np.int64) + 1
    if ij.shape[0] and (int(ij.min()) < 1 or int(ij[:, 0].max()) > n0 - 2 or int(ij[:, 1].max()) > n1 - 2):
        return None
    return ij[:, 0] * n1 + ij[:, 1], n0, n1


def _same_cell(
    object_xy: np.ndarray, foot_xy: np.ndarray, lo: np.ndarray, hi: np.ndarray, cell_m: float
) -> np.ndarray | None:
    """(F,) bool: the foot's points in a cell of side ``cell_m`` holding one of the
    object's points (all in the box ``lo``, ``hi``); None: not worked out."""
    objects = _cell_of(object_xy, lo, hi, cell_m)
    feet = _cell_of(foot_xy, lo, hi, cell_m)
    if objects is None or feet is None:
        return None
    held = np.zeros(objects[1] * objects[2], dtype=bool)
    held[objects[0]] = True
    return np.take(held, feet[0])


def _cells_around(
    foot_xy: np.ndarray, object_xy: np.ndarray, lo: np.ndarray, hi: np.ndarray, cell_m: float
) -> np.ndarray | None:
    """(M,) bool: the object's points in the cell (of side ``cell_m``) of one of the foot's
    points or in one of the 8 around it (all in the box ``lo``, ``hi``); None: not worked out."""
    objects = _cell_of(object_xy, lo, hi, cell_m)
    feet = _cell_of(foot_xy, lo, hi, cell_m)
    if objects is None or feet is None:
        return None
    n1 = objects[2]
    held = np.zeros(objects[1] * n1, dtype=bool)
    # the foot's cells and their 8 neighbours (the margin keeps every one on the raster)
    for d in (-n1 - 1, -n1, -n1 + 1, -1, 0, 1, n1 - 1, n1, n1 + 1):
        held[feet[0] + d] = True
    return np.take(held, objects[0])


def _foot_of(
    whole: np.ndarray,
    owner_window: np.ndarray,
    near: np.ndarray,
    v0: int,
    u0: int,
    width: int,
    object_pixels: np.ndarray,
    object_bounds: np.ndarray,
    owner: np.ndarray,
    colors: np.ndarray,
    object_lab: dict[int, np.ndarray],
) -> tuple[int, np.ndarray, np.ndarray] | None:  # owner: (height * width,) each pixel's object, -1 none
    """The one object, among those a candidate (``whole``, in a window at row ``v0``,
    column ``u0`` of the grid ``width`` wide) touches (within 2 pixels), whose colour it
    has (median CIELAB within `_FOOT_MAX_DE` of the object's pixels beside it
    (`_FOOT_SIDE_PX`) or of all of them), or None: none has, or several have (module
    doc, 5.). Until stop 62 it had to touch one object only:
    thin_flat(5)'s pen, its foot touching the pen and a box beside it, was missed.
    ``object_lab``: the objects' median colours worked out so far, filled here (an
    object's median over all its pixels cost most of the flat step when several
    candidates touched it, issue 39); ``object_bounds``: where each object's pixels
    start in ``object_pixels`` (and the last ends).

    Returns (the object, the colour its foot matched (CIELAB, (3,)), the candidate's
    pixels' colours in the order of ``np.nonzero(whole)``), or None."""
    touched = np.unique(owner_window[dilate_square(whole, _FOOT_TOUCH_PX) & near])
    touched = touched[touched >= 0]
    if not touched.size:
        return None
    rows, cols = np.nonzero(whole)
    pixel_lab = lab_of(np.take(colors, (rows + v0) * width + (cols + u0), axis=0))
    mine_lab = np.median(pixel_lab, axis=0)
    of_colour: list[tuple[int, np.ndarray]] = []
    beside = dilate_square(whole, _FOOT_SIDE_PX)
    for j in touched.tolist():
        # first against the object's pixels just above the foot, in the same light (most
        # feet pass it: the median over all the object's pixels is then not worked out)
        rows_j, cols_j = np.nonzero(beside & (owner_window == j))
        if rows_j.size:
            side_lab = np.median(lab_of(np.take(colors, (rows_j + v0) * width + (cols_j + u0), axis=0)), axis=0)
            if float(np.linalg.norm(mine_lab - side_lab)) < _FOOT_MAX_DE:
                of_colour.append((j, side_lab))
                continue
        their_lab = object_lab.get(j)
        if their_lab is None:
            # the pixels ``owner`` gives to j, in their order in ``object_pixels``: its own
            # rows there when no later object took one of them (objects share no pixel), read
            # without a pass over every object's pixels (issue 39: one pass per object touched)
            theirs = object_pixels[object_bounds[j] : object_bounds[j + 1]]
            if not np.all(np.take(owner, theirs) == j):
                theirs = np.compress(np.take(owner, object_pixels) == j, object_pixels)
            their_lab = object_lab[j] = np.median(lab_of(np.take(colors, theirs, axis=0)), axis=0)
        if float(np.linalg.norm(mine_lab - their_lab)) < _FOOT_MAX_DE:
            of_colour.append((j, their_lab))
    return (*of_colour[0], pixel_lab) if len(of_colour) == 1 else None


def _other_colour(whole: np.ndarray, pixel_lab: np.ndarray, foot_lab: np.ndarray) -> list[np.ndarray]:
    """The pieces (each an (h, w) bool mask of ``whole``'s window) of a foot candidate
    ``whole`` that are of another colour than its object's foot (``foot_lab``):
    8-connected pixels each at least `_SPLIT_DE` from it (``pixel_lab``: the
    candidate's pixels' CIELAB, in the order of ``np.nonzero(whole)``), `_MIN_PIXELS` or
    more of them, their median `_SPLIT_DE` or more from it: a thing lying against the
    object's foot, joined to it by the candidate's colour test alone."""
    far = np.linalg.norm(pixel_lab - foot_lab, axis=1) >= _SPLIT_DE
    if int(np.count_nonzero(far)) < _MIN_PIXELS:
        return []
    rows, cols = np.nonzero(whole)
    grid = np.zeros(whole.shape, dtype=bool)
    grid[rows[far], cols[far]] = True
    labels, n = label_8(grid)
    piece_of = labels[rows, cols]
    out = []
    for k in range(1, n + 1):
        mine = piece_of == k
        if int(np.count_nonzero(mine)) < _MIN_PIXELS:
            continue
        if float(np.linalg.norm(np.median(pixel_lab[mine], axis=0) - foot_lab)) >= _SPLIT_DE:
            out.append(labels == k)
    return out


def _raised(
    window: np.ndarray,
    mine: np.ndarray,
    near: np.ndarray,
    height_of: Callable[[np.ndarray], np.ndarray],
    base_m: float,
    grow_min_m: float,
) -> np.ndarray:
    """(h, w) bool of a ``window`` of the pixel grid ((h, w, 3) points): the pixels within
    `_GROW_PX` of the candidate ``mine`` that stand ``grow_min_m`` or more above the table
    around it (``base_m``), joined over 8 neighbours to such a pixel of the candidate
    (module doc, 4.); none ``near`` an object (within `_CLEARANCE_PX`: its depth smears
    over the table beside it)."""
    zone = dilate_square(mine, _GROW_PX) & ~near & np.isfinite(window).all(axis=2)
    rows, cols = np.nonzero(zone)
    up = np.zeros_like(zone)
    up[rows, cols] = height_of(window[rows, cols]) - base_m >= grow_min_m
    comps, _ = label_8(up)
    seeds = np.unique(comps[mine & up])
    up = np.isin(comps, seeds[seeds > 0])
    return up


def _ring(region: np.ndarray) -> np.ndarray:
    """The ring round ``region`` (a bool window): its pixels `_RING_INNER_PX` to
    `_RING_OUTER_PX` out (module doc, 3.)."""
    return dilate_square(region, _RING_OUTER_PX) & ~dilate_square(region, _RING_INNER_PX)


def _relief(
    region: np.ndarray,
    ring_may: np.ndarray,
    v0: int,
    u0: int,
    width: int,
    points: np.ndarray,
    height_of: Callable[[np.ndarray], np.ndarray],
) -> tuple[np.ndarray, float, float] | None:
    """(the flat pixel indices of ``region``, the table's height round it, its relief
    above that) for a candidate or a foot (module doc, 3.): ``region`` is a window at
    row ``v0``, column ``u0`` of the grid ``width`` wide; the ring `_RING_INNER_PX` to
    `_RING_OUTER_PX` pixels out, where ``ring_may`` (the table's pixels no candidate or
    object's reach holds), is measured; None when it holds under `_MIN_PIXELS`."""
    ring = _ring(region) & ring_may
    rows, cols = np.nonzero(ring)
    if rows.size < _MIN_PIXELS:
        return None
    # rows by index: take gathers several times faster than a[idx] (per candidate and foot)
    base = float(np.median(height_of(np.take(points, (rows + v0) * width + (cols + u0), axis=0))))
    rows, cols = np.nonzero(region)
    pixels = (rows + v0) * width + (cols + u0)
    return pixels, base, float(np.median(height_of(np.take(points, pixels, axis=0)))) - base


def _no_depth_share(region: np.ndarray, window: np.ndarray) -> float:
    """The share of the ring round ``region`` (`_RING_INNER_PX` to `_RING_OUTER_PX`
    pixels out, in a ``window`` of the pixel grid: (h, w, 3) points) whose pixels have no
    depth (module doc, 3.)."""
    ring = _ring(region)
    n_ring = int(np.count_nonzero(ring))
    if not n_ring:
        return 0.0
    rows, cols = np.nonzero(ring)
    return 1.0 - int(np.count_nonzero(np.isfinite(window[rows, cols]).all(axis=1))) / n_ring


def _pieces(grid: np.ndarray, pixels: np.ndarray) -> tuple[np.ndarray, int, list[tuple[slice, ...] | None]]:
    """`label_8` of the (H, W) bool ``grid`` and the pieces' `boxes`, worked out on the box
    of its set cells (``pixels``: their flat indices, none outside the grid): the same
    pieces, numbered alike (in raster order of their first cells, which the box keeps),
    and their boxes moved back to the grid's rows and columns. The candidates of a
    frame lie on the table's part of the image (a tenth to three quarters of it on the
    mOSD and RealSense frames): the labelling and the boxes read only that (issue 39)."""
    width = grid.shape[1]
    rows = pixels // width
    cols = pixels - rows * width
    r0, r1, c0, c1 = int(rows.min()), int(rows.max()) + 1, int(cols.min()), int(cols.max()) + 1
    part, n = label_8(np.ascontiguousarray(grid[r0:r1, c0:c1]))
    labels = np.zeros(grid.shape, dtype=part.dtype)
    labels[r0:r1, c0:c1] = part
    moved: list[tuple[slice, ...] | None] = [
        None if b is None else (slice(b[0].start + r0, b[0].stop + r0), slice(b[1].start + c0, b[1].stop + c0))
        for b in boxes(part, n)
    ]
    return labels, n, moved


def flat_objects(
    points: np.ndarray,
    colors: np.ndarray,
    shape: tuple[int, int],
    table_pixels: np.ndarray,
    loose_pixels: np.ndarray,
    object_pixels: np.ndarray,
    height_of: Callable[[np.ndarray], np.ndarray],
    pixel_area_m2: Callable[[np.ndarray], float],
    min_color_delta: float,
    min_relief_m: float,
    min_area_m2: float,
    max_area_m2: float,
    grow_min_m: float,
    support: tuple[np.ndarray, float] | None = None,
    object_sizes: Sequence[int] = (),
) -> FlatFinds:
    """Flat pixel indices of each object found lying flat on the table (module doc).

    ``table_pixels``: the table's points; ``loose_pixels``: points above the table that
    no object kept; ``object_pixels``: the objects'; all flat indices into the organized
    ``points`` / ``colors`` of ``shape``. ``height_of(points) -> heights`` above the table;
    ``pixel_area_m2(flat indices) -> m^2`` the visible area of a set of pixels.
    ``support``: `support_colour` of ``table_pixels`` when the caller has it already.
    ``object_sizes``: the objects' pixel counts, in the order their pixels are in
    ``object_pixels``; when given, an object's foot below the prism is found (module
    doc, 5.)."""
    height, width = shape
    if table_pixels.size < 100:
        return FlatFinds([], {})
    centre, threshold = support_colour(colors, shape, table_pixels, min_color_delta) if support is None else support
    free = np.concatenate([table_pixels, loose_pixels])
    differs = _far_from(np.take(colors, free, axis=0), centre, threshold)  # take: several times faster than a[idx]
    cand = np.zeros(height * width, dtype=bool)
    cand_pixels = np.compress(differs, free)
    if not cand_pixels.size:
        return FlatFinds([], {})
    cand[cand_pixels] = True
    grid = cand.reshape(height, width)
    comps, n, comp_boxes = _pieces(grid, cand_pixels)
    # each piece's size from the candidate pixels' labels (every labelled pixel is one):
    # not a count over the whole image (sizes[0], the background, is not read)
    sizes = np.bincount(np.take(comps.ravel(), cand_pixels), minlength=n + 1)
    big = (np.flatnonzero(sizes[1:] >= _MIN_PIXELS) + 1).tolist()  # most are specks: not even looked at
    if not big:
        return FlatFinds([], {})
    taken: np.ndarray = np.zeros(height * width, dtype=bool)  # flat, then (height, width)
    taken[object_pixels] = True
    taken = taken.reshape(height, width)
    table_once: list[np.ndarray] = []  # the table's pixels as a mask, the first time a ring is looked at

    def is_table() -> np.ndarray:
        if not table_once:
            mask = np.zeros(height * width, dtype=bool)
            mask[table_pixels] = True
            table_once.append(mask.reshape(height, width))
        return table_once[0]

    found: list[np.ndarray] = []
    grid_points = points.reshape(height, width, 3)
    owner_once: list[np.ndarray] = []  # each pixel's object (-1 none), the first time a foot is looked for

    def owner() -> np.ndarray:
        if not owner_once:
            # int32: an object's number fits, and the map is half the bytes to fill
            flat = np.full(height * width, -1, dtype=np.int32)
            flat[object_pixels] = np.repeat(np.arange(len(object_sizes), dtype=np.int32), object_sizes)
            owner_once.append(flat)
        return owner_once[0]

    object_bounds = np.concatenate([[0], np.cumsum(np.asarray(object_sizes, dtype=np.int64))])
    feet: dict[int, list[np.ndarray]] = {}
    object_lab: dict[int, np.ndarray] = {}  # _foot_of's, each object's once
    # each candidate in its window (rows v0:v1, columns u0:u1); the pieces of another
    # colour a foot gives up (`_other_colour`) join the end of the list
    work: list[tuple[int, int, int, int, np.ndarray]] = []
    pad = _RING_OUTER_PX + _GROW_PX + 1
    for k in big:
        box = comp_boxes[k - 1]
        if box is None:
            continue
        v0, v1 = max(0, box[0].start - pad), min(height, box[0].stop + pad)
        u0, u1 = max(0, box[1].start - pad), min(width, box[1].stop + pad)
        work.append((v0, v1, u0, u1, comps[v0:v1, u0:u1] == k))
    for v0, v1, u0, u1, whole in work:  # (the list grows as it is read)
        near = dilate_square(taken[v0:v1, u0:u1], _CLEARANCE_PX)
        n_mine = int(np.count_nonzero(whole))
        mine = whole & ~near
        if np.count_nonzero(mine) < max(_MIN_PIXELS, (1.0 - _NEAR_MAX_SHARE) * n_mine):
            if len(object_sizes):
                foot = _foot_of(
                    whole,
                    owner().reshape(height, width)[v0:v1, u0:u1],
                    near,
                    v0,
                    u0,
                    width,
                    object_pixels,
                    object_bounds,
                    owner(),
                    colors,
                    object_lab,
                )
                if foot is not None:
                    j, foot_lab, pixel_lab = foot
                    others = _other_colour(whole, pixel_lab, foot_lab)
                    for piece in others:
                        whole = whole & ~piece
                        work.append((v0, v1, u0, u1, piece))
                    measured = _relief(
                        whole, is_table()[v0:v1, u0:u1] & ~grid[v0:v1, u0:u1] & ~near, v0, u0, width, points, height_of
                    )
                    if measured is not None and measured[2] >= min_relief_m:
                        feet.setdefault(j, []).append(measured[0])
                    continue
            # nobody's foot: a thing lying apart beside an object (a notebook against a
            # box) when at most half of it lies near objects and the table shows round
            # half its ring or more; else its pixels far from them do not count alone
            if np.count_nonzero(mine) < max(_MIN_PIXELS, (1.0 - _NEAR_NOBODY_MAX_SHARE) * n_mine):
                continue
            ring = _ring(whole)
            ring_table = np.count_nonzero(ring & is_table()[v0:v1, u0:u1] & ~grid[v0:v1, u0:u1])
            if ring_table < _NOBODY_RING_TABLE_MIN * np.count_nonzero(ring):
                continue
        measured = _relief(
            mine, is_table()[v0:v1, u0:u1] & ~grid[v0:v1, u0:u1] & ~near, v0, u0, width, points, height_of
        )
        if measured is None or measured[2] < min_relief_m:
            continue
        if _no_depth_share(mine, grid_points[v0:v1, u0:u1]) > _RING_MAX_NO_DEPTH_SHARE:
            continue
        inside, base, _ = measured
        # found or not by its colour's pixels (their area; the depth smeared round a
        # notebook took thin_flat(4)'s over flat_max_area_m2), its points where its depth is
        least_m2 = min_area_m2 * (_NEAR_MIN_AREA_FACTOR if np.count_nonzero(mine) < n_mine else 1.0)
        if not least_m2 <= pixel_area_m2(inside) <= max_area_m2:
            continue
        raised = _raised(grid_points[v0:v1, u0:u1], mine, near, height_of, base, grow_min_m)
        rows, cols = np.nonzero(raised)
        if _RAISED_MIN_SHARE * inside.size <= rows.size <= _RAISED_MAX_RATIO * inside.size:
            inside = (rows + v0) * width + (cols + u0)
        found.append(inside)
    return FlatFinds(found, {j: np.concatenate(parts) for j, parts in sorted(feet.items())})
