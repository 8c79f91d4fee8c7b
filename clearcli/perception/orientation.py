"""Which way an organized camera image looks, and which way is up in it (issue 37: frames of
labs no one here has seen).

The steps read an organized frame as a camera image in the optical frame (x right, y down
the image, z forward, the camera at the origin), the right way up (the table's normal,
seen in the image, towards its top): depth is read along +z, the table's far side up the
image. Two kinds of frames meet that only after a turn; each turn keeps every coordinate
or negates it and moves it to another axis, and moves pixels whole, so it is exact in
floating point, and the steps see the very points of the upright optical image:

- another axis convention about the same camera (`axes_turn`): OpenGL's (y up, looking
  along -z: Open3D's tutorials turn their clouds so, ARKit and Unity write them so), ROS's
  camera_link (x forward, y left, z up), and the rest. Told from the rays: the mean point
  nearest an axis (`_FORWARD_COS`), and the rays' steps along a row and down a column,
  each within `_AXIS_COS` of an axis,
  the three a right-handed frame, and the turned frame a pinhole's grid about the origin
  (resolution.py). The optical frame itself is told by the mean ray alone, so it costs a
  sample's mean.
- a camera rolled about its optical axis (mounted upside down or on its side, as wrist
  cameras are; `quarter_turns_for`): told once the table is found, by its normal seen in
  the image. When the camera looks 30 degrees or more off straight down (the normal's
  in-image part at least `_TILT_MIN`) and that part points more than 60 degrees away
  from the image's top, the image is turned by quarter turns until it points nearest to
  the top, and segmented again. Looking straight down an image has no top, and within 60
  degrees of upright it is segmented as it is (as before: no frame so far was rolled).

`Orientation` does the turn and undoes it: the frame's points, colours and per-pixel
fields moved to the working image; the segmentation's indices and every point and
direction moved back to the frame's own.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from clearcli.io.frames import Frame
from clearcli.perception.openings import Opening
from clearcli.perception.resolution import pixel_pitch
from clearcli.perception.types import Segmentation, TablePlane

# the rays' steps along a row and down a column lie on the image's axes: within 25 degrees
_AXIS_COS = 0.9
# the mean point lies within half the field of view of the axis the camera looks along
# (a wide RealSense's 87 degrees across: 44): within 45 degrees, the nearest axis, which
# the steps then confirm
_FORWARD_COS = math.sqrt(0.5)
# the mean point from a sample of about this many pixels
_SAMPLE = 2048
# the camera looks far enough off straight down for the image to have a top: the table's
# normal (towards the camera) has at least this much in the image's plane (30 degrees)
_TILT_MIN = 0.5
# and the image is rolled when that part points more than 60 degrees from the image's
# top (-y): cos 60
_UPRIGHT_COS = 0.5


@dataclass(frozen=True)
class Orientation:
    """working[:, i] = sign[i] * frame[:, perm[i]] for every point, and the working image
    the frame's turned by ``quarter_turns`` (np.rot90's k) after that."""

    perm: tuple[int, int, int] = (0, 1, 2)
    sign: tuple[float, float, float] = (1.0, 1.0, 1.0)
    quarter_turns: int = 0

    @property
    def identity(self) -> bool:
        return self.perm == (0, 1, 2) and self.sign == (1.0, 1.0, 1.0) and self.quarter_turns % 4 == 0

    def rolled(self, k: int) -> Orientation:
        """This one, then the image turned by ``k`` more quarter turns: per quarter turn the
        image's right becomes its former down, its down its former left."""
        perm, sign = list(self.perm), list(self.sign)
        for _ in range(k % 4):
            perm = [perm[1], perm[0], perm[2]]
            sign = [sign[1], -sign[0], sign[2]]
        p0, p1, p2 = perm
        s0, s1, s2 = sign
        return Orientation((p0, p1, p2), (s0, s1, s2), (self.quarter_turns + k) % 4)

    def _pixels(self, shape: tuple[int, int]) -> np.ndarray:
        """(N,) the frame's pixel of each working pixel."""
        h, w = shape
        return np.ascontiguousarray(np.rot90(np.arange(h * w).reshape(h, w), self.quarter_turns)).reshape(-1)

    def _points(self, points: np.ndarray) -> np.ndarray:
        out = np.empty_like(points)
        for i in range(3):
            np.multiply(points[:, self.perm[i]], points.dtype.type(self.sign[i]), out=out[:, i])
        return out

    def back(self, vectors: np.ndarray) -> np.ndarray:
        """Points or directions (..., 3) of the working frame in the frame's own."""
        v = np.asarray(vectors, dtype=np.float64)
        out = np.empty_like(v)
        for i in range(3):
            out[..., self.perm[i]] = self.sign[i] * v[..., i]
        return out

    def frame(self, frame: Frame) -> Frame:
        """The working frame: ``frame``'s points turned, and its pixels (points, colours,
        per-pixel fields) rolled."""
        points = self._points(frame.points)
        if self.quarter_turns % 4 == 0 or frame.shape is None:
            return dataclasses.replace(frame, points=points)
        h, w = frame.shape
        at = self._pixels((h, w))
        n = frame.n_points
        shape = (h, w) if self.quarter_turns % 2 == 0 else (w, h)
        return dataclasses.replace(
            frame,
            points=np.take(points, at, axis=0),
            colors=None if frame.colors is None else np.take(frame.colors, at, axis=0),
            shape=shape,
            fields={
                name: np.take(np.asarray(v), at, axis=0) if np.shape(v)[:1] == (n,) else v
                for name, v in frame.fields.items()
            },
        )

    def segmentation_back(self, seg: Segmentation, frame: Frame) -> Segmentation:
        """``seg`` of the working frame in ``frame``'s own pixels and coordinates."""
        if self.quarter_turns % 4 == 0 or frame.shape is None:

            def pixels(idx: np.ndarray) -> np.ndarray:
                return idx
        else:
            at = self._pixels(frame.shape)

            def pixels(idx: np.ndarray) -> np.ndarray:
                return np.sort(np.take(at, idx))

        def opening(o: Opening) -> Opening:
            rim = o.rim
            return (
                o if rim is None else dataclasses.replace(o, rim=dataclasses.replace(rim, center=self.back(rim.center)))
            )

        turned_normal = self.back(seg.table.normal)
        return dataclasses.replace(
            seg,
            table=TablePlane(normal=turned_normal, offset=seg.table.offset),
            table_polygon=self.back(seg.table_polygon),
            table_indices=pixels(seg.table_indices),
            objects=tuple(
                dataclasses.replace(
                    o,
                    indices=pixels(o.indices),
                    centroid=self.back(o.centroid),
                    obb_center=self.back(o.obb_center),
                    obb_axes=self.back(o.obb_axes),
                    principal_axes=self.back(o.principal_axes),
                )
                for o in seg.objects
            ),
            support=tuple(
                dataclasses.replace(v, normal=tuple(float(x) for x in self.back(np.array(v.normal))))  # type: ignore[arg-type]
                for v in seg.support
            ),
            openings=tuple(opening(o) for o in seg.openings),
            table_edges=tuple(
                dataclasses.replace(e, start=self.back(e.start), end=self.back(e.end)) for e in seg.table_edges
            ),
            excluded=tuple(
                dataclasses.replace(e, indices=pixels(e.indices), centroid=self.back(e.centroid)) for e in seg.excluded
            ),
        )


def _axis(v: np.ndarray, within_cos: float = _AXIS_COS) -> tuple[int, float] | None:
    """(axis, sign) of the axis ``v`` lies within ``within_cos`` of, or None."""
    norm = float(np.linalg.norm(v))
    if not norm > 0:
        return None
    k = int(np.argmax(np.abs(v)))
    if abs(float(v[k])) < within_cos * norm:
        return None
    return k, 1.0 if v[k] > 0 else -1.0


def _mean_step(rays: np.ndarray) -> np.ndarray:
    """The mean difference of neighbouring unit rays along axis 1 of (a, b, 3) ``rays``."""
    step = rays[:, 1:] - rays[:, :-1]
    ok = np.isfinite(step).all(axis=2)
    return step[ok].mean(axis=0) if ok.any() else np.zeros(3)


def axes_turn(frame: Frame) -> Orientation | None:
    """The turn of ``frame``'s axes into the optical frame's when it is an organized pinhole
    image in another axis convention about the camera (module docstring); None for the
    optical frame itself, an unorganized cloud, or a grid that is no camera image."""
    shape = frame.shape
    points = frame.points
    if not frame.is_organized or shape is None or points.ndim != 2 or shape[0] * shape[1] != points.shape[0]:
        return None
    # the mean of a sample of the points: it lies inside the cone of the image's rays, so
    # within half the field of view (up to some 45 degrees) of the axis the camera looks along
    sample = points[:: max(1, points.shape[0] // _SAMPLE)]
    sample = sample[np.isfinite(sample).all(axis=1)]
    if sample.shape[0] < 100:
        return None
    forward = _axis(sample.mean(axis=0, dtype=np.float64), _FORWARD_COS)
    if forward is None or forward == (2, 1.0):
        return None  # the optical frame's +z, or no axis: read as it is, as before
    h, w = shape
    grid = np.asarray(points, dtype=np.float64).reshape(h, w, 3)
    with np.errstate(invalid="ignore", divide="ignore"):
        rows = grid[:: max(1, h // 60)]
        rows = rows / np.linalg.norm(rows, axis=2, keepdims=True)
        cols = grid[:, :: max(1, w // 80)].transpose(1, 0, 2)
        cols = cols / np.linalg.norm(cols, axis=2, keepdims=True)
        right, down = _axis(_mean_step(rows)), _axis(_mean_step(cols))
    if right is None or down is None or len({right[0], down[0], forward[0]}) != 3:
        return None
    turn = Orientation((right[0], down[0], forward[0]), (right[1], down[1], forward[1]))
    matrix = np.zeros((3, 3))
    for i in range(3):
        matrix[i, turn.perm[i]] = turn.sign[i]
    if np.linalg.det(matrix) < 0:
        return None  # a mirror image: no turn of a camera gives it
    if pixel_pitch(turn.frame(frame).points, shape) is None:
        return None
    return turn


def quarter_turns_for(normal: np.ndarray) -> int:
    """How many quarter turns (np.rot90's k) bring the table's ``normal`` (towards the
    camera, in the working optical frame) seen in the image nearest to the image's top;
    0 when the camera looks nearly straight down or the image is within 60 degrees of
    upright (module docstring)."""
    x, y = float(normal[0]), float(normal[1])
    part = float(np.hypot(x, y))
    if part < _TILT_MIN or -y >= _UPRIGHT_COS * part:
        return 0
    # per quarter turn the in-image vector (x, y) becomes (y, -x): up (-y) after k turns
    ups = [-y, x, y, -x]  # the working y of the vector after k = 0, 1, 2, 3 turns, negated
    return int(np.argmax(ups))
