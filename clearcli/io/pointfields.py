"""Turning a packed point record array (PCD data, PointCloud2 / foxglove blobs) into a `Frame`.

Every reader ends here so that all formats agree on what x/y/z, colour and the extra fields
become. Everything is vectorised: a blob is viewed through a NumPy structured dtype and
split into columns; nothing loops over points in Python.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clearcli.io.frames import Frame

# sensor_msgs/PointField datatypes (same numbering in ROS 1 and ROS 2).
ROS_DATATYPES: dict[int, str] = {
    1: "i1",
    2: "u1",
    3: "i2",
    4: "u2",
    5: "i4",
    6: "u4",
    7: "f4",
    8: "f8",
}
ROS_DATATYPE_OF: dict[str, int] = {v: k for k, v in ROS_DATATYPES.items()}

# foxglove.PackedElementField.NumericType.
FOXGLOVE_TYPES: dict[int, str] = {
    1: "u1",
    2: "i1",
    3: "u2",
    4: "i2",
    5: "u4",
    6: "i4",
    7: "f4",
    8: "f8",
}
FOXGLOVE_TYPE_NAMES: dict[str, int] = {
    "UINT8": 1,
    "INT8": 2,
    "UINT16": 3,
    "INT16": 4,
    "UINT32": 5,
    "INT32": 6,
    "FLOAT32": 7,
    "FLOAT64": 8,
}

# Colour fields consumed into Frame.colors (and so not repeated in Frame.fields).
_PACKED_COLOUR_FIELDS = ("rgb", "rgba")
_CHANNEL_COLOUR_FIELDS = (("r", "g", "b"), ("red", "green", "blue"))


@dataclass(frozen=True)
class FieldSpec:
    """One field of a packed point record: name, byte offset, NumPy scalar code, count."""

    name: str
    offset: int
    code: str  # "f4", "u1", ... (no byte order)
    count: int = 1


def unpack_rgb(values: np.ndarray) -> np.ndarray:
    """Packed 0x(AA)RRGGBB, stored as uint32 or as the bits of a float32 -> (N, 3) uint8."""
    values = np.ascontiguousarray(values)
    if values.dtype.itemsize != 4:
        raise ValueError(f"packed colour must be 4 bytes per point, got {values.dtype}")
    packed = values.view(np.uint32)
    # The little-endian bytes of 0xAARRGGBB are B, G, R, A: take them without shifting.
    as_bytes = packed.astype("<u4", copy=False).view(np.uint8).reshape(-1, 4)
    return np.ascontiguousarray(as_bytes[:, 2::-1])


def pack_rgb_float(colors: np.ndarray) -> np.ndarray:
    """(N, 3) uint8 RGB -> (N,) float32 whose bits are 0x00RRGGBB, as PCL stores `rgb`."""
    colors = np.asarray(colors, dtype=np.uint8)
    packed = (
        (colors[:, 0].astype(np.uint32) << 16) | (colors[:, 1].astype(np.uint32) << 8) | colors[:, 2].astype(np.uint32)
    )
    return packed.view(np.float32)


def blob_dtype(specs: list[FieldSpec], point_step: int, big_endian: bool = False) -> np.dtype:
    """Structured dtype with explicit offsets, one record per `point_step` bytes."""
    order = ">" if big_endian else "<"
    names, formats, offsets = [], [], []
    for spec in specs:
        base = np.dtype(order + spec.code)
        names.append(spec.name)
        formats.append(base if spec.count == 1 else (base, (spec.count,)))
        offsets.append(spec.offset)
    return np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": point_step})


def check_specs(specs: list[FieldSpec], point_step: int) -> str | None:
    """Why these fields cannot describe a `point_step`-byte record, or None when they can."""
    if point_step <= 0:
        return f"point_step is {point_step}"
    seen: set[str] = set()
    for spec in specs:
        if spec.name in seen:
            return f"field {spec.name!r} appears twice"
        seen.add(spec.name)
        end = spec.offset + np.dtype(spec.code).itemsize * max(spec.count, 1)
        if spec.offset < 0 or end > point_step or spec.count < 1:
            return (
                f"field {spec.name!r} (offset {spec.offset}, count {spec.count}) does not fit a {point_step}-byte point"
            )
    return None


def records_from_blob(
    data: bytes | bytearray | memoryview,
    specs: list[FieldSpec],
    point_step: int,
    width: int,
    height: int,
    row_step: int,
    big_endian: bool = False,
) -> np.ndarray:
    """(height*width,) structured view of a row-major point blob; rows may carry padding.

    Raises ValueError when the blob is shorter than the layout says.
    """
    dtype = blob_dtype(specs, point_step, big_endian)
    n = width * height
    buf = np.frombuffer(data, dtype=np.uint8)
    if n == 0:
        return np.empty(0, dtype=dtype)
    row_bytes = width * point_step
    if row_step < row_bytes:
        raise ValueError(f"row_step {row_step} < width {width} * point_step {point_step}")
    # The last row needs only its points, not the row padding.
    needed = (height - 1) * row_step + row_bytes
    if buf.size < needed:
        raise ValueError(f"data holds {buf.size} bytes, the layout needs {needed}")
    if row_step == row_bytes:
        return buf[: n * point_step].view(dtype)
    rows = np.lib.stride_tricks.as_strided(buf, shape=(height, row_bytes), strides=(row_step, 1))
    return np.ascontiguousarray(rows).reshape(-1).view(dtype)


def _column(col: np.ndarray) -> np.ndarray:
    """A field's column as the frame keeps it: contiguous, native byte order, its own
    writable array (a column read straight from a file's bytes is copied)."""
    # Native byte order so that later arithmetic and comparisons are cheap and unsurprising.
    if not col.dtype.isnative:
        col = col.astype(col.dtype.newbyteorder("="))
    col = np.ascontiguousarray(col)
    return col if col.flags.writeable else col.copy()


def _native(col: np.ndarray) -> np.ndarray:
    """A column in native byte order, contiguous (unpack_rgb reads it and keeps nothing)."""
    if not col.dtype.isnative:
        col = col.astype(col.dtype.newbyteorder("="))
    return np.ascontiguousarray(col)


def frame_from_records(
    records: np.ndarray,
    shape: tuple[int, int] | None,
    *,
    stamp_s: float = 0.0,
    frame_id: str = "",
    source: str = "",
    skip: tuple[str, ...] = (),
) -> Frame:
    """Split a structured record array into a Frame.

    x/y/z -> points (float32); `rgb`/`rgba` (packed uint32 or float bits) or r/g/b
    (red/green/blue) uint8 channels -> colors; every other field, except those in `skip`,
    -> Frame.fields under its own name with its own dtype ((N,) or (N, count)).
    The caller has checked that x, y and z exist.
    """
    return frame_from_columns(
        record_columns(records), shape, stamp_s=stamp_s, frame_id=frame_id, source=source, skip=skip
    )


def record_columns(records: np.ndarray) -> dict[str, np.ndarray]:
    """A structured record array's fields by name, as columns (views), in its order."""
    return {name: records[name] for name in records.dtype.names or ()}


def frame_from_columns(
    columns: dict[str, np.ndarray],
    shape: tuple[int, int] | None,
    *,
    stamp_s: float = 0.0,
    frame_id: str = "",
    source: str = "",
    skip: tuple[str, ...] = (),
) -> Frame:
    """`frame_from_records` of the fields given as columns, (N,) or (N, count) each, in
    the records' order (a compressed PCD holds them so: no record array between, issue 39)."""
    names = list(columns)
    n = columns["x"].shape[0]
    points = np.empty((n, 3), dtype=np.float32)
    # a float64 coordinate beyond float32's range becomes inf, an invalid point as NaN is,
    # without numpy's overflow warning (damaged or absurd data, not a sensor's)
    with np.errstate(over="ignore", invalid="ignore"):
        for axis, name in enumerate(("x", "y", "z")):
            points[:, axis] = columns[name]
        # a NaN whose bits a damaged file made a signalling one would raise numpy's
        # "invalid value" warning at the first cast or sum downstream: times 1 makes it a
        # quiet NaN and leaves every other value as it is, bit for bit (-0.0 and inf too)
        np.multiply(points, np.float32(1.0), out=points)
    consumed = {"x", "y", "z", *skip}
    colors: np.ndarray | None = None
    for name in _PACKED_COLOUR_FIELDS:
        if name in names and columns[name].ndim == 1 and columns[name].dtype.itemsize == 4:
            colors = unpack_rgb(_native(columns[name]))
            consumed.add(name)
            break
    if colors is None:
        for triple in _CHANNEL_COLOUR_FIELDS:
            if all(c in names and columns[c].ndim == 1 and columns[c].dtype == np.uint8 for c in triple):
                colors = np.stack([columns[c] for c in triple], axis=1)
                consumed.update(triple)
                if triple == ("red", "green", "blue"):
                    consumed.add("alpha")
                else:
                    consumed.add("a")
                break
    fields = {name: _column(columns[name]) for name in names if name not in consumed}
    return Frame(
        points=points,
        colors=colors,
        shape=shape,
        fields=fields,
        stamp_s=float(stamp_s),
        frame_id=frame_id,
        source=source,
    )
