"""A new input format is one module and one registry line (clearcli/io/formats/).

The toy format below (`.xyz`: rows of "x y z" in text) is all a new format is: its
class, and the line that registers it, which the test makes (monkeypatching
`formats.FORMATS`). With nothing else touched, `clear info` (table and --json),
`clear segment` and a folder batch's enumeration take it.
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from helpers import FIXTURES

from clearcli.errors import InputError
from clearcli.io.formats.base import InputFormat, SingleFrame
from clearcli.io.frames import Frame

# --- the toy format: what would be clearcli/io/formats/xyz.py -------------------------------


class Xyz(SingleFrame):
    """A text file of "x y z" rows (metres), one point each: an unorganized cloud."""

    name = "xyz"
    what = "an XYZ file"
    suffixes = (".xyz",)

    def recognises(self, path: Path, head: bytes) -> bool:
        words = head.split(b"\n", 1)[0].split()
        try:
            return len(words) == 3 and all(np.isfinite(float(w)) for w in words)
        except ValueError:
            return False

    def read(self, path: Path, images: Any, color: Path | None) -> Frame:
        try:
            points = np.loadtxt(path, dtype=np.float32, ndmin=2)
        except ValueError as exc:
            raise InputError(f"{path}: not an XYZ file ({exc})") from None
        if points.shape[1] != 3:
            raise InputError(f"{path}: rows of {points.shape[1]} numbers, not x y z")
        return Frame(points=points, source=str(path))


FORMAT = Xyz()


# --- the tests ------------------------------------------------------------------------------


@pytest.fixture
def registered(monkeypatch: pytest.MonkeyPatch) -> None:
    from clearcli.io import formats

    monkeypatch.setattr(formats, "FORMATS", [*formats.FORMATS, FORMAT])  # the one registry line


@pytest.fixture(scope="module")
def box_points() -> np.ndarray:
    from clearcli.io.read import read_frame

    frame = read_frame(FIXTURES / "isolated_box.pcd")
    return frame.points[frame.finite_mask]


@pytest.fixture
def box_xyz(tmp_path: Path, box_points: np.ndarray) -> Path:
    path = tmp_path / "box.xyz"
    np.savetxt(path, box_points, fmt="%.9g")  # float32 round trip
    return path


def test_every_format_offers_the_interface() -> None:
    from clearcli.io import formats

    assert all(isinstance(fmt, InputFormat) for fmt in [*formats.FORMATS, FORMAT])
    assert {"mcap", "rosbag1", "rosbag2", "image", "pcd"} <= {fmt.name for fmt in formats.FORMATS}


def test_unregistered_it_is_no_input(box_xyz: Path) -> None:
    from clearcli.io.read import sniff
    from clearcli.tasks.sources import expand

    with pytest.raises(InputError, match="unrecognised first bytes"):
        sniff(box_xyz)
    assert [it.message for it in expand([box_xyz.parent])] == [  # type: ignore[union-attr]
        f"{box_xyz.parent}: folder holds no .pcd, .mcap or .bag file and no depth image named "
        "<stem>_depth.png (.tif, .npy)"
    ]


def test_registered_it_is_read(registered: None, box_xyz: Path, box_points: np.ndarray) -> None:
    from clearcli.io.read import iter_frames, read_frame, sniff

    assert sniff(box_xyz) == "xyz"
    frame = read_frame(box_xyz)
    assert np.array_equal(frame.points, box_points) and frame.shape is None
    assert [f.n_points for f in iter_frames(box_xyz)] == [len(box_points)]
    with pytest.raises(InputError, match=r"--frame 1 does not exist: an XYZ file holds 1 frame \(0\)"):
        read_frame(box_xyz, index=1)
    with pytest.raises(InputError, match=r"only a depth image takes a colour image; .* is a xyz file"):
        read_frame(box_xyz, color=box_xyz)
    # the formats before it still come first: a PCD named .xyz is a PCD
    pcd = box_xyz.with_name("cloud.xyz")
    shutil.copy(FIXTURES / "isolated_box.pcd", pcd)
    assert sniff(pcd) == "pcd"


def test_clear_info_takes_it(registered: None, box_xyz: Path, box_points: np.ndarray) -> None:
    from typer.testing import CliRunner

    from clearcli.cli import make_app

    app = make_app("info")
    res = CliRunner().invoke(app, ["info", str(box_xyz), "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout.strip().splitlines()[-1])
    assert (doc["schema"], doc["format"], doc["file"]) == ("clear.info", "xyz", str(box_xyz))
    assert doc["frame"]["points"] == doc["frame"]["finite_points"] == len(box_points)
    assert doc["frame"]["organized"] is False
    res = CliRunner().invoke(app, ["info", str(box_xyz)])
    assert res.exit_code == 0, res.output
    assert re.search(r"^format\s+xyz\s*$", res.stdout, re.M), res.stdout
    n = f"{len(box_points):,}".replace(",", " ")  # as the table writes it
    assert re.search(rf"^points\s+{n} \(unorganized\)", res.stdout, re.M), res.stdout


def test_clear_segment_takes_it(registered: None, box_xyz: Path) -> None:
    from typer.testing import CliRunner

    from clearcli.cli import make_app

    res = CliRunner().invoke(make_app("segment"), ["segment", str(box_xyz), "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout.strip().splitlines()[-1])
    assert doc["schema"] == "clear.segmentation" and len(doc["objects"]) == 1


def test_a_folder_batch_takes_it(registered: None, box_xyz: Path) -> None:
    from clearcli.tasks.sources import FrameRef, expand, files_read

    folder = box_xyz.parent
    shutil.copy(FIXTURES / "box_on_box.pcd", folder / "a.pcd")
    (folder / "notes.txt").write_text("not a frame")
    for every in (None, 2):
        items = expand([folder], every=every)
        assert items == [FrameRef(str(folder / "a.pcd"), 0, False, "a"), FrameRef(str(box_xyz), 0, False, "box")]
    assert files_read(box_xyz) == (box_xyz,)
