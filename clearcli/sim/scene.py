"""Self-made tabletop scenes with known ground truth, for tests, fixtures and replays.

Everything here is a frozen value and every builder is a pure function: moving or
removing an object returns a new `Scene`.

Frames:
  table frame: origin at the centre of the table's top surface, z up, x to the right as
  the camera sees it, y away from the camera. Object poses are given in it.
  camera frame: the optical frame of the virtual Kinect (z forward, y down, x right).
  `Scene.T_camera_table` maps table-frame points into the camera frame.

Object identity: each object carries an ``object_id``; its ground-truth label is
``10 * (object_id + 1)`` (the project's label convention). Builders number objects
0..n-1, and `with_object_pose`/`without_object` keep the ids of the others, so an
object keeps its label across the frames of a session (after a removal the labels have
a gap). ``k`` in the editing functions is the index into ``scene.objects``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from clearcli.transforms import rot2

# Camera placement like the mOSD frames: the Kinect there is ~0.59 m above the table,
# its optical axis 37-42 degrees below the horizontal. We take the middle of that.
CAMERA_HEIGHT_M = 0.62
CAMERA_PITCH_DEG = 42.0

# Table top: large enough to fill the lower image like mOSD's cropped tables, small
# enough that the camera sees all of it (keeps PCD fixtures small: misses are NaN rows).
TABLE_SIZE_X_M = 0.80
TABLE_SIZE_Y_M = 0.60

# Graspable objects: the thesis's gripper closes on 3-7 cm widths.
MIN_WIDTH_M = 0.03
MAX_WIDTH_M = 0.07

# A mug's handle (`Cylinder.handle_m`): a loop modelled as a solid box this thick across,
# over this share of the mug's height, centred on its middle.
HANDLE_THICKNESS_M = 0.012
HANDLE_SPAN = 0.6

# What the camera does not see of an object (issue 36, the suction cup's concern): its
# true mass and the surface of its top.
# An object built without a mass weighs its volume at this density: 500 kg/m^3, within
# household goods' 170 (a cracker box) to 1000 (a full can), stated by the world alone
# (the planner estimates with its own [suction] density_kg_m3).
WORLD_DENSITY_KG_M3 = 500.0
# smooth: a cup seals on it; porous: perforated or open-weave (air holes, a mesh or a
# fabric lid); ribbed: ridges and grooves deeper than a bellows follows (a ribbed lid).
# Only the top is marked: an object's sides are smooth.
SURFACES = ("smooth", "porous", "ribbed")


def camera_pose_T_camera_table(height_m: float = CAMERA_HEIGHT_M, pitch_deg: float = CAMERA_PITCH_DEG) -> np.ndarray:
    """T_camera_table (4x4) of a camera ``height_m`` above the table plane, in the plane
    x = 0, looking along +y of the table, pitched ``pitch_deg`` below the horizontal so
    that its optical axis hits the table-frame origin."""
    pitch = math.radians(pitch_deg)
    c, s = math.cos(pitch), math.sin(pitch)
    # Camera axes written in the table frame (right-handed: x_c cross y_c = z_c).
    x_c = np.array([1.0, 0.0, 0.0])
    y_c = np.array([0.0, -s, -c])  # image "down": towards the near edge and the table
    z_c = np.array([0.0, c, -s])  # optical axis
    position = np.array([0.0, -height_m / math.tan(pitch), height_m])
    T_table_camera = np.eye(4)
    T_table_camera[:3, :3] = np.stack([x_c, y_c, z_c], axis=1)
    T_table_camera[:3, 3] = position
    return invert_transform(T_table_camera)


def convex_hull(points: np.ndarray) -> np.ndarray:
    """(m, 2) counter-clockwise convex hull of (n, 2) points (SciPy's Qhull, as every other
    hull in the project); fewer than three distinct or collinear points: their extremes."""
    from scipy.spatial import ConvexHull, QhullError

    pts = np.unique(np.asarray(points, dtype=float).reshape(-1, 2), axis=0)
    if len(pts) < 3:
        return pts
    try:
        return pts[ConvexHull(pts).vertices]
    except QhullError:  # all on one line
        along = (pts - pts[0]) @ (pts[-1] - pts[0])
        return pts[[int(np.argmin(along)), int(np.argmax(along))]]


def invert_transform(T: np.ndarray) -> np.ndarray:
    """Inverse of a rigid 4x4 transform."""
    R = T[:3, :3]
    out = np.eye(4)
    out[:3, :3] = R.T
    out[:3, 3] = -R.T @ T[:3, 3]
    return out


# The transform of the camera every built-in scene uses.
T_CAMERA_TABLE: np.ndarray = camera_pose_T_camera_table()
T_CAMERA_TABLE.setflags(write=False)


@dataclass(frozen=True)
class Table:
    """Rectangular table top, centred on the table-frame origin, sides along x and y."""

    size_x_m: float = TABLE_SIZE_X_M
    size_y_m: float = TABLE_SIZE_Y_M


@dataclass(frozen=True)
class Box:
    """A box standing on the table (or on another object, ``base_z_m`` above the table).

    Pose in the table frame: the centre of its bottom face at (x_m, y_m, base_z_m), its
    local x axis turned ``yaw_rad`` from the table's x about z. Sizes are full lengths
    along its local x, y and z.
    """

    object_id: int
    size_x_m: float
    size_y_m: float
    size_z_m: float
    x_m: float
    y_m: float
    yaw_rad: float = 0.0
    base_z_m: float = 0.0
    # what no camera sees (issue 36): the true mass (0: its volume at
    # `WORLD_DENSITY_KG_M3`) and its top's surface (`SURFACES`); last, with defaults that
    # leave every scene built before them as it was
    mass_kg: float = 0.0
    surface: str = "smooth"

    @property
    def height_m(self) -> float:
        return self.size_z_m

    @property
    def volume_m3(self) -> float:
        return self.size_x_m * self.size_y_m * self.size_z_m

    @property
    def true_mass_kg(self) -> float:
        """Its mass: ``mass_kg``, or its volume at `WORLD_DENSITY_KG_M3`."""
        return self.mass_kg if self.mass_kg > 0.0 else self.volume_m3 * WORLD_DENSITY_KG_M3

    @property
    def top_z_m(self) -> float:
        return self.base_z_m + self.size_z_m

    def footprint(self) -> np.ndarray:
        """(4, 2) corners of its footprint on the table, counter-clockwise."""
        hx, hy = self.size_x_m / 2, self.size_y_m / 2
        local = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
        return local @ rot2(self.yaw_rad).T + np.array([self.x_m, self.y_m])


@dataclass(frozen=True)
class Cylinder:
    """An upright cylinder; pose as for `Box` (yaw is kept only so that moves are uniform).

    ``wall_m`` > 0 makes it an open container (a cup, a bowl with straight sides): no
    top cap, a wall that thick, and a floor inside ``floor_m`` above its base. 0 is a
    solid, closed cylinder (a can).

    ``handle_m`` > 0 gives it a mug's handle: the loop is modelled as a solid box
    (`handle_box`) sticking out radially from the wall along the yaw direction,
    ``handle_m`` beyond the outer wall, `HANDLE_THICKNESS_M` across, over the middle
    `HANDLE_SPAN` of the height. It is part of the object (same id and label)."""

    object_id: int
    radius_m: float
    height_m: float
    x_m: float
    y_m: float
    yaw_rad: float = 0.0
    base_z_m: float = 0.0
    wall_m: float = 0.0
    floor_m: float = 0.005
    handle_m: float = 0.0  # after the others, so positional construction elsewhere stays valid
    # as for `Box`: the true mass (0: its volume at `WORLD_DENSITY_KG_M3`) and its top's
    # surface (`SURFACES`; an open container has no top)
    mass_kg: float = 0.0
    surface: str = "smooth"

    @property
    def is_open(self) -> bool:
        return self.wall_m > 0.0

    @property
    def volume_m3(self) -> float:
        """What it is made of: a closed cylinder's whole volume, an open one's wall and
        floor (its handle left out)."""
        outer = math.pi * self.radius_m**2
        if not self.is_open:
            return outer * self.height_m
        inner = math.pi * (self.radius_m - self.wall_m) ** 2
        return (outer - inner) * (self.height_m - self.floor_m) + outer * self.floor_m

    @property
    def true_mass_kg(self) -> float:
        """Its mass: ``mass_kg``, or its volume at `WORLD_DENSITY_KG_M3`."""
        return self.mass_kg if self.mass_kg > 0.0 else self.volume_m3 * WORLD_DENSITY_KG_M3

    @property
    def has_handle(self) -> bool:
        return self.handle_m > 0.0

    def handle_box(self) -> Box | None:
        """The handle as a `Box` in the table frame (same id, so same label), or None.

        Its inner face sits inside the wall where the outer surface is at least as far
        out as the box's corners (so no gap shows between box and wall) but never inside
        the inner wall (so an open mug shows no handle stub on its inside)."""
        if not self.has_handle:
            return None
        half = HANDLE_THICKNESS_M / 2
        r_in = self.radius_m - self.wall_m if self.is_open else 0.0
        inner = max(math.sqrt(max(self.radius_m**2 - half**2, 0.0)), r_in)
        outer = self.radius_m + self.handle_m
        mid = (inner + outer) / 2
        c, s = math.cos(self.yaw_rad), math.sin(self.yaw_rad)
        low = (1.0 - HANDLE_SPAN) / 2 * self.height_m
        return Box(
            self.object_id,
            outer - inner,
            HANDLE_THICKNESS_M,
            HANDLE_SPAN * self.height_m,
            x_m=self.x_m + mid * c,
            y_m=self.y_m + mid * s,
            yaw_rad=self.yaw_rad,
            base_z_m=self.base_z_m + low,
        )

    @property
    def top_z_m(self) -> float:
        return self.base_z_m + self.height_m

    def footprint(self, n_sides: int = 32) -> np.ndarray:
        """(n_sides, 2) polygon circumscribing its footprint circle, counter-clockwise."""
        angles = np.arange(n_sides) * (2 * math.pi / n_sides)
        r = self.radius_m / math.cos(math.pi / n_sides)  # circumscribed: never under-covers
        circle = np.stack([self.x_m + r * np.cos(angles), self.y_m + r * np.sin(angles)], axis=1)
        handle = self.handle_box()
        if handle is None:
            return circle  # the exact polygon of before handles existed
        # still convex (every caller's separating-axis tests need that): the hull of both
        return convex_hull(np.vstack([circle, handle.footprint()]))


SceneObject = Box | Cylinder


@dataclass(frozen=True)
class Scene:
    """A table, the objects on it, and the camera (its T_camera_table) that sees them.

    ``T_camera_table_rows`` stores the 4x4 as nested tuples so the value stays hashable
    and immutable; read it through ``T_camera_table``.
    """

    name: str
    table: Table
    objects: tuple[SceneObject, ...]
    T_camera_table_rows: tuple[tuple[float, ...], ...]

    @property
    def T_camera_table(self) -> np.ndarray:
        return np.array(self.T_camera_table_rows, dtype=float)

    @property
    def n_objects(self) -> int:
        return len(self.objects)


def _rows(T: np.ndarray) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(float(v) for v in row) for row in np.asarray(T))


def make_scene(
    name: str,
    objects: tuple[SceneObject, ...] | list[SceneObject],
    table: Table | None = None,
    T_camera_table: np.ndarray | None = None,
) -> Scene:
    return Scene(
        name=name,
        table=table or Table(),
        objects=tuple(objects),
        T_camera_table_rows=_rows(T_CAMERA_TABLE if T_camera_table is None else T_camera_table),
    )


# ---------------------------------------------------------------------------------------
# Fixed scenes


def isolated_box() -> Scene:
    """One 5 x 4 x 8 cm box in the middle of the table, turned 30 degrees."""
    return make_scene(
        "isolated_box()",
        [Box(0, 0.05, 0.04, 0.08, x_m=0.0, y_m=0.0, yaw_rad=math.radians(30.0))],
    )


def two_touching_boxes() -> Scene:
    """Two boxes side by side along the table's x, faces in contact (zero gap)."""
    a = Box(0, 0.06, 0.05, 0.10, x_m=-0.03, y_m=0.0)
    b = Box(1, 0.04, 0.07, 0.06, x_m=0.02, y_m=0.01)  # a's +x face at x=0, b's -x face at x=0
    return make_scene("two_touching_boxes()", [a, b])


def box_on_box() -> Scene:
    """A 4 x 3 x 4 cm box lying on top of an 8 x 6 x 5 cm box, turned 20 degrees on it."""
    lower = Box(0, 0.08, 0.06, 0.05, x_m=0.0, y_m=0.02, yaw_rad=math.radians(-10.0))
    upper = Box(1, 0.04, 0.03, 0.04, x_m=0.005, y_m=0.015, yaw_rad=math.radians(10.0), base_z_m=lower.top_z_m)
    return make_scene("box_on_box()", [lower, upper])


# ---------------------------------------------------------------------------------------
# Random clutter


# Where clutter goes: the middle of the table, in the arm's reach and away from the edges.
CLUTTER_HALF_X_M = 0.22
CLUTTER_HALF_Y_M = 0.15
# Share of objects placed in contact with an earlier one (the thesis's hard case).
CLUTTER_TOUCH_FRACTION = 0.4
# Gap kept between objects that are meant not to touch (> the sensor's noise, so a
# segmenter can be expected to separate them).
CLUTTER_MIN_GAP_M = 0.015
# Contact gap: bisection stops when the gap is below this (point clouds cannot tell it
# from zero).
CONTACT_TOLERANCE_M = 0.0002


def deadlock_row() -> Scene:
    """Two 12 x 5 x 12 cm boxes touching along their long sides, and beside them a box
    too wide for the gripper (9 cm) and taller (18 cm), touching too. Each of the pair
    blocks the other's grasp; a push across the row needs the gripper between two
    boxes or runs into one; a push along the row, at the table, brings the arm's wrist
    into the neighbour beside it. The thesis's model has no plan here (every object
    "blocked by objects that cannot be moved"); a push with the contact raised clears
    the wrist (`clearcli.geometry.poses.raised_contact_lifts`)."""
    yaw = math.pi / 2  # long sides along the table's y, away from the camera
    a = Box(0, 0.12, 0.05, 0.12, x_m=-0.05, y_m=0.05, yaw_rad=yaw)
    b = Box(1, 0.12, 0.05, 0.12, x_m=0.0, y_m=0.05, yaw_rad=yaw)
    c = Box(2, 0.12, 0.09, 0.18, x_m=0.07, y_m=0.05, yaw_rad=yaw)
    return make_scene("deadlock_row", [a, b, c])


def polygons_overlap(a: np.ndarray, b: np.ndarray, clearance_m: float = 0.0) -> bool:
    """Separating-axis test of two convex polygons, treating gaps < clearance as overlap."""
    for poly in (a, b):
        edges = np.roll(poly, -1, axis=0) - poly
        normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1)
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        pa = a @ normals.T  # (na, k)
        pb = b @ normals.T
        separated = (pa.max(axis=0) + clearance_m <= pb.min(axis=0)) | (pb.max(axis=0) + clearance_m <= pa.min(axis=0))
        if separated.any():
            return False
    return True


def _random_object(rng: np.random.Generator, object_id: int) -> SceneObject:
    height = float(rng.uniform(0.04, 0.15))
    yaw = float(rng.uniform(-math.pi / 2, math.pi / 2))
    if rng.random() < 0.3:
        radius = float(rng.uniform(MIN_WIDTH_M, MAX_WIDTH_M)) / 2
        return Cylinder(object_id, round(radius, 4), round(height, 4), 0.0, 0.0, round(yaw, 4))
    sx, sy = rng.uniform(MIN_WIDTH_M, MAX_WIDTH_M, size=2)
    # Some boxes are longer than a gripper's opening along one side only (still graspable
    # across the other), like the cereal and tea boxes of the OSD scenes.
    if rng.random() < 0.25:
        sx = float(rng.uniform(0.08, 0.14))
    return Box(object_id, round(float(sx), 4), round(float(sy), 4), round(height, 4), 0.0, 0.0, round(yaw, 4))


def _in_region(poly: np.ndarray) -> bool:
    return bool((np.abs(poly[:, 0]) <= CLUTTER_HALF_X_M).all() and (np.abs(poly[:, 1]) <= CLUTTER_HALF_Y_M).all())


def _place_touching(obj: SceneObject, anchor: SceneObject, direction: float) -> SceneObject:
    """``obj`` moved along ``direction`` (radians, from the anchor's centre) to the
    smallest distance at which its footprint no longer overlaps the anchor's."""
    ux, uy = math.cos(direction), math.sin(direction)
    anchor_poly = anchor.footprint()

    def at(d: float) -> SceneObject:
        return replace(obj, x_m=anchor.x_m + d * ux, y_m=anchor.y_m + d * uy)

    lo, hi = 0.0, 0.3
    while hi - lo > CONTACT_TOLERANCE_M:
        mid = (lo + hi) / 2
        if polygons_overlap(at(mid).footprint(), anchor_poly):
            lo = mid
        else:
            hi = mid
    return at(hi)


def clutter(n_objects: int, seed: int) -> Scene:
    """``n_objects`` boxes and cylinders (3-7 cm wide, some boxes up to 14 cm long, 4-15 cm
    tall) on the middle of the table, none overlapping, about 40 % of them in contact with
    an earlier one. Deterministic from ``seed``."""
    rng = np.random.default_rng(seed)
    placed: list[SceneObject] = []
    for object_id in range(n_objects):
        obj = _random_object(rng, object_id)
        for _attempt in range(500):
            touch = bool(placed) and rng.random() < CLUTTER_TOUCH_FRACTION
            if touch:
                anchor = placed[int(rng.integers(len(placed)))]
                # Touch face to face for boxes (same yaw) now and then: the hardest case.
                if isinstance(anchor, Box) and isinstance(obj, Box) and rng.random() < 0.5:
                    obj = replace(obj, yaw_rad=anchor.yaw_rad)
                    direction = anchor.yaw_rad + float(rng.integers(4)) * math.pi / 2
                else:
                    direction = float(rng.uniform(-math.pi, math.pi))
                candidate = _place_touching(obj, anchor, direction)
                others = [p for p in placed if p is not anchor]
            else:
                candidate = replace(
                    obj,
                    x_m=float(rng.uniform(-CLUTTER_HALF_X_M, CLUTTER_HALF_X_M)),
                    y_m=float(rng.uniform(-CLUTTER_HALF_Y_M, CLUTTER_HALF_Y_M)),
                )
                others = placed
            poly = candidate.footprint()
            if not _in_region(poly):
                continue
            if any(polygons_overlap(poly, p.footprint(), CLUTTER_MIN_GAP_M) for p in others):
                continue
            placed.append(candidate)
            break
        else:
            raise ValueError(f"clutter({n_objects}, seed={seed}): no room for object {object_id}")
    return make_scene(f"clutter({n_objects}, seed={seed})", placed)


def dense(n_objects: int, seed: int) -> Scene:
    """Up to ``n_objects`` objects packed in rows and blocks: two to four boxes of one
    length standing side by side, touching along their long sides (a row), or four in a
    2 x 2 block, with the rest placed as `clutter` places them. A row of long boxes is
    where the thesis's model deadlocks: each box blocks its neighbours' grasps, and every
    push that would free one starts or ends against another. An object that finds no
    room after 300 tries is left out (its id unused). Deterministic from ``seed``."""
    rng = np.random.default_rng(seed)
    placed: list[SceneObject] = []
    object_id = 0
    tries = 0
    while object_id < n_objects and tries < 60:
        tries += 1
        left = n_objects - object_id
        kind = rng.random()
        if left >= 2 and kind < 0.75:
            # a row (or a 2 x 2 block) of boxes sharing a length and a yaw
            block = left >= 4 and kind < 0.2
            count = 4 if block else int(rng.integers(2, min(4, left) + 1))
            length = (
                float(rng.uniform(0.08, 0.14)) if rng.random() < 0.6 else float(rng.uniform(MIN_WIDTH_M, MAX_WIDTH_M))
            )
            yaw = float(rng.uniform(-math.pi / 2, math.pi / 2))
            cx, cy = (
                float(rng.uniform(-CLUTTER_HALF_X_M, CLUTTER_HALF_X_M)),
                float(rng.uniform(-CLUTTER_HALF_Y_M, CLUTTER_HALF_Y_M)),
            )
            widths = rng.uniform(MIN_WIDTH_M, MAX_WIDTH_M, size=count)
            heights = rng.uniform(0.04, 0.15, size=count)
            gaps = rng.uniform(0.0, 0.002, size=count)  # touching, or a hair apart
            along, across = rot2(yaw) @ np.array([1.0, 0.0]), rot2(yaw) @ np.array([0.0, 1.0])
            group: list[SceneObject] = []
            per_row = 2 if block else count
            for r in range((count + per_row - 1) // per_row):
                offset = -0.5 * float(widths[:per_row].sum())
                for c in range(per_row):
                    i = r * per_row + c
                    if i >= count:
                        break
                    if block:
                        # a block's boxes share a width too, so the rows line up
                        widths[i] = widths[c]
                    w = float(widths[i])
                    pos = np.array([cx, cy]) + across * (offset + w / 2) + along * r * (length + float(gaps[i]))
                    offset += w + float(gaps[i])
                    group.append(
                        Box(
                            object_id + i,
                            round(length, 4),
                            round(w, 4),
                            round(float(heights[i]), 4),
                            float(pos[0]),
                            float(pos[1]),
                            round(yaw, 4),
                        )
                    )
            if all(_in_region(o.footprint()) for o in group) and not any(
                polygons_overlap(o.footprint(), p.footprint(), CLUTTER_MIN_GAP_M) for o in group for p in placed
            ):
                placed.extend(group)
                object_id += len(group)
            continue
        obj = _random_object(rng, object_id)
        for _attempt in range(300):
            if placed and rng.random() < CLUTTER_TOUCH_FRACTION:
                anchor_obj = placed[int(rng.integers(len(placed)))]
                cand = _place_touching(obj, anchor_obj, float(rng.uniform(-math.pi, math.pi)))
                others = [p for p in placed if p is not anchor_obj]
            else:
                cand = replace(
                    obj,
                    x_m=float(rng.uniform(-CLUTTER_HALF_X_M, CLUTTER_HALF_X_M)),
                    y_m=float(rng.uniform(-CLUTTER_HALF_Y_M, CLUTTER_HALF_Y_M)),
                )
                others = placed
            poly = cand.footprint()
            if _in_region(poly) and not any(polygons_overlap(poly, p.footprint(), CLUTTER_MIN_GAP_M) for p in others):
                placed.append(cand)
                break
        object_id += 1
    return make_scene(f"dense({n_objects}, seed={seed})", placed)


# ---------------------------------------------------------------------------------------
# Editing (for replays: pushes move objects, picks remove them)


def with_object_pose(scene: Scene, k: int, x_m: float, y_m: float, yaw_rad: float) -> Scene:
    """The scene with object ``k`` (index into ``scene.objects``) at a new table pose."""
    _check_index(scene, k)
    moved = replace(scene.objects[k], x_m=float(x_m), y_m=float(y_m), yaw_rad=float(yaw_rad))
    objects = scene.objects[:k] + (moved,) + scene.objects[k + 1 :]
    return replace(scene, name=f"{scene.name}.move({k})", objects=objects)


def without_object(scene: Scene, k: int) -> Scene:
    """The scene with object ``k`` (index into ``scene.objects``) taken away."""
    _check_index(scene, k)
    objects = scene.objects[:k] + scene.objects[k + 1 :]
    return replace(scene, name=f"{scene.name}.remove({k})", objects=objects)


def _check_index(scene: Scene, k: int) -> None:
    if not 0 <= k < len(scene.objects):
        raise IndexError(f"{scene.name}: no object {k} (it has {len(scene.objects)})")


def object_pose_T_table_object(obj: SceneObject) -> np.ndarray:
    """T_table_object: the object frame has its origin at the bottom-face centre, z up."""
    T = np.eye(4)
    T[:2, :2] = rot2(obj.yaw_rad)
    T[:3, 3] = (obj.x_m, obj.y_m, obj.base_z_m)
    return T


def objects_overlap(a: SceneObject, b: SceneObject, clearance_m: float = 0.0) -> bool:
    """Do the footprints of two objects on the same level overlap (gaps below
    ``clearance_m`` count as overlap)? Objects at different heights (stacks) never do."""
    if a.base_z_m >= b.top_z_m or b.base_z_m >= a.top_z_m:
        return False
    return polygons_overlap(a.footprint(), b.footprint(), clearance_m)
