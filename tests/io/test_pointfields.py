"""Tests of clearcli/io/pointfields.py."""

from __future__ import annotations

import numpy as np
import pytest

from clearcli.io.pointfields import pack_rgb_float, unpack_rgb


def test_rgb_packing_hand_values() -> None:
    colors = np.array([[255, 0, 0], [0, 128, 0], [1, 2, 3]], dtype=np.uint8)
    packed = pack_rgb_float(colors)
    assert packed.dtype == np.float32
    assert packed.view(np.uint32).tolist() == [0xFF0000, 0x008000, 0x010203]
    assert unpack_rgb(packed).tolist() == colors.tolist()
    # rgba as uint32 0xAARRGGBB: alpha ignored.
    assert unpack_rgb(np.array([0x80102030], dtype=np.uint32)).tolist() == [[0x10, 0x20, 0x30]]


def test_pointcloud2_blob_big_endian_with_row_padding() -> None:
    """Rows padded beyond width*point_step, big-endian fields, a COUNT-2 field, an rgb float."""
    from clearcli.io.pointfields import FieldSpec, frame_from_records, records_from_blob

    height, width, step, pad = 2, 3, 20, 4
    specs = [
        FieldSpec("x", 0, "f4"),
        FieldSpec("y", 4, "f4"),
        FieldSpec("z", 8, "f4"),
        FieldSpec("rgb", 12, "f4"),
        FieldSpec("uv", 16, "u2", 2),
    ]
    dtype = np.dtype(
        {
            "names": ["x", "y", "z", "rgb", "uv"],
            "formats": [">f4", ">f4", ">f4", ">u4", (">u2", (2,))],
            "offsets": [0, 4, 8, 12, 16],
            "itemsize": step,
        }
    )
    rows = []
    for r in range(height):
        rec = np.zeros(width, dtype=dtype)
        rec["x"] = np.arange(width) + 10 * r
        rec["y"] = -1.5
        rec["z"] = 2.0 + r
        rec["rgb"] = 0x00A0B0C0 + r
        rec["uv"] = [[c, r] for c in range(width)]
        rows.append(rec.tobytes() + b"\xee" * pad)
    records = records_from_blob(b"".join(rows)[:-pad], specs, step, width, height, width * step + pad, True)
    frame = frame_from_records(records, (height, width))
    assert frame.points[:, 0].tolist() == [0, 1, 2, 10, 11, 12]
    assert frame.points[:, 2].tolist() == [2, 2, 2, 3, 3, 3]
    assert frame.colors[0].tolist() == [0xA0, 0xB0, 0xC0] and frame.colors[3].tolist() == [0xA0, 0xB0, 0xC1]
    assert frame.fields["uv"].shape == (6, 2) and frame.fields["uv"][4].tolist() == [1, 1]
    assert frame.fields["uv"].dtype.isnative
    with pytest.raises(ValueError, match="layout needs"):
        records_from_blob(b"\x00" * 50, specs, step, width, height, width * step, True)


def test_float64_coordinates_beyond_float32_become_inf_without_a_warning() -> None:
    import warnings

    from clearcli.io.pointfields import frame_from_records

    records = np.zeros(3, dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8")])
    records["x"] = (1.0, 1e300, -1e39)
    records["z"] = 1.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        frame = frame_from_records(records, None)
    assert frame.points[0].tolist() == [1.0, 0.0, 1.0]
    assert frame.points[1, 0] == np.inf and frame.points[2, 0] == -np.inf


def test_a_signalling_nan_becomes_a_quiet_one_and_every_other_value_keeps_its_bits() -> None:
    # a flipped byte can make a signalling NaN, which raised numpy's "invalid value"
    # warning at the first cast downstream (the openings step's float64 copy)
    import warnings

    from clearcli.io.pointfields import frame_from_columns

    snan = np.array([0x7FA00000], dtype=np.uint32).view(np.float32)[0]
    values = np.array([snan, -0.0, np.inf, 1e-45, 3.0e38, np.nan], dtype=np.float32)
    columns = {"x": values, "y": values.copy(), "z": np.ones(6, dtype=np.float32)}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        frame = frame_from_columns(columns, None)
        as_double = frame.points.astype(np.float64)  # warned on the signalling NaN
    bits = frame.points[:, 0].view(np.uint32)
    assert bits[0] & 0x00400000 and np.isnan(as_double[0, 0])  # quiet now
    assert (bits[1:] == values[1:].view(np.uint32)).all()  # the rest bit for bit
