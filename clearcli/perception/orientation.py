"""Which way a camera's frame looks, and which way is up in it (issue 37: frames of labs
no one here has seen).

The steps read an organized frame as a camera image in the optical frame (x right, y down
the image, z forward, the camera at the origin), the right way up (the table's normal,
seen in the image, towards its top): depth is read along +z, the table's far side up the
image. Four kinds of frames meet that only after a turn. All but the moved image's turn
keeps every coordinate or negates it and moves it to another axis, and moves pixels
whole, so it is exact in floating point, and the steps see the very points of the
upright optical image:

- another axis convention about the same camera (`axes_turn`): OpenGL's (y up, looking
  along -z: Open3D's tutorials turn their clouds so, ARKit and Unity write them so), ROS's
  camera_link (x forward, y left, z up), and the rest. Told from the rays: the mean point
  nearest an axis (`_FORWARD_COS`), and the rays' steps along a row and down a column,
  each within `_AXIS_COS` of an axis, the three a right-handed frame, and the turned
  frame a pinhole's grid about the origin (resolution.py). The optical frame itself is
  told by its pixel pitch (`resolution.pixel_pitch` reads, which `segment` reads anyway
  for the working grid's stride; `axes_turn` alone: the mean point and a coarse probe).
- a camera image moved into another frame (a cloud transformed into a robot's base frame,
  organized still, as ROS's transforms keep it; `camera_pose`): its pixels' points are a
  pinhole's image seen from elsewhere, and the camera's pose follows from them (the
  direct linear transform of points to pixels). The image is moved into the camera's
  frame (rounded to the frame's dtype: not exact, micrometre changes) and the results
  moved back. Tried when the frame is no pinhole image about its origin in any axis
  convention.
- an unorganized cloud in a camera frame (`cloud_turn`): no pixels, so forward is the
  axis its mean point lies nearest and up the one the table's normal leans along; the
  same signed reordering, exact.
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
from clearcli.perception.types import PlaneVerdict, Segmentation, TablePlane

# the rays' steps along a row and down a column lie on the image's axes: within 25 degrees
_AXIS_COS = 0.9
# the mean point lies within half the field of view of the axis the camera looks along
# (a wide RealSense's 87 degrees across: 44): within 45 degrees, the nearest axis, which
# the steps then confirm
_FORWARD_COS = math.sqrt(0.5)
# the mean point from a sample of about this many pixels
_SAMPLE = 2048
# the optical frame's pinhole grid told cheaply: every this many rows and columns probed
_COARSE_PROBE = 32
# a camera's pose from about this many pixels' points (camera_pose)
_POSE_SAMPLE = 3000
# a pinhole's image: its pixels' points reproject onto their pixels within this (median;
# four times this for every one): a depth image's back-projection is exact but for the
# points' float32 rounding (far below a hundredth of a pixel)
_REPROJECTION_PX = 0.25
# the projection is unique when its singular value is this many times below the next
# (moved mOSD and RealSense frames: 1e5 to 1e6; points all on one plane: about 1)
_UNIQUE_RATIO = 1000.0
# the camera looks far enough off straight down for the image to have a top: the table's
# normal (towards the camera) has at least this much in the image's plane (30 degrees)
_TILT_MIN = 0.5
# and the image is rolled when that part points more than 60 degrees from the image's
# top (-y): cos 60
_UPRIGHT_COS = 0.5


@dataclass(frozen=True, eq=False)
class Orientation:
    """working[:, i] = sign[i] * frame[:, perm[i]] for every point, and the working image
    the frame's turned by ``quarter_turns`` (np.rot90's k) after that."""

    perm: tuple[int, int, int] = (0, 1, 2)
    sign: tuple[float, float, float] = (1.0, 1.0, 1.0)
    quarter_turns: int = 0
    # first, before the axes' turn: the camera's pose recovered from the grid (`camera_pose`),
    # camera = R_camera_frame @ frame + t_camera_frame (not exact: rounded to the frame's dtype)
    R_camera_frame: np.ndarray | None = None
    t_camera_frame: np.ndarray | None = None

    @property
    def identity(self) -> bool:
        return (
            self.perm == (0, 1, 2)
            and self.sign == (1.0, 1.0, 1.0)
            and self.quarter_turns % 4 == 0
            and self.R_camera_frame is None
        )

    def describe(self) -> str:
        """How the frame was read, for the chosen support's ``why`` in --json."""
        parts = []
        if self.R_camera_frame is not None:
            parts.append("a camera image in another frame, read in its camera's frame (its pose from its pixels)")
        axes_only = self.rolled(-self.quarter_turns)
        if axes_only.perm != (0, 1, 2) or axes_only.sign != (1.0, 1.0, 1.0):
            names = "xyz"
            axes = ", ".join(
                f"{'-' if s < 0 else ''}{names[p]}" for p, s in zip(axes_only.perm, axes_only.sign, strict=True)
            )
            parts.append(f"the frame's axes turned into the optical frame's: x, y, z = {axes}")
        if self.quarter_turns % 4:
            turn = ("", "90 degrees counter-clockwise", "180 degrees", "90 degrees clockwise")[self.quarter_turns % 4]
            parts.append(f"the image turned {turn} to be the right way up")
        return "; ".join(parts)

    def rolled(self, k: int) -> Orientation:
        """This one, then the image turned by ``k`` more quarter turns: per quarter turn the
        image's right becomes its former down, its down its former left."""
        perm, sign = list(self.perm), list(self.sign)
        for _ in range(k % 4):
            perm = [perm[1], perm[0], perm[2]]
            sign = [sign[1], -sign[0], sign[2]]
        p0, p1, p2 = perm
        s0, s1, s2 = sign
        return dataclasses.replace(
            self, perm=(p0, p1, p2), sign=(s0, s1, s2), quarter_turns=(self.quarter_turns + k) % 4
        )

    def _pixels(self, shape: tuple[int, int]) -> np.ndarray:
        """(N,) the frame's pixel of each working pixel."""
        h, w = shape
        return np.ascontiguousarray(np.rot90(np.arange(h * w).reshape(h, w), self.quarter_turns)).reshape(-1)

    def _points(self, points: np.ndarray) -> np.ndarray:
        if self.R_camera_frame is not None and self.t_camera_frame is not None:
            camera = points.astype(np.float64) @ self.R_camera_frame.T + self.t_camera_frame
            points = camera.astype(points.dtype)
        out = np.empty_like(points)
        for i in range(3):
            np.multiply(points[:, self.perm[i]], points.dtype.type(self.sign[i]), out=out[:, i])
        return out

    def back(self, vectors: np.ndarray, points: bool = True) -> np.ndarray:
        """Points (or directions: ``points`` False) (..., 3) of the working frame in the
        frame's own."""
        v = np.asarray(vectors, dtype=np.float64)
        out = np.empty_like(v)
        for i in range(3):
            out[..., self.perm[i]] = self.sign[i] * v[..., i]
        if self.R_camera_frame is not None and self.t_camera_frame is not None:
            out = (out - self.t_camera_frame if points else out) @ self.R_camera_frame
        return out

    def offset_back(self, offset: float, normal: np.ndarray) -> float:
        """A plane's offset in the frame's own coordinates (``normal``: the working one):
        n . p_camera + d = 0 with p_camera = R p + t gives (R^T n) . p + (d + n . t) = 0;
        the axes' turn moves no plane's distance from the origin."""
        R, t = self.R_camera_frame, self.t_camera_frame
        if R is None or t is None:
            return float(offset)
        camera_normal = np.empty(3)
        for i in range(3):
            camera_normal[self.perm[i]] = self.sign[i] * float(normal[i])
        return float(offset) + float(camera_normal @ t)

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

        def verdict(v: PlaneVerdict) -> PlaneVerdict:
            normal = np.array(v.normal)
            x, y, z = (float(c) for c in self.back(normal, points=False))
            why = f"{v.why} ({self.describe()})" if v.chosen else v.why
            return dataclasses.replace(v, normal=(x, y, z), offset_m=self.offset_back(v.offset_m, normal), why=why)

        table = seg.table
        return dataclasses.replace(
            seg,
            table=TablePlane(
                normal=self.back(table.normal, points=False), offset=self.offset_back(table.offset, table.normal)
            ),
            table_polygon=self.back(seg.table_polygon),
            table_indices=pixels(seg.table_indices),
            objects=tuple(
                dataclasses.replace(
                    o,
                    indices=pixels(o.indices),
                    centroid=self.back(o.centroid),
                    obb_center=self.back(o.obb_center),
                    obb_axes=self.back(o.obb_axes, points=False),
                    principal_axes=self.back(o.principal_axes, points=False),
                )
                for o in seg.objects
            ),
            support=tuple(verdict(v) for v in seg.support),
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
    """The turn of ``frame`` into the optical frame of its camera when it is an organized
    pinhole image in another axis convention about the camera, or a camera image moved
    into another frame (module docstring); None for the optical frame itself, an
    unorganized cloud, or a grid that is no camera image."""
    shape = frame.grid
    points = frame.points
    if shape is None or points.ndim != 2:
        return None
    # the mean of a sample of the points: it lies inside the cone of the image's rays, so
    # within half the field of view (up to some 45 degrees) of the axis the camera looks along
    sample = points[:: max(1, points.shape[0] // _SAMPLE)]
    sample = sample[np.isfinite(sample).all(axis=1)]
    if sample.shape[0] < 100:
        return None
    forward = _axis(sample.mean(axis=0, dtype=np.float64), _FORWARD_COS)
    if forward == (2, 1.0) and pixel_pitch(points, shape, _COARSE_PROBE) is not None:
        return None  # the optical frame: read as it is
    turn = _signed_axes(frame, forward) if forward is not None else None
    if turn is not None:
        return turn
    pose = camera_pose(points, shape)
    if pose is None:
        return None  # no camera image: read as it is, as before
    return Orientation(R_camera_frame=pose[0], t_camera_frame=pose[1])


def _signed_axes(frame: Frame, forward: tuple[int, float]) -> Orientation | None:
    """The signed reordering of ``frame``'s axes that makes it an optical pinhole image
    about the origin (the camera looking along ``forward``), or None."""
    assert frame.shape is not None
    h, w = frame.shape
    grid = frame.points.reshape(h, w, 3)
    with np.errstate(invalid="ignore", divide="ignore"):
        # some 16 rows and 16 columns, in float64 (not the whole grid): thousands of steps
        rows = grid[:: max(1, h // 16)].astype(np.float64)
        rows /= np.linalg.norm(rows, axis=2, keepdims=True)
        cols = grid[:, :: max(1, w // 16)].transpose(1, 0, 2).astype(np.float64)
        cols /= np.linalg.norm(cols, axis=2, keepdims=True)
        right, down = _axis(_mean_step(rows)), _axis(_mean_step(cols))
    if right is None or down is None or len({right[0], down[0], forward[0]}) != 3:
        return None
    turn = Orientation((right[0], down[0], forward[0]), (right[1], down[1], forward[1]))
    if turn.identity:
        return None  # the optical axes, yet no pinhole about the origin: moved (camera_pose)
    matrix = np.zeros((3, 3))
    for i in range(3):
        matrix[i, turn.perm[i]] = turn.sign[i]
    if np.linalg.det(matrix) < 0:
        return None  # a mirror image: no turn of a camera gives it
    if pixel_pitch(turn.frame(frame).points, frame.shape, _COARSE_PROBE) is None:
        return None
    return turn


def camera_pose(points: np.ndarray, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray] | None:
    """(R_camera_frame, t_camera_frame): the pose of the pinhole camera whose image the
    organized ``points`` (of ``shape``) are, camera = R @ point + t in its optical frame;
    None when they are no pinhole's image (their pixels' reprojection off by more than
    `_REPROJECTION_PX`), or already in its optical frame about the origin.

    Every pixel's point is a 3D point seen at that pixel: the camera's 3 x 4 projection
    follows from a sample of them by the direct linear transform (Hartley's normalised
    DLT), and its RQ decomposition gives the intrinsics and the pose."""
    h, w = shape
    flat = np.flatnonzero(np.isfinite(points).all(axis=1))
    if flat.size < 100:
        return None
    flat = flat[:: max(1, flat.size // _POSE_SAMPLE)]
    X = points[flat].astype(np.float64)
    uv = np.stack([flat % w, flat // w], axis=1).astype(np.float64)
    mean_x, mean_uv = X.mean(axis=0), uv.mean(axis=0)
    with np.errstate(all="ignore"):
        spread_x = float(np.mean(np.linalg.norm(X - mean_x, axis=1)))
        spread_uv = float(np.mean(np.linalg.norm(uv - mean_uv, axis=1)))
    if not (0.0 < spread_x < 1e6 and 0.0 < spread_uv):
        return None  # one point repeated, or coordinates no camera gives
    try:
        return _pose_of(X, uv, mean_x, mean_uv, math.sqrt(3.0) / spread_x, math.sqrt(2.0) / spread_uv)
    except np.linalg.LinAlgError:
        return None


def _pose_of(
    X: np.ndarray, uv: np.ndarray, mean_x: np.ndarray, mean_uv: np.ndarray, scale_x: float, scale_uv: float
) -> tuple[np.ndarray, np.ndarray] | None:
    """`camera_pose` of the points ``X`` seen at the pixels ``uv`` (their means and the
    scales that normalise them given)."""
    xn, un = (X - mean_x) * scale_x, (uv - mean_uv) * scale_uv
    rows = np.zeros((2 * X.shape[0], 12))
    rows[0::2, 0:3], rows[0::2, 3] = xn, 1.0
    rows[0::2, 8:11], rows[0::2, 11] = -un[:, :1] * xn, -un[:, 0]
    rows[1::2, 4:7], rows[1::2, 7] = xn, 1.0
    rows[1::2, 8:11], rows[1::2, 11] = -un[:, 1:] * xn, -un[:, 1]
    # the least singular vector of rows, from the 12 x 12 normal matrix (the data
    # normalised: well conditioned), not an SVD of the (2N, 12) rows (100 times the time)
    values, vectors = np.linalg.eigh(rows.T @ rows)
    # one projection only: points all on a plane (an empty table) fit a family of them
    # (each the same on the plane, different off it), their least two values alike
    # (the least may come out as rounding's noise, even below 0: a floor of the largest's
    # 1e-15, so that a plane's points, whose least few are all such noise, are refused)
    if not values[1] > _UNIQUE_RATIO**2 * max(values[0], 1e-15 * values[-1]):
        return None
    projection_n = vectors[:, 0].reshape(3, 4)
    to_uv = np.array([[scale_uv, 0.0, -scale_uv * mean_uv[0]], [0.0, scale_uv, -scale_uv * mean_uv[1]], [0, 0, 1]])
    to_x = np.eye(4)
    to_x[:3, :3] *= scale_x
    to_x[:3, 3] = -scale_x * mean_x
    projection = np.linalg.solve(to_uv, projection_n @ to_x)
    m = projection[:, :3]
    if np.linalg.det(m) < 0:
        projection, m = -projection, -m
    # RQ of m by the QR of its rows reversed: m = K R, K upper triangular, diag(K) > 0
    flip = np.eye(3)[::-1]
    q, r = np.linalg.qr((flip @ m).T)
    K, R = flip @ r.T @ flip, flip @ q.T
    signs = np.diag(np.sign(np.diag(K)))
    K, R = K @ signs, signs @ R
    if np.linalg.det(R) < 0 or not K[2, 2] > 0:
        return None
    # projection = K [R | t] up to its scale, which K carries until it is normalised
    t = np.linalg.solve(K, projection[:, 3])
    K = K / K[2, 2]
    camera = X @ R.T + t
    if not (K[0, 0] > 0 and K[1, 1] > 0 and abs(K[0, 1]) <= 0.01 * K[0, 0]) or np.mean(camera[:, 2] > 0) < 0.99:
        return None
    seen = camera @ K.T
    error = np.linalg.norm(seen[:, :2] / seen[:, 2:] - uv, axis=1)
    if float(np.median(error)) > _REPROJECTION_PX or float(error.max()) > 4 * _REPROJECTION_PX:
        return None
    if np.abs(R - np.eye(3)).max() < 1e-4 and float(np.abs(t).max()) < 1e-4:
        return None  # its own optical frame already
    return R, t


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


def cloud_turn(points: np.ndarray, normal: np.ndarray) -> Orientation | None:
    """The turn of an unorganized cloud in a camera frame (its ``points``, the table's
    ``normal`` towards the camera at the origin) into the optical frame's axes, the right
    way up, or None when it is in them already (within 60 degrees of upright, as
    `quarter_turns_for` reads an image) or looks along no axis.

    Without pixels the axes are told by the view: forward is the axis the mean point lies
    nearest (within 45 degrees), and the image's "up" the one the table's normal leans
    along, across forward. The turn only reorders and negates coordinates: the cloud's
    objects become those of the same points in the optical frame's axes (the voxel grid
    lies along the axes, so the axes matter), exactly."""
    forward = _axis(np.asarray(points, dtype=np.float64).mean(axis=0), _FORWARD_COS)
    if forward is None:
        return None
    k, s = forward
    # a right-handed frame with z along forward: x and y the next axes in cyclic order
    provisional = Orientation(((k + 1) % 3, (k + 2) % 3, k), (1.0, s, s))
    working_normal = provisional._points(np.asarray(normal, dtype=np.float64)[None])[0]
    rolled = provisional.rolled(quarter_turns_for(working_normal))
    turn = Orientation(rolled.perm, rolled.sign)  # no pixels to move: the axes alone
    return None if turn.identity else turn
