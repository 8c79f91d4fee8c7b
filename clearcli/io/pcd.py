"""PCD files <-> `Frame`.

Reading: the header is parsed here (`_parse_metadata`, the rules of pypcd4 1.5.1's
`MetaData.parse_header` and of its pydantic model, checked in tests/io/test_pcd.py), the
data block decoded with NumPy and python-lzf (the decompressor pypcd4 itself uses).
pypcd4 is not imported to read: it imports pydantic, 0.13-0.2 s of every cold
`clear segment` / `plan` / `info` on a PCD (issue 39), for a header of a dozen ASCII lines.
pypcd4's own `PointCloud.from_path` is not used for the data either, because it trusts
the header: a binary file shorter than declared silently yields fewer points, it stops
looking for DATA after ten header lines, and it splits COUNT>1 fields of compressed files
into the wrong blocks. Here every size the header claims is checked against the file and
any failure becomes an `InputError` naming the file.

Writing: pypcd4 composes the header and the binary_compressed block (readable by PCL,
open3d and this reader); the file appears atomically.
"""

from __future__ import annotations

import math
import os
import re
import struct
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

import numpy as np

from clearcli.errors import InputError, OutputError
from clearcli.files import atomic_path
from clearcli.io.frames import Frame, labels_to_write
from clearcli.io.pointfields import frame_from_columns, pack_rgb_float, record_columns
from clearcli.io.sniff import PCD_HEADER_KEYS, open_input

# A PCD header is ten short lines; anything without DATA in the first 64 KiB is not a PCD.
_MAX_HEADER_BYTES = 1 << 16
_MAX_RECORD_BYTES = 1 << 20  # 1 MiB per point: see _parse_metadata
_HEADER_KEYS = tuple(k.decode() for k in PCD_HEADER_KEYS)
_PCD_CODES = {
    ("F", 4): "f4",
    ("F", 8): "f8",
    ("U", 1): "u1",
    ("U", 2): "u2",
    ("U", 4): "u4",
    ("U", 8): "u8",
    ("I", 1): "i1",
    ("I", 2): "i2",
    ("I", 4): "i4",
    ("I", 8): "i8",
}
# PCL's name of a padding field.
_PADDING = "_"
# A header line as pypcd4 1.5.1 reads it (its HEADER_PATTERN): a key, then the longest run
# of these characters; a line that does not match is skipped, as there.
_HEADER_LINE = re.compile(r"(\w+)\s+([\w\s\.\-?\d+\.?\d*]+)")
_ENCODINGS = ("ascii", "binary", "binary_compressed", "binaryscompressed")  # pypcd4's Encoding
_VERSIONS = (".7", "0.7")
_DEFAULT_VIEWPOINT = (0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class PcdHeader:
    """What a PCD header says (pypcd4's MetaData fields, same defaults)."""

    fields: tuple[str, ...]
    size: tuple[int, ...]
    type: tuple[str, ...]
    count: tuple[int, ...]
    points: int
    width: int
    height: int = 1
    version: str = "0.7"
    viewpoint: tuple[float, ...] = _DEFAULT_VIEWPOINT
    data: str = "binary_compressed"  # the encoding


class _BadHeader(ValueError):
    """A header value pypcd4's model would reject: "loc: msg" as pydantic words it."""


def _header_values(lines: list[str]) -> dict[str, object]:
    """pypcd4's parse_header: each known key's value, converted (a bad number raises
    ValueError here, as there); the last line of a key wins."""
    header: dict[str, object] = {}
    for line in lines:
        if line.startswith("#") or len(line) < 2:
            continue
        match = _HEADER_LINE.match(line)
        if match is None:
            continue
        value = match.group(2).split()
        key = match.group(1).lower()
        if key in ("version", "data"):
            header[key] = value[0]
        elif key in ("width", "height", "points"):
            header[key] = int(value[0])
        elif key in ("fields", "type"):
            header[key] = tuple(value)
        elif key in ("size", "count"):
            header[key] = tuple(int(v) for v in value)
        elif key == "viewpoint":
            header[key] = tuple(float(v) for v in value)
    return header


def _validated(values: dict[str, object]) -> PcdHeader:
    """pypcd4's MetaData model's checks on `_header_values`, in the order of its fields;
    the first failure raises `_BadHeader` with pydantic's wording."""

    def need(key: str) -> object:
        if key not in values:
            raise _BadHeader(f"{key}: Field required")
        return values[key]

    def positive(key: str) -> tuple[int, ...]:
        sizes: tuple[int, ...] = need(key)  # type: ignore[assignment]  # a tuple of int (_header_values)
        for i, v in enumerate(sizes):
            if v <= 0:
                raise _BadHeader(f"{key}.{i}: Input should be greater than 0")
        return sizes

    def non_negative(key: str, default: int | None = None) -> int:
        v: int = values.get(key, default) if default is not None else need(key)  # type: ignore[assignment]
        if v < 0:
            raise _BadHeader(f"{key}: Input should be greater than or equal to 0")
        return v

    fields: tuple[str, ...] = need("fields")  # type: ignore[assignment]  # a tuple of str
    size = positive("size")
    types: tuple[str, ...] = need("type")  # type: ignore[assignment]  # a tuple of str
    for i, t in enumerate(types):
        if t not in ("F", "U", "I"):
            raise _BadHeader(f"type.{i}: Input should be 'F', 'U' or 'I'")
    count = positive("count")
    points = non_negative("points")
    width = non_negative("width")
    height = non_negative("height", 1)
    version = str(values.get("version", "0.7"))
    if version not in _VERSIONS:
        raise _BadHeader("version: Input should be '.7' or '0.7'")
    viewpoint: tuple[float, ...] = values.get("viewpoint", _DEFAULT_VIEWPOINT)  # type: ignore[assignment]
    if len(viewpoint) < 7:
        raise _BadHeader(f"viewpoint.{len(viewpoint)}: Field required")
    if len(viewpoint) > 7:
        raise _BadHeader(f"viewpoint: Tuple should have at most 7 items after validation, not {len(viewpoint)}")
    if not all(math.isfinite(v) for v in viewpoint):
        # the sensor's pose: a NaN or inf there is damage, and would reach every output
        raise _BadHeader(f"viewpoint: every value should be a finite number, not {' '.join(map(str, viewpoint))}")
    data = str(values.get("data", "binary_compressed"))
    if data not in _ENCODINGS:
        listed = ", ".join(f"'{e}'" for e in _ENCODINGS[:-1])
        raise _BadHeader(f"data: Input should be {listed} or '{_ENCODINGS[-1]}'")
    return PcdHeader(fields, size, types, count, points, width, height, version, viewpoint, data)


def _read_header_lines(fp: BinaryIO, path: Path) -> tuple[list[str], int]:
    """Non-comment header lines up to and including DATA, and the byte offset of the data."""
    lines: list[str] = []
    offset = 0
    while True:
        raw = fp.readline(_MAX_HEADER_BYTES)
        if not raw:
            if not lines and offset == 0:
                raise InputError(f"{path}: empty file (0 bytes); expected a PCD file")
            raise InputError(f"{path}: not a PCD file: the header has no DATA line (file truncated?)")
        offset += len(raw)
        if offset > _MAX_HEADER_BYTES:
            raise InputError(f"{path}: not a PCD file: no DATA line in the first 64 KiB")
        try:
            line = raw.decode("ascii").strip()
        except UnicodeDecodeError:
            raise InputError(f"{path}: not a PCD file: binary bytes in the header") from None
        if not line or line.startswith("#"):
            continue
        key = line.split(None, 1)[0].upper()
        if not raw.endswith(b"\n") and key != "DATA":
            # readline stopped without a newline: the file ends inside the header.
            raise InputError(f"{path}: not a PCD file: the header has no DATA line (file truncated?)")
        if key not in _HEADER_KEYS:
            raise InputError(f"{path}: not a PCD file: unexpected header line {line[:40]!r}")
        lines.append(line)
        if key == "DATA":
            return lines, offset


def _parse_metadata(lines: list[str], path: Path) -> PcdHeader:
    keys = {line.split(None, 1)[0].upper() for line in lines}
    missing = [k for k in ("FIELDS", "SIZE", "TYPE", "WIDTH") if k not in keys]
    if missing:
        raise InputError(f"{path}: bad PCD header: no {', '.join(missing)} line")
    # PCL accepts headers without COUNT/HEIGHT/POINTS (defaults 1s, 1, WIDTH*HEIGHT);
    # pypcd4's model wants them, so they are filled in the same way.
    fields_line = next(line for line in lines if line.upper().startswith("FIELDS"))
    n_fields = len(fields_line.split()) - 1
    if "COUNT" not in keys:
        lines = lines[:-1] + ["COUNT " + " ".join(["1"] * n_fields)] + lines[-1:]
    if "HEIGHT" not in keys:
        lines = lines[:-1] + ["HEIGHT 1"] + lines[-1:]
    try:
        if "POINTS" not in keys:
            width = int(next(line for line in lines if line.upper().startswith("WIDTH")).split()[1])
            height = int(next(line for line in lines if line.upper().startswith("HEIGHT")).split()[1])
            lines = lines[:-1] + [f"POINTS {width * height}"] + lines[-1:]
        meta = _validated(_header_values(lines))
    except (ValueError, IndexError) as exc:  # a bad number, a check of the model (_BadHeader)
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InputError(f"{path}: bad PCD header ({reason})") from None
    lengths = {len(meta.fields), len(meta.size), len(meta.type), len(meta.count)}
    if len(lengths) != 1:
        raise InputError(
            f"{path}: bad PCD header: {len(meta.fields)} FIELDS but {len(meta.size)} SIZE, "
            f"{len(meta.type)} TYPE, {len(meta.count)} COUNT values"
        )
    for name, typ, size in zip(meta.fields, meta.type, meta.size):
        if (typ, size) not in _PCD_CODES:
            raise InputError(f"{path}: bad PCD header: field {name!r} has TYPE {typ} SIZE {size}")
    record_bytes = sum(size * count for size, count in zip(meta.size, meta.count))
    if record_bytes > _MAX_RECORD_BYTES:
        # PCL's largest point types (descriptor histograms) are a few kilobytes; a record
        # past this is a damaged header, and numpy cannot even describe one past 2 GiB
        raise InputError(
            f"{path}: bad PCD header: one point of {record_bytes} bytes (SIZE x COUNT summed over the "
            f"fields) is more than {_MAX_RECORD_BYTES} bytes; is COUNT right?"
        )
    if meta.points != meta.width * meta.height:
        raise InputError(
            f"{path}: bad PCD header: POINTS {meta.points} but WIDTH*HEIGHT = "
            f"{meta.width}*{meta.height} = {meta.width * meta.height}"
        )
    return meta


def _record_dtype(meta: PcdHeader) -> np.dtype:
    """Packed little-endian record dtype; COUNT>1 fields become sub-arrays, `_` padding `_pad<i>`."""
    names, formats = [], []
    for i, (name, typ, size, count) in enumerate(zip(meta.fields, meta.type, meta.size, meta.count)):
        base = np.dtype("<" + _PCD_CODES[(typ, size)])
        if name == _PADDING or name in names:
            name = f"_pad{i}"
        names.append(name)
        formats.append(base if count == 1 else (base, (count,)))
    return np.dtype({"names": names, "formats": formats})


def _decode_data(fp: BinaryIO, path: Path, meta: PcdHeader, dtype: np.dtype, data_bytes: int) -> dict[str, np.ndarray]:
    """The point data's fields by name, as columns ((N,) or (N, count)), in the header's order."""
    import lzf

    n = int(meta.points)
    need = n * dtype.itemsize
    encoding = meta.data
    if encoding == "ascii":
        try:
            with warnings.catch_warnings():
                # no rows at all: numpy warns beside returning none; the count check says it
                warnings.simplefilter("ignore", UserWarning)
                records = np.loadtxt(fp, dtype=dtype, ndmin=1, comments="#")
        except Exception as exc:
            first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise InputError(f"{path}: bad ASCII point data ({first[:120]})") from None
        if records.shape[0] != n:
            raise InputError(f"{path}: the header declares {n} points but the ASCII data has {records.shape[0]} rows")
        return record_columns(records)
    if encoding == "binary":
        if data_bytes < need:
            raise InputError(
                f"{path}: truncated PCD: the header declares {n} points of {dtype.itemsize} bytes "
                f"({need} bytes) but the data holds {data_bytes}"
            )
        return record_columns(np.frombuffer(fp.read(need), dtype=dtype, count=n))
    # binary_compressed: sizes, then an LZF block holding each field's column in turn.
    head = fp.read(8)
    if len(head) < 8:
        raise InputError(f"{path}: truncated PCD: the compressed block's size header is missing")
    compressed_size, uncompressed_size = struct.unpack("<II", head)
    if uncompressed_size != need:
        raise InputError(
            f"{path}: bad PCD: the header declares {n} points ({need} bytes) but the compressed "
            f"block unpacks to {uncompressed_size} bytes"
        )
    if data_bytes - 8 < compressed_size:
        raise InputError(
            f"{path}: truncated PCD: the compressed block should hold {compressed_size} bytes, "
            f"the file has {max(data_bytes - 8, 0)}"
        )
    if n == 0:
        return record_columns(np.empty(0, dtype=dtype))
    try:
        raw = lzf.decompress(fp.read(compressed_size), uncompressed_size)
    except Exception as exc:
        raise InputError(f"{path}: corrupt PCD: the compressed data cannot be unpacked ({exc})") from None
    if raw is None or len(raw) != uncompressed_size:
        raise InputError(f"{path}: corrupt PCD: the compressed data unpacks to the wrong size")
    # each field's column read where it lies in the unpacked bytes (a view: the frame copies
    # what it keeps), not written into a record array first and read back out of it
    columns = {}
    offset = 0
    fields = dtype.fields
    for name in dtype.names or ():
        assert fields is not None  # a structured dtype: a field per name
        field = fields[name][0]
        block = field.itemsize * n
        base = field.base if field.shape else field
        column = np.frombuffer(raw, dtype=base, count=block // base.itemsize, offset=offset)
        columns[name] = column.reshape((n, *field.shape))
        offset += block
    return columns


def read_pcd(path: Path) -> Frame:
    """Read a PCD file (ascii, binary or binary_compressed) into a `Frame`.

    Organized clouds keep (height, width) and their NaN pixels in place. Colour comes from
    `rgb` (float or uint32 bits) or `rgba`; every other field (label, normals, curvature,
    intensity, ...) is kept in Frame.fields. Raises InputError on anything unreadable.
    """
    path = Path(path)
    fp = open_input(path, "a PCD file")
    size = os.fstat(fp.fileno()).st_size
    with fp:
        if size == 0:
            raise InputError(f"{path}: empty file (0 bytes); expected a PCD file")
        try:
            lines, data_offset = _read_header_lines(fp, path)
            meta = _parse_metadata(lines, path)
            dtype = _record_dtype(meta)
            columns = _decode_data(fp, path, meta, dtype, size - data_offset)
        except OSError as exc:
            raise InputError(f"{path}: cannot read ({exc.strerror})") from None
    names = [n for n in columns if not n.startswith("_pad")]
    if not {"x", "y", "z"} <= set(names):
        raise InputError(
            f"{path}: the cloud has no x/y/z fields (fields: {' '.join(names) or 'none'}); clear needs 3-D points"
        )
    shape = (int(meta.height), int(meta.width)) if meta.height > 1 else None
    skip = tuple(n for n in columns if n.startswith("_pad"))
    return frame_from_columns(columns, shape, source=str(path), skip=skip)


def write_pcd(path: Path, frame: Frame, labels: np.ndarray | None = None) -> None:
    """Write x y z (+ rgb, + label) as binary_compressed PCD, atomically.

    Points keep their order and organisation (WIDTH/HEIGHT from frame.shape; unorganized
    clouds get HEIGHT 1). Colours become PCL's packed-float `rgb`. The `label` field
    (uint32) holds `labels` when given, else the frame's own "label" field when it has one.
    The caller decides about overwriting (see commands.common.check_output_path).
    """
    from pypcd4.pypcd4 import Encoding, PointCloud

    path = Path(path)
    n = frame.n_points
    pts = np.asarray(frame.points, dtype=np.float32).reshape(n, 3)
    arrays: list[np.ndarray] = [pts[:, 0], pts[:, 1], pts[:, 2]]
    names: list[str] = ["x", "y", "z"]
    types: list[type] = [np.float32, np.float32, np.float32]
    if frame.colors is not None:
        arrays.append(pack_rgb_float(frame.colors))
        names.append("rgb")
        types.append(np.float32)
    labels = labels_to_write(frame, labels)
    if labels is not None:
        arrays.append(labels.astype(np.uint32))
        names.append("label")
        types.append(np.uint32)
    height, width = frame.shape if frame.shape is not None else (1, n)
    if height * width != n:
        raise ValueError(f"frame.shape {frame.shape} does not hold {n} points")
    cloud = PointCloud.from_points(arrays, names, types)
    cloud.metadata = cloud.metadata.derive(width=width, height=height)
    try:
        with atomic_path(path) as tmp:
            cloud.save(tmp, encoding=Encoding.BINARY_COMPRESSED)
    except OSError as exc:
        raise OutputError(f"{path}: cannot write ({exc.strerror or exc})") from None


def pcd_header_fields(path: Path) -> dict[str, object]:
    """The header of a PCD (fields, types, encoding) without decoding its points; for `info`."""
    path = Path(path)
    try:
        with open(path, "rb") as fp:
            lines, _ = _read_header_lines(fp, path)
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror})") from None
    meta = _parse_metadata(lines, path)
    return {
        "encoding": meta.data,
        "fields": [
            {"name": f, "type": f"{t}{s}", "count": c}
            for f, t, s, c in zip(meta.fields, meta.type, meta.size, meta.count)
        ],
        "width": int(meta.width),
        "height": int(meta.height),
        "viewpoint": [float(v) for v in meta.viewpoint],
        "file_bytes": os.path.getsize(path),
    }
