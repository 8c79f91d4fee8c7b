"""Issue 34: faults found by feeding the newer inputs garbage, each fixed at its root.

Each test names its fault; each failed on the code before the fix (the message or exit
code it checks did not exist, or an input was overwritten)."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import stat
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest
from helpers import FIXTURES, shared_path
from helpers import run_clear as clear

BOX = FIXTURES / "box_on_box.pcd"


def _one_line(res, code: int) -> str:
    lines = res.stderr.strip().splitlines()
    assert res.returncode == code and len(lines) == 1, (res.returncode, res.stderr)
    assert "Traceback" not in res.stderr
    return lines[0]


def _digest(folder: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir()) if p.is_file()}


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def _png(path: Path, width: int, height: int, bit_depth: int, rows: int | None = None) -> Path:
    """A grey PNG claiming ``width`` x ``height``; ``rows`` of zeros really in it (None:
    all of them, streamed through zlib so that a real 16000 x 16000 image costs no
    memory), the header's CRCs right, so that only the size can be refused."""
    comp = zlib.compressobj(9)
    row = b"\0" * (1 + width * bit_depth // 8)
    body = b"".join(comp.compress(row) for _ in range(height if rows is None else rows)) + comp.flush()
    path.write_bytes(
        b"\x89PNG\r\n\x1a\n"
        + _png_chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, bit_depth, 0, 0, 0, 0))
        + _png_chunk(b"IDAT", body)
        + _png_chunk(b"IEND", b"")
    )
    return path


# -- fault 1: images too large to decode -------------------------------------------------


@pytest.mark.parametrize("command", ["info", "segment", "plan"])
def test_a_png_header_claiming_100000_square_is_refused_before_decoding(tmp_path: Path, command: str) -> None:
    bomb = _png(tmp_path / "bomb_depth.png", 100_000, 100_000, 16, rows=4)
    line = _one_line(clear(command, bomb, "--intrinsics", "500 500 320 240"), 3)
    assert "100000 x 100000" in line and "larger than any camera frame" in line


def test_a_real_16000_square_image_is_refused_and_so_is_its_colour_pair(tmp_path: Path) -> None:
    # a real image (every row there): PIL's own bomb check raised DecompressionBombError (exit 1)
    big = _png(tmp_path / "big_depth.png", 16_000, 16_000, 8)
    line = _one_line(clear("plan", big, "--intrinsics", "500 500 320 240"), 3)
    assert "16000 x 16000" in line
    depth = tmp_path / "x_depth.png"
    shutil.copy(shared_path("rgbd/uois/uois_0003_depth.png"), depth)
    shutil.copy(big, tmp_path / "x_color.png")
    line = _one_line(clear("segment", depth, "--intrinsics", "612.9 613.2 322.5 248.2"), 3)
    assert "x_color.png" in line and "16000 x 16000" in line


def test_an_npy_header_claiming_a_huge_array_is_refused_before_reading(tmp_path: Path) -> None:
    path = tmp_path / "huge_depth.npy"
    with open(path, "wb") as fp:
        np.lib.format.write_array_header_1_0(fp, {"descr": "<u2", "fortran_order": False, "shape": (40000, 40000)})
    line = _one_line(clear("segment", path, "--intrinsics", "500 500 320 240"), 3)
    assert "40000 x 40000" in line


# -- fault 3: inputs found by the naming rule are inputs ---------------------------------


@pytest.fixture()
def pair(tmp_path: Path) -> Path:
    src = shared_path("rgbd/uois")
    for name in ("uois_0003_depth.png", "uois_0003_color.png", "camera_info.yaml"):
        shutil.copy(src / name, tmp_path / name)
    return tmp_path


@pytest.mark.parametrize(
    "flag, name", [("-o", "uois_0003_color.png"), ("--png", "camera_info.yaml"), ("--problem", "camera_info.yaml")]
)
def test_an_output_naming_a_paired_input_is_refused_even_with_force(pair: Path, flag: str, name: str) -> None:
    before = _digest(pair)
    line = _one_line(clear("plan", pair / "uois_0003_depth.png", flag, pair / name, "--force"), 8)
    assert "is an input of this run" in line and name in line
    assert _digest(pair) == before


def test_an_output_naming_the_settings_file_or_the_urdf_is_refused(tmp_path: Path) -> None:
    settings = tmp_path / "s.toml"
    settings.write_text("[plan]\ntime_limit_s = 20\n")
    line = _one_line(clear("plan", BOX, "--settings", settings, "-o", settings, "--force"), 8)
    assert "is an input of this run" in line and settings.read_text() == "[plan]\ntime_limit_s = 20\n"
    urdf = tmp_path / "arm.urdf"
    shutil.copy(Path(__file__).resolve().parents[2] / "clearcli" / "robot" / "panda.urdf", urdf)
    before = urdf.read_bytes()
    res = clear(
        "plan",
        BOX,
        "--set",
        f"robot.urdf={urdf}",
        "--set",
        "robot.base_frame=panda_link0",
        "--set",
        "robot.flange_frame=panda_link8",
        "--png",
        urdf,
        "--force",
    )
    _one_line(res, 8)
    assert urdf.read_bytes() == before


def test_a_batch_output_naming_an_intrinsics_file_beside_a_frame_is_refused(pair: Path) -> None:
    # a frame named `camera` writes its mark camera.json, which is the intrinsics file
    # the depth image beside it reads
    (pair / "camera.json").write_text(
        json.dumps(
            {
                "fx": 612.937,
                "fy": 613.173,
                "x_offset": 322.549,
                "y_offset": 248.158,
                "img_width": 640,
                "img_height": 480,
            }
        )
    )
    (pair / "camera_info.yaml").unlink()
    shutil.copy(BOX, pair / "camera.pcd")
    before = _digest(pair)
    res = clear("segment", pair, "--out-dir", pair, "--force", "--json", "--jobs", "1")
    lines = [json.loads(x) for x in res.stdout.splitlines()]
    clash = [ln for ln in lines if ln.get("name") == "camera"]
    assert clash and clash[0]["exit_code"] == 8 and "is an input of this batch" in clash[0]["error"]["message"]
    assert [ln["exit_code"] for ln in lines if ln.get("name") == "uois_0003"] == [0]
    assert {k: v for k, v in _digest(pair).items() if k in before} == before


# -- fault 4: outputs onto devices and FIFOs -----------------------------------------------


needs_root = pytest.mark.skipif(os.geteuid() != 0, reason="making a device node (mknod) needs root")


@needs_root
def test_an_output_onto_a_device_is_written_into_never_replaced(tmp_path: Path) -> None:
    null, full = tmp_path / "null", tmp_path / "full"
    os.mknod(null, 0o666 | stat.S_IFCHR, os.makedev(1, 3))  # twins of /dev/null and /dev/full
    os.mknod(full, 0o666 | stat.S_IFCHR, os.makedev(1, 7))
    for flag in ("-o", "--png", "--problem"):
        res = clear("plan", BOX, flag, null, "--force")
        assert res.returncode == 0, res.stderr
        res = clear("plan", BOX, flag, null)  # nothing is replaced: no --force needed
        assert res.returncode == 0, res.stderr
        line = _one_line(clear("plan", BOX, flag, full, "--force"), 8)
        assert "No space left" in line
    for node in (null, full):
        assert stat.S_ISCHR(node.stat().st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["full", "null"]  # no temporary left


def test_an_output_onto_a_fifo_nobody_reads_is_refused_at_once(tmp_path: Path) -> None:
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    line = _one_line(clear("segment", BOX, "-o", fifo, timeout=60), 8)
    assert "FIFO that nobody reads" in line and stat.S_ISFIFO(fifo.stat().st_mode)


def test_an_output_onto_dev_stdout_goes_to_stdout(tmp_path: Path) -> None:
    res = clear("plan", BOX, "-o", "/dev/stdout")
    assert res.returncode == 0, res.stderr
    assert "(grasp o0)" in res.stdout and "; cost = 2" in res.stdout  # the plan file, after the table


def test_a_batch_refuses_a_device_named_as_an_output(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    os.mkfifo(out / "box_on_box.labels.pcd")
    res = clear("segment", BOX, "--out-dir", out, "--outputs", "labels", "--json", "--resume")
    frame = json.loads(res.stdout.splitlines()[0])
    assert res.returncode == 11 and frame["exit_code"] == 8 and "FIFO" in frame["error"]["message"]
    assert stat.S_ISFIFO((out / "box_on_box.labels.pcd").stat().st_mode)  # --resume did not remove it


# -- fault 8: each real folder searched once -------------------------------------------------


def test_a_folder_linking_back_to_itself_gives_its_frame_once(tmp_path: Path) -> None:
    folder = tmp_path / "d"
    folder.mkdir()
    shutil.copy(BOX, folder / "box.pcd")
    (folder / "again").symlink_to(".")
    out = tmp_path / "out"
    res = clear("segment", folder, folder / "again", "--json", "--out-dir", out, "--jobs", "1")
    assert res.returncode == 0, res.stderr
    lines = [json.loads(x) for x in res.stdout.splitlines()]
    done = [ln for ln in lines if ln["type"] == "frame" and "skipped" not in ln]
    assert [ln["source"] for ln in done] == [str(folder / "box.pcd")]
    assert lines[-1]["done"] == 1 and lines[-1]["skipped"] == 2


# -- the --grasps rule -----------------------------------------------------------------------


@pytest.mark.parametrize("kinds", ["rim,pinch", "pinch,pinch", "pinch,,rim", "slide , pinch", "rim"])
def test_grasps_flag_and_set_follow_one_rule(kinds: str) -> None:
    by_flag = clear("domain", "--grasps", kinds)
    plan_flag = clear("plan", BOX, "--grasps", kinds, "--json")
    plan_set = clear("plan", BOX, "--set", f"plan.grasps={kinds}", "--json")
    ok = kinds in ("rim,pinch", "slide , pinch")
    for res in (by_flag, plan_flag, plan_set):
        if ok:
            assert res.returncode == 0, res.stderr
        else:
            assert "any order, each at most once" in _one_line(res, 3)
    if ok:  # the same settings, so the same digest, whichever way given
        digests = {json.loads(r.stdout)["clear"]["settings_digest"] for r in (plan_flag, plan_set)}
        assert len(digests) == 1


# -- found by the harness (tests/test_harness.py) once the nine were fixed -----------------


@pytest.fixture()
def small_pair(tmp_path: Path) -> Path:
    """A 64 x 48 depth image (a flat table 1 m away) with its colour and intrinsics."""
    from PIL import Image

    depth = np.full((48, 64), 1000, dtype=np.uint16)
    Image.fromarray(depth).save(tmp_path / "f_depth.png")
    Image.fromarray(np.zeros((48, 64, 3), dtype=np.uint8)).save(tmp_path / "f_color.png")
    (tmp_path / "camera_params.json").write_text(
        json.dumps({"fx": 52.5, "fy": 52.5, "x_offset": 31.5, "y_offset": 23.5, "img_width": 64, "img_height": 48})
    )
    return tmp_path


def test_an_output_name_too_long_names_the_output_not_stdout(small_pair: Path) -> None:
    for flag in ("-o", "--png"):
        line = _one_line(clear("segment", small_pair / "f_depth.png", flag, small_pair / ("x" * 300 + ".png")), 8)
        assert "File name too long" in line and "stdout" not in line


def test_an_intrinsics_string_longer_than_a_file_name_is_bad_input(small_pair: Path) -> None:
    line = _one_line(clear("info", small_pair / "f_depth.png", "--intrinsics", "9" * 400 + " 52.5 31.5 23.5"), 3)
    assert "stdout" not in line


def test_an_npy_whose_header_is_cut_is_bad_input(tmp_path: Path) -> None:
    path = tmp_path / "d_depth.npy"
    header = b"{'descr': '<f4', 'fortran_order': False, 'shape': (48, 64)"
    path.write_bytes(b"\x93NUMPY\x01\x00" + struct.pack("<H", 118) + header.ljust(117) + b"\n" + b"\0" * 64)
    assert "not a readable NPY array" in _one_line(clear("segment", path, "--intrinsics", "52.5 52.5 31.5 23.5"), 3)


def test_an_intrinsics_number_too_large_for_a_float_is_bad_input(small_pair: Path) -> None:
    (small_pair / "camera_params.json").write_text(
        '{"fx": 52.5, "fy": 52.5, "x_offset": 31.5, "y_offset": ' + "9" * 400 + ', "img_width": 64, "img_height": 48}'
    )
    assert "cy = 999" in _one_line(clear("info", small_pair / "f_depth.png"), 3)  # y_offset is cy


def test_a_fifo_given_as_colour_or_settings_is_refused_not_waited_on(small_pair: Path) -> None:
    fifo = small_pair / "pipe"
    os.mkfifo(fifo)
    assert "not a regular file" in _one_line(
        clear("segment", small_pair / "f_depth.png", "--color", fifo, timeout=60), 3
    )
    assert "not a regular file" in _one_line(clear("segment", BOX, "--settings", fifo, timeout=60), 3)


def test_a_settings_file_nested_too_deeply_is_bad_input(tmp_path: Path) -> None:
    deep = tmp_path / "deep.toml"
    deep.write_text("a = " + "[" * 2000 + "\n")
    assert "not valid TOML" in _one_line(clear("segment", BOX, "--settings", deep), 3)


def test_two_outputs_naming_one_file_are_refused(tmp_path: Path) -> None:
    line = _one_line(clear("segment", BOX, "-o", tmp_path / "out.png", "--png", tmp_path / "out.png"), 3)
    assert "name the same file" in line and not (tmp_path / "out.png").exists()


def test_an_error_naming_a_file_with_a_newline_stays_on_one_line(tmp_path: Path) -> None:
    # a script reads stderr line by line: the file name's newline is shown escaped
    odd = tmp_path / "new\nline.pcd"
    shutil.copy(FIXTURES / "clutter10.pcd", odd)
    run = clear("segment", odd, "-o", odd)
    assert run.returncode == 8  # -o naming the input: an output error, refused before anything is read
    assert run.stderr.count("\n") == 1 and "new\\nline.pcd" in run.stderr, run.stderr
