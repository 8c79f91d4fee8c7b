"""Tests of clearcli/io/pcd.py."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest
from helpers import SHARED_DATA, shared_path
from helpers.io import _header, _one_line_error, _same, _small_frame

from clearcli.errors import ClearError, InputError
from clearcli.io.frames import Frame
from clearcli.io.pcd import read_pcd, write_pcd
from clearcli.io.read import read_frame

MOSD_TEST = ["test44", "test46", "test47", "test55", "test57"]


def _all_pcds() -> list[Path]:
    base = shared_path("pcd_formats")
    files = sorted(base.glob("*.pcd")) + sorted((SHARED_DATA / "mosd").rglob("*.pcd"))
    return files


def test_every_shared_pcd_reads_or_is_rejected_cleanly() -> None:
    files = _all_pcds()
    assert len(files) >= 9 + 50
    for path in files:
        if path.name == "stereo_left.pcd":
            with pytest.raises(InputError, match="no x/y/z"):
                read_pcd(path)
            continue
        frame = read_pcd(path)
        assert frame.points.dtype == np.float32 and frame.points.shape == (frame.n_points, 3)
        if frame.shape is not None:
            assert frame.shape[0] * frame.shape[1] == frame.n_points
        assert frame.finite_mask.sum() > 0


def test_pcd_formats_values() -> None:
    bun = read_pcd(shared_path("pcd_formats/bun0.pcd"))  # ascii, normals + curvature
    assert bun.n_points == 397 and bun.shape is None and bun.colors is None
    assert set(bun.fields) == {"normal_x", "normal_y", "normal_z", "curvature"}
    colored = read_pcd(shared_path("pcd_formats/colored_cloud.pcd"))  # binary, rgb as U4
    assert colored.n_points == 1000 and colored.shape == (1000, 1) and colored.colors is not None
    assert "rgb" not in colored.fields and "curvature" in colored.fields
    mug = read_pcd(shared_path("pcd_formats/table_scene_mug_rgb_float.pcd"))  # rgb as F4
    assert mug.shape == (480, 640) and mug.colors is not None
    assert int(mug.finite_mask.sum()) == 209280
    room = read_pcd(shared_path("pcd_formats/capture0001_xyz_only_room.pcd"))
    assert room.colors is None and room.fields == {} and room.shape == (480, 640)
    keys = read_pcd(shared_path("pcd_formats/office1_keypoints.pcd"))
    assert keys.n_points == 1318 and keys.fields["intensity"].dtype == np.float32


def test_rgb_float_colours_match_open3d() -> None:
    import open3d as o3d

    path = shared_path("pcd_formats/table_scene_mug_rgb_float.pcd")
    ours = read_pcd(path)
    theirs = o3d.io.read_point_cloud(str(path), remove_nan_points=False)
    assert _same(np.asarray(theirs.points).astype(np.float32), ours.points)
    assert np.array_equal(np.round(np.asarray(theirs.colors) * 255).astype(np.uint8), ours.colors)


def test_test57_three_encodings_identical() -> None:
    ascii_ = read_pcd(shared_path("pcd_formats/mosd_test57_ascii.pcd"))
    binary = read_pcd(shared_path("pcd_formats/mosd_test57_binary.pcd"))
    compressed = read_pcd(shared_path("mosd/test/test57.pcd"))
    for other in (ascii_, binary):
        assert other.shape == compressed.shape == (480, 640)
        assert _same(other.points, compressed.points)
        assert np.array_equal(other.colors, compressed.colors)
        assert np.array_equal(other.fields["label"], compressed.fields["label"])
    assert int(compressed.finite_mask.sum()) == 171483


def test_mosd_frames_organized_with_labels_and_nan_in_place() -> None:
    for name in MOSD_TEST:
        frame = read_pcd(shared_path(f"mosd/test/{name}.pcd"))
        assert frame.shape == (480, 640) and frame.n_points == 640 * 480
        labels = frame.fields["label"]
        assert labels.dtype == np.uint32 and labels.shape == (640 * 480,)
        finite = frame.finite_mask
        # Invalid pixels stay where they are and carry label 0; some objects (>= 10) exist.
        assert 0 < finite.sum() < frame.n_points
        assert np.all(labels[~finite] == 0)
        assert len(np.unique(labels[labels >= 10] // 10)) >= 5
    # test57: complex clutter, 14-16 objects by the README.
    t57 = read_pcd(shared_path("mosd/test/test57.pcd")).fields["label"]
    assert 14 <= len(np.unique(t57[t57 >= 10] // 10)) <= 16


def test_write_pcd_round_trip_organized(tmp_path: Path) -> None:
    frame = _small_frame()
    out = tmp_path / "small.pcd"
    write_pcd(out, frame)
    back = read_pcd(out)
    assert back.shape == (4, 5)
    assert _same(back.points, frame.points)
    assert np.array_equal(back.colors, frame.colors)
    assert np.array_equal(back.fields["label"], frame.fields["label"])
    assert b"DATA binary_compressed" in out.read_bytes()[:400]
    assert not [p for p in tmp_path.iterdir() if p.name != "small.pcd"]  # no temp file left


def test_write_pcd_labels_argument_and_unorganized(tmp_path: Path) -> None:
    base = _small_frame()
    frame = Frame(points=base.points, colors=None, shape=None)
    labels = np.full(frame.n_points, 7, dtype=np.int64)
    out = tmp_path / "u.pcd"
    write_pcd(out, frame, labels=labels)
    back = read_pcd(out)
    assert back.shape is None and back.colors is None
    assert back.fields["label"].dtype == np.uint32 and set(back.fields["label"].tolist()) == {7}
    header = out.read_bytes()[:300].decode("ascii", "replace")
    assert "FIELDS x y z label" in header and "WIDTH 20" in header and "HEIGHT 1" in header


def test_write_pcd_mosd_round_trip_and_open3d(tmp_path: Path) -> None:
    import open3d as o3d

    frame = read_pcd(shared_path("mosd/test/test57.pcd"))
    out = tmp_path / "t57.pcd"
    write_pcd(out, frame)
    back = read_pcd(out)
    assert _same(back.points, frame.points) and np.array_equal(back.colors, frame.colors)
    assert np.array_equal(back.fields["label"], frame.fields["label"])
    cloud = o3d.io.read_point_cloud(str(out), remove_nan_points=False)
    assert len(cloud.points) == 307200 and cloud.has_colors()
    assert _same(np.asarray(cloud.points).astype(np.float32), frame.points)
    finite = frame.finite_mask
    assert np.array_equal(np.round(np.asarray(cloud.colors)[finite] * 255).astype(np.uint8), frame.colors[finite])


def _xyz(n: int) -> bytes:
    return np.arange(3 * n, dtype="<f4").tobytes()


def test_bad_pcd_inputs(tmp_path: Path) -> None:
    cases: dict[str, tuple[bytes, str]] = {
        "empty.pcd": (b"", "empty file"),
        "garbage.pcd": (b"\x00\x01\x02binary junk", "not a PCD file"),
        "text.pcd": (b"hello world\n", "not a PCD file"),
        "comment_only.pcd": (b"# .PCD v0.7\n", "no DATA line"),
        "header_cut.pcd": (_header()[:60], "no DATA line"),
        "points_lie.pcd": (_header(n=5) + _xyz(5), r"POINTS 5 but WIDTH\*HEIGHT = 3\*1 = 3"),
        "organized_lie.pcd": (_header(w=2, h=2, n=3) + _xyz(3), "POINTS 3 but WIDTH"),
        "binary_short.pcd": (_header(w=4) + _xyz(3), "truncated PCD"),
        "binary_cut_mid_point.pcd": (_header(w=3) + _xyz(3)[:-5], "truncated PCD"),
        "compressed_no_sizes.pcd": (_header(d="binary_compressed") + b"\x01\x02", "size header is missing"),
        "compressed_cut.pcd": (
            _header(d="binary_compressed") + struct.pack("<II", 30, 36) + b"\x00" * 10,
            "truncated PCD",
        ),
        "compressed_wrong_size.pcd": (
            _header(d="binary_compressed") + struct.pack("<II", 4, 99) + b"\x00" * 4,
            "unpacks to 99 bytes",
        ),
        "compressed_corrupt.pcd": (
            _header(d="binary_compressed") + struct.pack("<II", 8, 36) + b"\xff" * 8,
            "corrupt PCD",
        ),
        "ascii_short.pcd": (_header(d="ascii") + b"1 2 3\n4 5 6\n", "2 rows"),
        "ascii_bad_token.pcd": (_header(d="ascii") + b"1 2 3\n4 x 6\n7 8 9\n", "bad ASCII point data"),
        "fields_mismatch.pcd": (_header().replace(b"SIZE 4 4 4", b"SIZE 4 4"), "3 FIELDS but 2 SIZE"),
        "bad_type.pcd": (_header().replace(b"TYPE F F F", b"TYPE F F Q"), "bad PCD header"),
        "bad_width.pcd": (_header().replace(b"WIDTH 3", b"WIDTH three"), "bad PCD header"),
        "no_xyz.pcd": (_header().replace(b"FIELDS x y z", b"FIELDS a b c") + _xyz(3), "no x/y/z"),
        # a record numpy cannot describe (COUNT 1e9 x 4 bytes): one line, not numpy's ValueError
        # the sensor's pose with a NaN: refused (it reached `info --json` as a bare NaN)
        "viewpoint_nan.pcd": (_header().replace(b"VIEWPOINT 0 0 0 1", b"VIEWPOINT nan 0 0 1") + _xyz(3), "finite"),
        "count_huge.pcd": (_header().replace(b"COUNT 1 1 1", b"COUNT 1 1 1000000000") + _xyz(3), "is COUNT right"),
        "ros1.bag.pcd": (b"#ROSBAG V2.0\n\x00\x00", "truncated or corrupt ROS 1 bag"),
    }
    for name, (content, match) in cases.items():
        path = tmp_path / name
        path.write_bytes(content)
        _one_line_error(path, match)
    _one_line_error(tmp_path / "missing.pcd", "file not found")
    with pytest.raises(InputError, match="directory"):
        read_frame(tmp_path)
    with pytest.raises(InputError, match="frame 1 does not exist"):
        read_frame(shared_path("pcd_formats/bun0.pcd"), index=1)


def test_stereo_left_has_no_xyz() -> None:
    path = shared_path("pcd_formats/stereo_left.pcd")
    message = _one_line_error(path, "no x/y/z fields")
    assert "rgba" in message


def test_pcd_count_field_and_padding(tmp_path: Path) -> None:
    """COUNT 3 fields become (N, 3); PCL's `_` padding is dropped; compressed layout is per field."""
    import lzf

    n = 3
    xyz = np.arange(3 * n, dtype="<f4").reshape(n, 3)
    normal = (np.arange(3 * n, dtype="<f4") + 100).reshape(n, 3)
    pad = np.zeros(n, dtype="<f4")
    blocks = b"".join(np.ascontiguousarray(a).tobytes() for a in (xyz[:, 0], xyz[:, 1], xyz[:, 2], normal, pad))
    packed = lzf.compress(blocks)
    header = (
        "VERSION 0.7\nFIELDS x y z normal _\nSIZE 4 4 4 4 4\nTYPE F F F F F\nCOUNT 1 1 1 3 1\n"
        f"WIDTH {n}\nHEIGHT 1\nPOINTS {n}\nDATA binary_compressed\n"
    ).encode()
    path = tmp_path / "normals.pcd"
    path.write_bytes(header + struct.pack("<II", len(packed), len(blocks)) + packed)
    frame = read_frame(path)
    assert np.array_equal(frame.points, xyz)
    assert list(frame.fields) == ["normal"] and np.array_equal(frame.fields["normal"], normal)


def test_pcd_truncation_fuzz_only_clear_errors(tmp_path: Path) -> None:
    """Every prefix of a small PCD (and a few byte flips) gives a frame or a ClearError."""
    frame = _small_frame(3, 4, nan_rows=())
    good = tmp_path / "good.pcd"
    write_pcd(good, frame)
    data = good.read_bytes()
    path = tmp_path / "cut.pcd"
    for end in range(0, len(data) - 1, 3):
        path.write_bytes(data[:end])
        with pytest.raises(ClearError):
            read_frame(path)
    rng = np.random.default_rng(0)
    for _ in range(60):
        flipped = bytearray(data)
        flipped[int(rng.integers(len(data)))] = int(rng.integers(256))
        path.write_bytes(bytes(flipped))
        try:
            back = read_frame(path)
        except ClearError:
            continue
        # a flip the reader accepts changed a value, never how many points there are
        assert back.n_points == frame.n_points


# Header lines changed from helpers.io._header (binary, 3 points of x y z): what pypcd4's
# reader and its pydantic model make of each, which the reader's own parser must repeat.
_HEADER_VARIANTS: dict[str, tuple[bytes, bytes]] = {
    "as_is": (b"", b""),
    "version_06": (b"VERSION 0.7", b"VERSION 0.6"),
    "version_dot7": (b"VERSION 0.7", b"VERSION .7"),
    "no_version": (b"VERSION 0.7\n", b""),
    "no_viewpoint": (b"VIEWPOINT 0 0 0 1 0 0 0\n", b""),
    "viewpoint_6": (b"VIEWPOINT 0 0 0 1 0 0 0", b"VIEWPOINT 0 0 0 1 0 0"),
    "viewpoint_8": (b"VIEWPOINT 0 0 0 1 0 0 0", b"VIEWPOINT 0 0 0 1 0 0 0 0"),
    "viewpoint_word": (b"VIEWPOINT 0 0 0 1 0 0 0", b"VIEWPOINT 0 0 0 1 0 0 x"),
    "viewpoint_values": (b"VIEWPOINT 0 0 0 1 0 0 0", b"VIEWPOINT 0.5 -1e-3 2 1 0 0 0"),
    "size_0": (b"SIZE 4 4 4", b"SIZE 4 4 0"),
    "size_negative": (b"SIZE 4 4 4", b"SIZE 4 4 -4"),
    "count_0": (b"COUNT 1 1 1", b"COUNT 1 1 0"),
    "type_lower": (b"TYPE F F F", b"TYPE F F f"),
    "width_negative": (b"WIDTH 3", b"WIDTH -3"),
    "width_float": (b"WIDTH 3", b"WIDTH 3.0"),
    "width_underscore": (b"WIDTH 3", b"WIDTH 3_0"),
    "width_plus": (b"WIDTH 3", b"WIDTH +3"),
    "width_twice": (b"WIDTH 3", b"WIDTH 5\nWIDTH 3"),
    "width_lower_key": (b"WIDTH 3", b"width 3"),
    "width_comment": (b"WIDTH 3", b"WIDTH 3 # c"),
    "height_word": (b"HEIGHT 1", b"HEIGHT x"),
    "points_word": (b"POINTS 3", b"POINTS x"),
    "data_upper": (b"DATA binary", b"DATA BINARY"),
    "data_no_value": (b"DATA binary", b"DATA"),
    "size_no_value": (b"SIZE 4 4 4", b"SIZE"),
    "fields_no_value": (b"FIELDS x y z", b"FIELDS"),
    "fields_comma": (b"FIELDS x y z", b"FIELDS x,y z"),
    "fields_colon": (b"FIELDS x y z", b"FIELDS x y z:1"),
    "tabs": (b"SIZE 4 4 4", b"SIZE\t4\t4\t4"),
}


@pytest.mark.parametrize("name", sorted(_HEADER_VARIANTS))
def test_header_parsed_as_pypcd4_does(name: str) -> None:
    """The reader's header parser (written so that reading does not import pypcd4 and
    pydantic) takes what pypcd4's MetaData.parse_header takes, with the same values, and
    rejects what it rejects, with pydantic's words for the same first error."""
    import pydantic
    from pypcd4.pypcd4 import MetaData

    from clearcli.io import pcd

    old, new = _HEADER_VARIANTS[name]
    text = _header().replace(old, new).decode()
    lines = [line.strip() for line in text.splitlines() if line.strip() and not line.startswith("#")]
    try:
        theirs = MetaData.parse_header(lines)
    except (pydantic.ValidationError, ValueError, IndexError) as exc:
        with pytest.raises((ValueError, IndexError)) as info:
            pcd._validated(pcd._header_values(lines))
        if isinstance(exc, pydantic.ValidationError):
            first = exc.errors()[0]
            assert str(info.value) == f"{'.'.join(str(p) for p in first['loc'])}: {first['msg']}"
        else:
            assert str(info.value) == str(exc)
        return
    ours = pcd._validated(pcd._header_values(lines))
    for key in ("fields", "size", "type", "count", "points", "width", "height", "version", "viewpoint"):
        assert getattr(ours, key) == getattr(theirs, key), key
    assert ours.data == theirs.data.value


def test_header_of_every_shared_pcd_as_pypcd4_reads_it() -> None:
    from pypcd4.pypcd4 import MetaData

    from clearcli.io import pcd

    for path in _all_pcds():
        with open(path, "rb") as fp:
            lines, _ = pcd._read_header_lines(fp, path)
        ours = pcd._parse_metadata(lines, path)
        theirs = MetaData.parse_header(lines)
        fields = tuple("_" if f.startswith("#$%&~~") else f for f in theirs.fields)  # pypcd4 renames padding
        assert (ours.fields, ours.size, ours.type, ours.count) == (fields, theirs.size, theirs.type, theirs.count)
        assert (ours.width, ours.height, ours.points, ours.viewpoint) == (
            theirs.width,
            theirs.height,
            theirs.points,
            theirs.viewpoint,
        )
        assert ours.data == theirs.data.value, path


def test_reading_a_pcd_imports_neither_pypcd4_nor_pydantic() -> None:
    """Cold start (issue 39): pypcd4 imports pydantic, 0.13-0.2 s; reading needs neither."""
    import subprocess
    import sys

    code = (
        "import sys\n"
        "from clearcli.io.pcd import pcd_header_fields, read_pcd\n"
        f"f = read_pcd({str(shared_path('mosd/test/test57.pcd'))!r})\n"
        f"h = pcd_header_fields({str(shared_path('pcd_formats/bun0.pcd'))!r})\n"
        "assert f.n_points == 307200 and h['encoding'] == 'ascii'\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('pypcd4', 'pydantic')))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_compressed_fields_read_as_columns_are_the_records_frame(tmp_path: Path) -> None:
    """Issue 39: a binary_compressed PCD's fields are read as columns of the unpacked
    bytes (no record array between); the frame is frame_from_records' of the same
    records, bit for bit: points, colour, a field of count 3, a padding field skipped,
    the label its own writable array."""
    import lzf

    from clearcli.io.pointfields import frame_from_records

    gen = np.random.default_rng(2)
    height, width = 3, 4
    n = height * width
    dtype = np.dtype(
        [
            ("x", "<f4"),
            ("y", "<f4"),
            ("z", "<f4"),
            ("rgb", "<u4"),
            ("_pad3", "u1"),
            ("normal", "<f4", (3,)),
            ("label", "<u4"),
        ]
    )
    records = np.zeros(n, dtype=dtype)
    for name in ("x", "y", "z"):
        records[name] = gen.normal(size=n).astype(np.float32)
    records["x"][5] = np.nan
    records["rgb"] = gen.integers(0, 1 << 24, n)
    records["_pad3"] = 7
    records["normal"] = gen.normal(size=(n, 3)).astype(np.float32)
    records["label"] = gen.integers(0, 100, n)
    raw = b"".join(np.ascontiguousarray(records[name]).tobytes() for name in dtype.names or ())
    header = (
        "VERSION 0.7\nFIELDS x y z rgb _ normal label\nSIZE 4 4 4 4 1 4 4\nTYPE F F F U U F U\n"
        f"COUNT 1 1 1 1 1 3 1\nWIDTH {width}\nHEIGHT {height}\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\n"
        "DATA binary_compressed\n"
    )
    packed = lzf.compress(raw, 2 * len(raw) + 64)  # random floats do not shrink
    path = tmp_path / "columns.pcd"
    path.write_bytes(header.encode() + struct.pack("<II", len(packed), len(raw)) + packed)
    got = read_pcd(path)
    want = frame_from_records(records, (height, width), source=str(path), skip=("_pad3",))
    assert got.points.tobytes() == want.points.tobytes() and got.points.dtype == np.float32
    assert got.colors is not None and want.colors is not None
    assert np.array_equal(got.colors, want.colors) and got.colors.flags.writeable
    assert list(got.fields) == list(want.fields) == ["normal", "label"]
    for name, column in got.fields.items():
        assert column.dtype == want.fields[name].dtype and column.shape == want.fields[name].shape
        assert column.tobytes() == want.fields[name].tobytes()
        assert column.flags.writeable and column.flags.c_contiguous  # its own array, not the file's bytes
    assert got.fields["normal"].shape == (n, 3) and got.shape == (height, width)


def test_an_ascii_pcd_without_rows_is_one_error_and_no_numpy_warning(tmp_path: Path) -> None:
    import warnings

    path = tmp_path / "empty_rows.pcd"
    path.write_bytes(_header(d="ascii"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _one_line_error(path, "0 rows")
