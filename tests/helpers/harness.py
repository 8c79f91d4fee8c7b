"""The garbage-input harness: seeded cases of damaged inputs, odd settings and odd output
targets, each run through `clear` in this process, each checked against the promises of
the README's "Exit codes", "Reliability", "Inputs" and "RGB-D inputs":

- the exit code is a documented one (0, 3, 4, 5, 6, 8, 9, 10, 11, 12; 1 is a bug) and, where
  the case knows better (a truncated log with complete frames: 9; an output onto an
  input: 8; a URDF whose base is its flange: 3), the right one;
- no Python traceback, ever; an error exit says so in exactly one line on stderr,
  ``clear: error: ...``, the last line;
- outputs (-o, --png, --out, ...) are whole or absent: what exists afterwards decodes (a
  PNG loads, a PCD reads, JSON parses, an MCAP iterates), and no temporary
  (``.<name>.<8 chars>.part`` / ``.<name>.<8 chars>.<suffix>``) is left beside it;
- inputs are never changed: every file of the case folder that is not a declared output
  is byte-identical afterwards; a FIFO or character device stays one (same device
  numbers); no file appears that nobody asked for.

Cases are made per input kind (``KINDS``) by generators that draw every choice from
``random.Random(f"{seed}:{index}")`` (and a NumPy Generator seeded from it), so a case is
rebuilt exactly from (seed, index): ``python benchmarks/fuzz.py --seed S --case I --keep
DIR`` writes its files and prints its command line. ``run_cases(seed, n, kinds)`` runs n
of them and returns a `Report` whose failures each carry a one-line repro.

Speed: `clear` runs in this process (``clearcli.cli.main`` with ``sys.argv`` set and file
descriptors 1 and 2 pointed at temporary files, so output from C libraries and from
threads is caught as a subprocess's pipes would catch it; SIGINT/SIGTERM handlers, the
warnings filters and the streams are restored after each case; a case's time is bounded
by SIGALRM). `compare_with_subprocess` runs a case both ways to hold that the two agree.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import io
import itertools
import json
import logging
import math
import os
import random
import re
import shutil
import signal
import stat
import struct
import subprocess
import sys
import tempfile
import threading
import time
import warnings
import zlib
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[2]
SHARED_DATA = Path(os.environ.get("CLEAR_SHARED", REPO.parent / "shared")).resolve() / "data"
SHARED_MCAP = SHARED_DATA / "rgbd" / "uois_realsense_ros2.mcap"

DOCUMENTED = frozenset({0, 3, 4, 5, 6, 8, 9, 10, 11, 12})
USAGE = 2  # click's usage error: allowed only where a case passes a value click parses
# exits that are errors of a single call: exactly one `clear: error:` line, the last
ONE_LINE_ERRORS = frozenset({3, 4, 6, 8, 9})
KINDS = ("depth", "color", "intrinsics", "log", "urdf", "settings", "outputs", "cloud")
# share of cases that run a whole segment/plan on a 160 x 120 frame instead of failing fast
HEAVY_SHARE = 0.06
CASE_TIMEOUT_S = 25.0
HEAVY_TIMEOUT_S = 45.0
FIFO_TIMEOUT_S = 6.0  # a FIFO given as an input must be refused, not read: a run past this is a hang
SMALL = (64, 48)
PLAN = (160, 120)
_TEMPORARY = re.compile(r"\A\..+\.[a-z0-9_]{8}(?:\.part|\.[A-Za-z0-9]+)\Z", re.DOTALL)
_PY_WARNING = re.compile(r"^\S+\.py:\d+: \w*Warning: ", re.MULTILINE)

# The faults other engineers were fixing when this harness was written, told by the case's
# tags and the symptom (see `known_fault`).
KNOWN_FAULTS = {
    "K1": "PNG decompression bomb (a header claiming a huge image) gives exit 1",
    "K2": "a truncated depth-image MCAP exits 3 instead of 9",
    "K3": "-o X_color.png --force / --png camera_info.yaml --force overwrites a paired input",
    "K4": "-o/--png onto a character device replaces it with a regular file",
    "K5": "a URDF joint with lower > upper limit gives exit 1",
    "K6": "[robot] base_frame == flange_frame is not refused with exit 3 (exit 5, or whatever the frame gives)",
    "K7": "a rosbag2 metadata.yaml with the wrong message type",
    "K8": "--grasps orders like rim,pinch accepted where --set plan.grasps refuses them (or the reverse)",
}


# ----------------------------------------------------------------------------- running


class CaseTimeout(BaseException):
    """Raised by SIGALRM in the main thread when a case runs past its time (a
    BaseException: `clear`'s own `except Exception` does not swallow it)."""


@dataclass
class Run:
    code: int | str  # the exit code; "timeout" when the case ran past its time
    stdout: str
    stderr: str
    seconds: float


def _text_stream(fd: int, stderr: bool) -> io.TextIOWrapper:
    """A stream on ``fd`` as the interpreter makes one for a pipe."""
    raw = io.FileIO(fd, "w", closefd=False)
    return io.TextIOWrapper(
        io.BufferedWriter(raw),
        encoding="utf-8",
        errors="backslashreplace" if stderr else "strict",
        line_buffering=stderr,
    )


def run_inprocess(args: Sequence[str], timeout_s: float = CASE_TIMEOUT_S, env: dict[str, str] | None = None) -> Run:
    """`clear ARGS` run by ``clearcli.cli.main`` in this process, its exit code, stdout and
    stderr caught at the file-descriptor level (what a subprocess's pipes would get)."""
    from clearcli import cli

    signals = (signal.SIGINT, signal.SIGTERM, signal.SIGALRM)
    saved_handlers = {s: signal.getsignal(s) for s in signals}
    saved = (sys.argv, sys.stdout, sys.stderr, warnings.filters[:])
    saved_env = {k: os.environ.get(k) for k in ("CLEAR_DEBUG", *(env or {}))}
    for s in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            s.flush()
    out_file, err_file = tempfile.TemporaryFile(), tempfile.TemporaryFile()  # noqa: SIM115 (closed below)
    fd1, fd2 = os.dup(1), os.dup(2)
    os.dup2(out_file.fileno(), 1)
    os.dup2(err_file.fileno(), 2)
    sys.stdout, sys.stderr = _text_stream(1, False), _text_stream(2, True)
    sys.argv = ["clear", *map(str, args)]
    os.environ.pop("CLEAR_DEBUG", None)
    os.environ.update(env or {})
    # warnings and log records as a fresh interpreter shows them (pytest records both itself)
    saved_showwarning = (warnings.showwarning, warnings._showwarnmsg_impl)  # type: ignore[attr-defined]
    warnings.showwarning = warnings._showwarning_orig  # type: ignore[attr-defined]
    warnings._showwarnmsg_impl = _stderr_showwarnmsg  # type: ignore[attr-defined]
    _fresh_warning_filters()
    root = logging.getLogger()
    saved_logging = (root.handlers[:], root.level)
    root.handlers[:] = []  # no handler: the last resort prints WARNING and above on stderr, as in a fresh process
    root.setLevel(logging.WARNING)

    def _alarm(signum: int, frame: Any) -> None:
        raise CaseTimeout()

    code: int | str
    t0 = time.perf_counter()
    try:
        signal.signal(signal.SIGALRM, _alarm)
        try:
            signal.setitimer(signal.ITIMER_REAL, timeout_s)
            cli.main()
            code = 0
        except SystemExit as exc:
            if exc.code is None:
                code = 0
            elif isinstance(exc.code, int):
                code = exc.code
            else:  # what the interpreter does with sys.exit("text")
                sys.stderr.write(f"{exc.code}\n")
                code = 1
        except CaseTimeout:
            code = "timeout"
        except BaseException:  # noqa: BLE001  (what the interpreter would print for an escaped exception)
            import traceback

            traceback.print_exc()
            code = 1
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        seconds = time.perf_counter() - t0
        for s in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                s.flush()
        os.dup2(fd1, 1)
        os.dup2(fd2, 2)
        os.close(fd1)
        os.close(fd2)
        sys.argv, sys.stdout, sys.stderr = saved[0], saved[1], saved[2]
        warnings.filters[:] = saved[3]
        warnings._filters_mutated()  # type: ignore[attr-defined]
        warnings.showwarning, warnings._showwarnmsg_impl = saved_showwarning  # type: ignore[attr-defined]
        root.handlers[:] = saved_logging[0]
        root.setLevel(saved_logging[1])
        for s, h in saved_handlers.items():
            signal.signal(s, h)
        for k, v in saved_env.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    out_file.seek(0)
    err_file.seek(0)
    out, err = out_file.read().decode("utf-8", "replace"), err_file.read().decode("utf-8", "replace")
    out_file.close()
    err_file.close()
    if code == "timeout":
        _recover_after_timeout()
    return Run(code, out, err, seconds)


def _stderr_showwarnmsg(msg: Any) -> None:
    """What Python prints for a warning (warnings._showwarnmsg_impl, which a
    catch_warnings(record=True) such as pytest's replaces)."""
    with contextlib.suppress(OSError):
        sys.stderr.write(warnings._formatwarnmsg(msg))  # type: ignore[attr-defined]


def _fresh_warning_filters() -> None:
    """The warnings filters of a fresh `python` (3.11, no -W): DeprecationWarning shown in
    __main__ only, the other deprecations, import and resource warnings ignored; every
    module's record of warnings already shown forgotten."""
    warnings.resetwarnings()
    warnings.filterwarnings("default", category=DeprecationWarning, module="__main__", append=True)
    for category in (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning):
        warnings.simplefilter("ignore", category, append=True)
    warnings._filters_mutated()  # type: ignore[attr-defined]


def _recover_after_timeout() -> None:
    """A case stopped by its alarm may leave `clear`'s colour-decoding thread blocked (on a
    FIFO): give the next case a fresh one."""
    with contextlib.suppress(Exception):
        from clearcli.io import images

        images._executor = None


def run_subprocess(args: Sequence[str], timeout_s: float = 120.0) -> Run:
    """`clear ARGS` as its own process (the installed script)."""
    exe = Path(sys.executable).with_name("clear")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "clearcli.cli"]
    env = {k: v for k, v in os.environ.items() if k != "CLEAR_DEBUG"}
    t0 = time.perf_counter()
    try:
        res = subprocess.run(
            [*cmd, *map(str, args)],
            capture_output=True,
            timeout=timeout_s,
            cwd=REPO,
            env=env,
            stdin=subprocess.DEVNULL,
            check=False,
        )
    except subprocess.TimeoutExpired as exc:
        return Run(
            "timeout",
            (exc.stdout or b"").decode("utf-8", "replace"),
            (exc.stderr or b"").decode("utf-8", "replace"),
            time.perf_counter() - t0,
        )
    return Run(
        res.returncode,
        res.stdout.decode("utf-8", "replace"),
        res.stderr.decode("utf-8", "replace"),
        time.perf_counter() - t0,
    )


# ----------------------------------------------------------------------------- bytes


PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def png_chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)


def png_encode(
    pixels: np.ndarray,
    *,
    extra: Sequence[tuple[bytes, bytes]] = (),
    colortype: int | None = None,
    bitdepth: int | None = None,
) -> bytes:
    """A PNG of ``pixels`` (H, W) or (H, W, C), uint8 or uint16, filter 0, one IDAT."""
    a = np.asarray(pixels)
    h, w = a.shape[:2]
    channels = 1 if a.ndim == 2 else a.shape[2]
    if bitdepth is None:
        bitdepth = 16 if a.dtype == np.uint16 else 8
    if colortype is None:
        colortype = {1: 0, 2: 4, 3: 2, 4: 6}[channels]
    rows = a.astype(">u2" if bitdepth == 16 else np.uint8).reshape(h, -1).view(np.uint8).reshape(h, -1)
    raw = np.concatenate([np.zeros((h, 1), np.uint8), rows], axis=1).tobytes()
    ihdr = struct.pack(">IIBBBBB", w, h, bitdepth, colortype, 0, 0, 0)
    body = b"".join(png_chunk(k, v) for k, v in extra)
    return (
        PNG_MAGIC
        + png_chunk(b"IHDR", ihdr)
        + body
        + png_chunk(b"IDAT", zlib.compress(raw, 6))
        + png_chunk(b"IEND", b"")
    )


def png_chunks(data: bytes) -> list[tuple[bytes, bytes]]:
    out, pos = [], 8
    while pos + 8 <= len(data):
        (n,) = struct.unpack(">I", data[pos : pos + 4])
        out.append((data[pos + 4 : pos + 8], data[pos + 8 : pos + 8 + n]))
        pos += 12 + n
    return out


def png_build(chunks: Iterable[tuple[bytes, bytes]]) -> bytes:
    return PNG_MAGIC + b"".join(png_chunk(k, v) for k, v in chunks)


def png_set_ihdr(data: bytes, **fields: int) -> bytes:
    """``data`` with IHDR fields (width, height, bitdepth, colortype, interlace) changed and
    the chunk's CRC recomputed: only what was changed lies."""
    chunks = png_chunks(data)
    kind, body = chunks[0]
    assert kind == b"IHDR"
    w, h, bd, ct, comp, filt, inter = struct.unpack(">IIBBBBB", body)
    w, h = fields.get("width", w), fields.get("height", h)
    bd, ct, inter = fields.get("bitdepth", bd), fields.get("colortype", ct), fields.get("interlace", inter)
    chunks[0] = (b"IHDR", struct.pack(">IIBBBBB", w & 0xFFFFFFFF, h & 0xFFFFFFFF, bd, ct, comp, filt, inter))
    return png_build(chunks)


def png_bomb(width: int, height: int, bitdepth: int = 16, colortype: int = 0) -> bytes:
    """A PNG whose IDAT really inflates to width x height pixels of zeros: a few hundred
    kilobytes on disk, width x height x 2 bytes decoded."""
    bpp = {0: 1, 2: 3, 4: 2, 6: 4}[colortype] * bitdepth // 8
    row = b"\x00" * (1 + width * bpp)
    comp = zlib.compressobj(9)
    parts = [comp.compress(row) for _ in range(height)]
    parts.append(comp.flush())
    ihdr = struct.pack(">IIBBBBB", width, height, bitdepth, colortype, 0, 0, 0)
    return PNG_MAGIC + png_chunk(b"IHDR", ihdr) + png_chunk(b"IDAT", b"".join(parts)) + png_chunk(b"IEND", b"")


def tiff_set_tag(data: bytes, tag: int, value: int) -> bytes:
    """A little-endian TIFF with the first IFD's ``tag`` (e.g. 256 width, 257 height) set
    to ``value`` in place (clipped to the entry's type)."""
    if not data.startswith(b"II*\x00"):
        return data
    b = bytearray(data)
    (ifd,) = struct.unpack("<I", b[4:8])
    if ifd + 2 > len(b):
        return data
    (n,) = struct.unpack("<H", b[ifd : ifd + 2])
    for k in range(n):
        e = ifd + 2 + 12 * k
        if e + 12 > len(b):
            break
        t, typ = struct.unpack("<HH", b[e : e + 4])
        if t == tag:
            if typ == 3:
                b[e + 8 : e + 10] = struct.pack("<H", min(value, 0xFFFF))
            else:
                b[e + 8 : e + 12] = struct.pack("<I", min(value, 0xFFFFFFFF))
    return bytes(b)


def npy_bytes(header: dict[str, Any] | str, payload: bytes) -> bytes:
    """An NPY v1.0 file with ``header`` (a dict written as numpy writes it, or raw text)
    over ``payload``, the header padded as numpy pads it."""
    text = header if isinstance(header, str) else repr(header)
    text = text + " " * ((64 - (10 + len(text) + 1) % 64) % 64) + "\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(text)) + text.encode("latin-1") + payload


def flip_bytes(data: bytes, rng: random.Random, n: int, start: int = 0) -> tuple[bytes, str]:
    if len(data) <= start:
        return data, "nothing to flip"
    b = bytearray(data)
    where = sorted(rng.randrange(start, len(b)) for _ in range(n))
    for p in where:
        b[p] ^= rng.randrange(1, 256)
    return bytes(b), f"{n} byte(s) flipped at {where[:6]}{'...' if n > 6 else ''}"


def truncate(data: bytes, rng: random.Random) -> tuple[bytes, int]:
    """``data`` cut at a random offset (favouring both ends: headers and last records)."""
    n = len(data)
    r = rng.random()
    if r < 0.25:
        off = rng.randrange(0, min(n, 128))
    elif r < 0.45:
        off = max(0, n - rng.randrange(1, min(n, 256) + 1))
    else:
        off = rng.randrange(0, n)
    return data[:off], off


def sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fp:
        for block in iter(lambda: fp.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


# ----------------------------------------------------------------------------- materials


@dataclass
class Frame2D:
    depth_mm: np.ndarray  # (H, W) uint16
    color: np.ndarray  # (H, W, 3) uint8
    k: tuple[float, float, float, float]  # fx fy cx cy

    @property
    def size(self) -> tuple[int, int]:
        return self.depth_mm.shape[1], self.depth_mm.shape[0]


class Materials:
    """Valid inputs every case starts from, made once per process (deterministic)."""

    def __init__(self) -> None:
        self.root = Path(tempfile.mkdtemp(prefix="clear-harness-materials-"))
        self.frames = {size: self._frame(*size) for size in (SMALL, PLAN)}
        self._cache: dict[str, Any] = {}

    @staticmethod
    def _frame(w: int, h: int) -> Frame2D:
        from clearcli.settings.sim import PinholeCamera
        from clearcli.sim.camera import render
        from clearcli.sim.scene import Box, make_scene

        scene = make_scene(
            "harness",
            [
                Box(0, 0.05, 0.04, 0.08, x_m=-0.1, y_m=0.0, yaw_rad=0.4),
                Box(1, 0.06, 0.05, 0.06, x_m=0.1, y_m=0.05),
            ],
        )
        f = w / 640 * 525.0
        cam = PinholeCamera(width=w, height=h, fx=f, fy=f, cx=(w - 1) / 2, cy=(h - 1) / 2)
        fr = render(scene, camera=cam, seed=0)
        z = fr.points[:, 2].reshape(h, w)
        depth = np.where(np.isfinite(z), np.round(z * 1000.0), 0).astype(np.uint16)
        color = np.asarray(fr.colors, dtype=np.uint8).reshape(h, w, 3)
        return Frame2D(depth, color, (f, f, (w - 1) / 2, (h - 1) / 2))

    def cached(self, key: str, make: Callable[[], Any]) -> Any:
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    # --- images
    def depth_bytes(self, fmt: str, size: tuple[int, int] = SMALL) -> bytes:
        return self.cached(f"depth:{fmt}:{size}", lambda: _encode_depth(self.frames[size].depth_mm, fmt))

    def color_bytes(self, fmt: str, size: tuple[int, int] = SMALL) -> bytes:
        return self.cached(f"color:{fmt}:{size}", lambda: _encode_color(self.frames[size].color, fmt))

    # --- logs
    def mcap_bytes(self, layout: str = "zstd") -> bytes:
        """Three 64 x 48 frames: "zstd" (the writer's default: one compressed chunk) or
        "plain" (uncompressed chunks of 4 KiB: a cut leaves whole frames before it)."""

        def make() -> bytes:
            fr = self.frames[SMALL]
            path = self.root / f"small-{layout}.mcap"
            write_image_mcap(path, [default_log_frame(fr, k) for k in range(3)], plain=layout == "plain")
            return path.read_bytes()

        return self.cached(f"mcap:{layout}", make)

    def rosbag2_dir(self) -> Path:
        def make() -> Path:
            from helpers.rgbd_logs import write_rgbd_bag

            fr = self.frames[SMALL]
            path = self.root / "bag2"
            write_rgbd_bag(path, [fr.depth_mm, fr.depth_mm], [fr.color, fr.color], ros1=False)
            return path

        return self.cached("rosbag2", make)

    def ros1_bytes(self) -> bytes:
        def make() -> bytes:
            from helpers.rgbd_logs import write_rgbd_bag

            fr = self.frames[SMALL]
            path = self.root / "small.bag"
            write_rgbd_bag(path, [fr.depth_mm, fr.depth_mm], [fr.color, fr.color], ros1=True)
            return path.read_bytes()

        return self.cached("ros1", make)

    # --- robots and settings
    def panda_urdf(self) -> str:
        return self.cached("panda", lambda: (REPO / "clearcli" / "robot" / "panda.urdf").read_text())

    def settings_ranges(self) -> list[tuple[str, str, str, str]]:
        """(section, key, default TOML value, accepted range text) of every setting."""

        def make() -> list[tuple[str, str, str, str]]:
            run = run_inprocess(["settings", "--ranges"])
            assert run.code == 0, run.stderr
            out, section = [], ""
            for line in run.stdout.splitlines():
                m = re.match(r"^\[(\w+)\]$", line.strip())
                if m:
                    section = m.group(1)
                    continue
                m = re.match(r"^(\w+) = (.*?)(?:  # (.*))?$", line)
                if m and section:
                    out.append((section, m.group(1), m.group(2), m.group(3) or ""))
            return out

        return self.cached("ranges", make)

    def settings_toml(self) -> str:
        def make() -> str:
            run = run_inprocess(["settings"])
            assert run.code == 0, run.stderr
            return run.stdout

        return self.cached("toml", make)

    def close(self) -> None:
        shutil.rmtree(self.root, ignore_errors=True)


def _encode_depth(depth_mm: np.ndarray, fmt: str) -> bytes:
    if fmt == "png":
        return png_encode(depth_mm)
    if fmt == "tiff":
        from PIL import Image

        buf = io.BytesIO()
        Image.fromarray(depth_mm.astype(np.float32) / 1000.0, mode="F").save(buf, format="TIFF")
        return buf.getvalue()
    buf = io.BytesIO()
    arr = {
        "npy_f32": depth_mm.astype(np.float32) / 1000.0,
        "npy_u16": depth_mm,
        "npy_f64": depth_mm.astype(np.float64) / 1000.0,
    }[fmt]
    np.save(buf, arr)
    return buf.getvalue()


def _encode_color(color: np.ndarray, fmt: str) -> bytes:
    if fmt == "png":
        return png_encode(color)
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(color).save(buf, format="JPEG", quality=90)
    return buf.getvalue()


def intrinsics_files(k: tuple[float, float, float, float], size: tuple[int, int]) -> dict[str, tuple[str, Any]]:
    """Each layout `clear` reads, as (file name, mapping) for the camera ``k`` at ``size``."""
    fx, fy, cx, cy = k
    w, h = size
    return {
        "ros_yaml": (
            "camera_info.yaml",
            {
                "image_width": w,
                "image_height": h,
                "camera_name": "cam",
                "camera_matrix": {"rows": 3, "cols": 3, "data": [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0]},
                "distortion_model": "plumb_bob",
                "distortion_coefficients": {"rows": 1, "cols": 5, "data": [0.0] * 5},
            },
        ),
        "camera_info": (
            "camera_info.yaml",
            {
                "width": w,
                "height": h,
                "distortion_model": "plumb_bob",
                "d": [0.0] * 5,
                "k": [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0],
                "binning_x": 0,
                "binning_y": 0,
                "roi": {"x_offset": 0, "y_offset": 0, "height": 0, "width": 0, "do_rectify": False},
            },
        ),
        "open3d": (
            "intrinsics.json",
            {"width": w, "height": h, "intrinsic_matrix": [fx, 0.0, 0.0, 0.0, fy, 0.0, cx, cy, 1.0]},
        ),
        "uois": (
            "camera_params.json",
            {"fx": fx, "fy": fy, "x_offset": cx, "y_offset": cy, "img_width": w, "img_height": h},
        ),
    }


def dump_mapping(name: str, data: Any) -> str:
    if name.endswith(".json"):
        return json.dumps(data, allow_nan=True)
    import yaml

    return yaml.safe_dump(data, sort_keys=False)


def four_numbers(k: Sequence[float]) -> str:
    return " ".join(repr(float(v)) for v in k)


# --- image logs (ROS 2 MCAP, written message by message so that any field may lie)


def default_log_frame(fr: Frame2D, k: int) -> dict[str, Any]:
    from helpers.rgbd_logs import image_msg, info_msg

    w, h = fr.size
    t = 1_700_000_000_000_000_000 + k * 1_000_000_000
    fid = "camera_color_optical_frame"
    return {
        "t": t,
        "info": info_msg(w, h, t, fid, k=fr.k),
        "color": image_msg(fr.color, "rgb8", t, fid),
        "depth": image_msg(fr.depth_mm, "16UC1", t, fid),
    }


def write_image_mcap(
    path: Path, frames: list[dict[str, Any]], ns: str = "/camera", depth_topic: str | None = None, plain: bool = False
) -> None:
    """Frames of dicts {t, info, color, depth} (message dicts, any of them None) as ROS 2
    CameraInfo + Image messages, in that order per frame."""
    from helpers.rgbd_logs import CAMERA_INFO_MSGDEF, IMAGE_MSGDEF
    from mcap_ros2.writer import Writer

    with open(path, "wb") as fp:
        if plain:
            from mcap.writer import CompressionType

            writer = Writer(fp, chunk_size=4096, compression=CompressionType.NONE)
        else:
            writer = Writer(fp)
        image = writer.register_msgdef("sensor_msgs/msg/Image", IMAGE_MSGDEF)
        camera = writer.register_msgdef("sensor_msgs/msg/CameraInfo", CAMERA_INFO_MSGDEF)
        for f in frames:
            t = f["t"]
            if f.get("info") is not None:
                writer.write_message(f"{ns}/depth/camera_info", camera, f["info"], log_time=t, publish_time=t)
            if f.get("color") is not None:
                writer.write_message(
                    f"{ns}/color/image_raw", image, f["color"], log_time=t + 1000, publish_time=t + 1000
                )
            if f.get("depth") is not None:
                writer.write_message(
                    depth_topic or f"{ns}/depth/image_raw", image, f["depth"], log_time=t + 2000, publish_time=t + 2000
                )
        writer.finish()


def complete_depth_frames(data: bytes) -> int:
    """How many depth Image messages, each with a camera info before it, a streaming MCAP
    reader gets whole out of ``data`` before it breaks."""
    from mcap.records import Channel, Message, Schema
    from mcap.stream_reader import StreamReader

    channels: dict[int, tuple[str, str]] = {}
    schemas: dict[int, str] = {}
    seen_info: set[str] = set()
    n = 0
    try:
        for record in StreamReader(io.BytesIO(data), skip_magic=False).records:
            if isinstance(record, Schema):
                schemas[record.id] = record.name
            elif isinstance(record, Channel):
                channels[record.id] = (record.topic, schemas.get(record.schema_id, ""))
            elif isinstance(record, Message):
                topic, schema = channels.get(record.channel_id, ("", ""))
                if schema.endswith("CameraInfo"):
                    seen_info.add(topic.rsplit("/", 1)[0])
                elif schema.endswith("/Image") and "depth" in topic and topic.rsplit("/", 1)[0] in seen_info:
                    n += 1
    except Exception:  # noqa: BLE001, S110  (where the reader breaks is the answer)
        pass
    return n


# ----------------------------------------------------------------------------- cases


@dataclass
class Output:
    path: Path
    kind: str  # png | pcd | json | text | pddl | mcap | dir
    must_refuse: bool = False  # the run must not write it (an input, an existing file without --force)
    required: bool = True  # a run that exits 0 has written it


@dataclass
class Case:
    kind: str
    seed: int
    index: int
    dir: Path
    runs: list[list[str]] = field(default_factory=list)  # one argv per run (most cases: one)
    recipe: list[str] = field(default_factory=list)
    tags: set[str] = field(default_factory=set)
    allowed: frozenset[int] = DOCUMENTED
    expect: frozenset[int] | None = None  # a stricter oracle where the case knows the right code
    outputs: list[Output] = field(default_factory=list)
    watched: list[Path] = field(default_factory=list)  # inputs outside the case folder (hashed)
    timeout_s: float = CASE_TIMEOUT_S
    heavy: bool = False
    consistent: bool = False  # every run must give the same exit code (the same rule said three ways)

    @property
    def args(self) -> list[str]:
        return self.runs[0] if self.runs else []

    def command_lines(self) -> list[str]:
        import shlex

        return ["clear " + " ".join(shlex.quote(a) for a in run) for run in self.runs]


class Ctx:
    """What a generator draws from: the case's random sources, its folder, the materials."""

    def __init__(self, case: Case, mat: Materials) -> None:
        self.case = case
        self.rng = random.Random(f"{case.seed}:{case.index}:{case.kind}")
        self.np = np.random.default_rng(self.rng.getrandbits(64))
        self.dir = case.dir
        self.mat = mat

    def note(self, text: str) -> None:
        self.case.recipe.append(text)

    def tag(self, *tags: str) -> None:
        self.case.tags.update(tags)

    def pick(self, weights: dict[str, float]) -> str:
        names = list(weights)
        return self.rng.choices(names, weights=[weights[n] for n in names])[0]

    def choice(self, seq: Sequence[Any]) -> Any:
        return seq[self.rng.randrange(len(seq))]

    def write(self, name: str, data: bytes | str) -> Path:
        path = self.dir / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data.encode() if isinstance(data, str) else data)
        return path

    def run(self, *args: Any) -> None:
        self.case.runs.append([str(a) for a in args])

    def rel(self, path: Path) -> str:
        with contextlib.suppress(ValueError):
            return str(Path(path).relative_to(self.dir))
        return str(path)


# odd numbers for numeric fields: (text for TOML/YAML/strings, Python value)
SPECIAL_NUMBERS: list[tuple[str, Any]] = [
    ("nan", float("nan")),
    ("inf", float("inf")),
    ("-inf", float("-inf")),
    ("0", 0),
    ("-0.0", -0.0),
    ("-1", -1),
    ("-1e-9", -1e-9),
    ("1e-300", 1e-300),
    ("5e-324", 5e-324),
    ("1e9", 1e9),
    ("1e308", 1e308),
    ("1e400", float("inf")),
    ("1" + "0" * 400, 10**400),
    ("9223372036854775808", 2**63),
    ("-9223372036854775809", -(2**63) - 1),
    ("4294967296", 2**32),
    ("0.5", 0.5),
    ("1.5", 1.5),
    ("3", 3),
    ("65535", 65535),
]
ODD_VALUES: list[Any] = [
    "abc",
    "",
    "1e3",
    "0x10",
    "nan",
    None,
    [],
    [1, 2],
    {},
    {"a": 1},
    True,
    False,
    "١٢٣",
    "1_000",
    " 5 ",
]


def odd_number(ctx: Ctx) -> tuple[str, Any]:
    if ctx.rng.random() < 0.8:
        return ctx.choice(SPECIAL_NUMBERS)
    v = ctx.choice(ODD_VALUES)
    return json.dumps(v), v


# --- depth images ------------------------------------------------------------------------


DEPTH_SUFFIX = {"png": ".png", "tiff": ".tif", "npy_f32": ".npy", "npy_u16": ".npy", "npy_f64": ".npy"}


def _command_for_image(ctx: Ctx, depth: Path, extra: Sequence[str] = (), heavy_ok: bool = True) -> None:
    """info / segment / plan on a depth image, most of them failing fast on the small frame."""
    weights = {"info": 0.35, "segment": 0.5, "plan": 0.15}
    if "--set" in extra or "--settings" in extra:  # info reads no settings
        weights["info"] = 0.0
    cmd = ctx.pick(weights)
    json_flag = ["--json"] if ctx.rng.random() < 0.5 else []
    ctx.run(cmd, depth, *extra, *json_flag)


def gen_depth(ctx: Ctx) -> None:
    """Depth images (16-bit PNG, float TIFF, NPY) damaged every way the README names."""
    fmt = ctx.pick({"png": 0.5, "tiff": 0.2, "npy_f32": 0.15, "npy_u16": 0.1, "npy_f64": 0.05})
    size = PLAN if ctx.case.heavy else SMALL
    fr = ctx.mat.frames[size]
    data = ctx.mat.depth_bytes(fmt, size)
    name = "f_depth" + DEPTH_SUFFIX[fmt]
    ctx.tag(fmt)
    mutation = (
        ctx.pick(
            {
                "valid": 0.03,
                "truncate": 0.16,
                "flip": 0.14,
                "ihdr_huge": 0.08,
                "ihdr_size": 0.08,
                "ihdr_format": 0.06,
                "idat_bad_crc_fixed": 0.04,
                "values": 0.12,
                "npy_header": 0.07,
                "empty": 0.02,
                "directory": 0.02,
                "wrong_content": 0.08,
                "bomb_text": 0.02,
                "bomb_idat": 0.01,
                "shapes": 0.05,
                "tiff_tags": 0.02,
            }
        )
        if not ctx.case.heavy
        else ctx.pick({"valid": 0.2, "values": 0.8})
    )
    ctx.tag(mutation)
    path = ctx.dir / name
    if mutation == "valid":
        ctx.note(f"valid {fmt} depth {size[0]}x{size[1]}")
    elif mutation == "truncate":
        data, off = truncate(data, ctx.rng)
        ctx.note(f"{fmt} depth truncated at byte {off}")
    elif mutation == "flip":
        data, how = flip_bytes(data, ctx.rng, ctx.rng.choice([1, 1, 2, 4, 16]))
        ctx.note(f"{fmt} depth: {how}")
    elif mutation in ("ihdr_huge", "ihdr_size", "ihdr_format", "idat_bad_crc_fixed") and fmt != "png":
        data, how = flip_bytes(data, ctx.rng, 2, start=min(8, len(data) - 1))
        ctx.note(f"{fmt} depth (no PNG header to change): {how}")
    elif mutation == "ihdr_huge":
        w, h = ctx.choice(
            [
                (100000, 100000),
                (16385, 1),
                (1, 16385),
                (6000, 6000),
                (70000, 2),
                (2**31 - 1, 2**31 - 1),
                (2**32 - 1, 1),
                (40000, 40000),
            ]
        )
        data = png_set_ihdr(data, width=w, height=h)
        ctx.tag("bomb")
        ctx.note(f"png depth, IHDR says {w}x{h} (CRC recomputed)")
    elif mutation == "ihdr_size":
        w0, h0 = size
        w, h = ctx.choice(
            [(w0 * 2, h0), (w0, h0 + 1), (w0 - 1, h0), (1, 1), (0, h0), (w0, 0), (h0, w0), (w0 // 2, h0 * 2)]
        )
        data = png_set_ihdr(data, width=w, height=h)
        ctx.note(f"png depth, IHDR size {w}x{h} for {w0}x{h0} data (CRC recomputed)")
    elif mutation == "ihdr_format":
        bd, ct = ctx.choice(
            [(8, 0), (1, 0), (4, 0), (16, 2), (16, 4), (8, 3), (16, 6), (3, 0), (32, 0), (16, 1), (8, 7)]
        )
        inter = ctx.choice([0, 0, 1, 2])
        data = png_set_ihdr(data, bitdepth=bd, colortype=ct, interlace=inter)
        ctx.note(f"png depth, IHDR bit depth {bd}, colour type {ct}, interlace {inter} (CRC recomputed)")
    elif mutation == "idat_bad_crc_fixed":
        chunks = png_chunks(data)
        for k, (t, body) in enumerate(chunks):
            if t == b"IDAT":
                nb, how = flip_bytes(body, ctx.rng, ctx.rng.choice([1, 3, 8]))
                if ctx.rng.random() < 0.3:
                    nb = body[: ctx.rng.randrange(0, len(body))]
                    how = f"cut to {len(nb)} of {len(body)} bytes"
                chunks[k] = (t, nb)
        data = png_build(chunks)
        ctx.note(f"png depth, IDAT {how} (CRC recomputed)")
    elif mutation == "values":
        arr = fr.depth_mm.astype(np.float32) / 1000.0
        special = ctx.choice(
            ["nan", "inf", "-inf", "neg", "zero", "huge", "tiny", "max16", "noise", "one_pixel", "all_nan"]
        )
        frac = ctx.choice([0.01, 0.2, 1.0])
        mask = ctx.np.random(arr.shape) < frac
        value = {
            "nan": np.nan,
            "inf": np.inf,
            "-inf": -np.inf,
            "neg": -0.5,
            "zero": 0.0,
            "huge": 3e38,
            "tiny": 1e-40,
            "max16": 65.535,
            "noise": None,
            "one_pixel": None,
            "all_nan": np.nan,
        }[special]
        if special == "noise":
            arr = arr + ctx.np.normal(0, 0.05, arr.shape).astype(np.float32)
        elif special == "one_pixel":
            arr = np.zeros_like(arr)
            arr[size[1] // 2, size[0] // 2] = 0.8
        elif special == "all_nan":
            arr[:] = np.nan
        else:
            arr[mask] = value
        ctx.note(f"{fmt} depth with {special} values in {frac:.0%} of pixels")
        if fmt == "png":
            with np.errstate(invalid="ignore", over="ignore"):
                mm = np.nan_to_num(arr * 1000.0, nan=0.0, posinf=65535, neginf=0)
            data = png_encode(np.clip(mm, 0, 65535).astype(np.uint16))
        elif fmt == "tiff":
            from PIL import Image

            buf = io.BytesIO()
            Image.fromarray(arr.astype(np.float32), mode="F").save(buf, format="TIFF")
            data = buf.getvalue()
        else:
            buf = io.BytesIO()
            with np.errstate(invalid="ignore", over="ignore"):
                out = (
                    np.nan_to_num(arr * 1000, nan=0, posinf=65535, neginf=0).clip(0, 65535).astype(np.uint16)
                    if fmt == "npy_u16"
                    else arr.astype(np.float64 if fmt == "npy_f64" else np.float32)
                )
            np.save(buf, out)
            data = buf.getvalue()
    elif mutation == "npy_header":
        payload = (fr.depth_mm.astype(np.float32) / 1000.0).tobytes()
        header = ctx.choice(
            [
                {"descr": "<f4", "fortran_order": False, "shape": (100000, 100000)},
                {"descr": "<f4", "fortran_order": False, "shape": (size[1] * 2, size[0])},
                {"descr": "<f4", "fortran_order": True, "shape": (size[1], size[0])},
                {"descr": "<f4", "fortran_order": False, "shape": (0, size[0])},
                {"descr": "<f4", "fortran_order": False, "shape": (size[1], size[0], 0)},
                {"descr": "<f4", "fortran_order": False, "shape": (-1, size[0])},
                {"descr": "|O", "fortran_order": False, "shape": (size[1], size[0])},
                {"descr": "<c8", "fortran_order": False, "shape": (size[1], size[0] // 2)},
                {"descr": "<U1", "fortran_order": False, "shape": (size[1], size[0])},
                {"descr": "|b1", "fortran_order": False, "shape": (size[1], size[0] * 4)},
                {"descr": ">f4", "fortran_order": False, "shape": (size[1], size[0])},
                {"descr": "<f2", "fortran_order": False, "shape": (size[1], size[0] * 2)},
                {"descr": "|V4", "fortran_order": False, "shape": (size[1], size[0])},
                {"descr": [("a", "<f4")], "fortran_order": False, "shape": (size[1], size[0])},
                {"descr": "<f4", "fortran_order": False, "shape": (size[1], size[0], 1, 1)},
                {"descr": "<f4", "fortran_order": False, "shape": ()},
                {"descr": "<f4", "fortran_order": False, "shape": (2**62, 2)},
                "{'descr': '<f4', 'fortran_order': False, 'shape': (48, 64), }" + " " * 5000,
                "{'descr': '<f4', 'fortran_order': False, 'shape': (48, 64)",
                "[1, 2, 3]",
                "{'descr': '<f4', 'fortran_order': False, 'shape': (1e9, 64), }",
                "{'descr': '<f4', 'fortran_order': False, 'shape': ('a', 64), }",
            ]
        )
        data = npy_bytes(header, payload)
        path = ctx.dir / "f_depth.npy"
        ctx.note(f"npy depth with header {str(header)[:90]!s}")
    elif mutation == "empty":
        data = b""
        ctx.note(f"empty {name}")
    elif mutation == "directory":
        path.mkdir()
        (path / "inside.png").write_bytes(ctx.mat.depth_bytes("png"))
        data = None
        ctx.note(f"{name} is a directory")
    elif mutation == "wrong_content":
        what = ctx.choice(
            [
                "color_png",
                "color_jpeg",
                "mcap",
                "text",
                "pcd_header",
                "rgb16",
                "gray_alpha16",
                "gray8",
                "palette",
                "tiff_rgb",
                "tiff_int32",
                "tiff_multi",
                "png_named_tif",
            ]
        )
        from PIL import Image

        buf = io.BytesIO()
        if what == "color_png":
            data = ctx.mat.color_bytes("png", size)
        elif what == "color_jpeg":
            data = ctx.mat.color_bytes("jpeg", size)
            path = ctx.dir / "f_depth.png"
        elif what == "mcap":
            data = ctx.mat.mcap_bytes()
        elif what == "text":
            data = b"this is not an image\n" * 3
        elif what == "pcd_header":
            data = b"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\n"
        elif what == "rgb16":
            data = png_encode(np.stack([fr.depth_mm] * 3, axis=-1))
        elif what == "gray_alpha16":
            data = png_encode(np.stack([fr.depth_mm, fr.depth_mm], axis=-1))
        elif what == "gray8":
            data = png_encode((fr.depth_mm // 8).astype(np.uint8))
        elif what == "palette":
            Image.fromarray(fr.color).convert("P").save(buf, format="PNG")
            data = buf.getvalue()
        elif what == "tiff_rgb":
            Image.fromarray(fr.color).save(buf, format="TIFF")
            data = buf.getvalue()
            path = ctx.dir / "f_depth.tif"
        elif what == "tiff_int32":
            Image.fromarray(fr.depth_mm.astype(np.int32), mode="I").save(buf, format="TIFF")
            data = buf.getvalue()
            path = ctx.dir / "f_depth.tif"
        elif what == "tiff_multi":
            a = Image.fromarray(fr.depth_mm.astype(np.float32) / 1000, mode="F")
            a.save(buf, format="TIFF", save_all=True, append_images=[a.resize((10, 10))])
            data = buf.getvalue()
            path = ctx.dir / "f_depth.tif"
        else:  # a PNG named .tif
            data = ctx.mat.depth_bytes("png", size)
            path = ctx.dir / "f_depth.tif"
        ctx.note(f"{what} given as the depth image {path.name}")
    elif mutation == "bomb_text":
        chunks = png_chunks(ctx.mat.depth_bytes("png", size))
        payload = zlib.compress(b"\x00" * ctx.choice([2**21, 2**26]), 9)
        kind = ctx.choice([b"zTXt", b"iCCP", b"iTXt"])
        body = {
            b"zTXt": b"Comment\x00\x00" + payload,
            b"iCCP": b"icc\x00\x00" + payload,
            b"iTXt": b"Comment\x00\x01\x00\x00\x00" + payload,
        }[kind]
        chunks.insert(1, (kind, body))
        data = png_build(chunks)
        path = ctx.dir / "f_depth.png"
        ctx.tag("bomb")
        ctx.note(f"png depth with a {kind.decode()} chunk inflating to megabytes")
    elif mutation == "bomb_idat":
        w, h = ctx.choice([(5000, 6000), (16384, 2048), (8192, 4096)])
        data = png_bomb(w, h)
        path = ctx.dir / "f_depth.png"
        ctx.tag("bomb")
        ctx.note(f"png depth whose IDAT really inflates to {w}x{h} zeros (within the size limit)")
    elif mutation == "shapes":
        arr = fr.depth_mm.astype(np.float32) / 1000.0
        shaped = ctx.choice(
            [
                arr.ravel(),
                arr[:, :, None],
                np.stack([arr] * 3, -1),
                arr[:1, :1],
                arr[None],
                arr.astype(bool),
                arr.astype(np.int8),
                arr.astype(np.complex64),
                np.zeros((0, 0), np.float32),
                (arr * 1000).astype(np.int64),
                (arr * 1000).astype(np.uint64) * (2**40),
            ]
        )
        buf = io.BytesIO()
        np.save(buf, shaped, allow_pickle=False)
        data = buf.getvalue()
        path = ctx.dir / "f_depth.npy"
        ctx.note(f"npy depth of shape {shaped.shape} and dtype {shaped.dtype}")
    elif mutation == "tiff_tags":
        if fmt != "tiff":
            data = ctx.mat.depth_bytes("tiff", size)
            path = ctx.dir / "f_depth.tif"
        tag, value = ctx.choice(
            [
                (256, 100000),
                (257, 100000),
                (256, 0),
                (257, 1),
                (258, 64),
                (277, 4),
                (259, 8),
                (273, 2**31),
                (279, 2**31),
                (278, 0),
            ]
        )
        data = tiff_set_tag(data, tag, value)
        ctx.tag("bomb" if value >= 100000 else "tiff_tag")
        ctx.note(f"tiff depth with tag {tag} set to {value}")
    if data is not None:
        path.write_bytes(data)
    flags: list[str] = []
    if ctx.rng.random() < 0.7:
        flags = ["--intrinsics", four_numbers(fr.k)]
    else:
        layout = ctx.choice(list(intrinsics_files(fr.k, size)))
        fname, mapping = intrinsics_files(fr.k, size)[layout]
        ctx.write(fname, dump_mapping(fname, mapping))
        ctx.note(f"{fname} ({layout}) beside it")
    if ctx.rng.random() < 0.12:
        text, _ = odd_number(ctx)
        flags += ["--depth-scale", text]
        ctx.note(f"--depth-scale {text}")
        ctx.tag("depth_scale")
        ctx.case.allowed = DOCUMENTED | {USAGE}
    if ctx.case.heavy:
        ctx.run(ctx.choice(["segment", "plan"]), path, *flags, "--json")
        ctx.case.timeout_s = HEAVY_TIMEOUT_S
    else:
        _command_for_image(ctx, path, flags)


# --- colour images ------------------------------------------------------------------------


def gen_color(ctx: Ctx) -> None:
    """A depth image with its colour image, by the naming rule or --color, the colour damaged."""
    size = PLAN if ctx.case.heavy else SMALL
    fr = ctx.mat.frames[size]
    fmt = ctx.pick({"png": 0.7, "jpeg": 0.3})
    ext = ".png" if fmt == "png" else ctx.choice([".jpg", ".jpeg"])
    data = ctx.mat.color_bytes(fmt, size)
    depth_suffix, color_suffix = "_depth", "_color"
    flags: list[str] = []
    if ctx.rng.random() < 0.15:  # the naming rule changed through [images]
        depth_suffix, color_suffix = ctx.choice(
            [
                ("_d", "_c"),
                ("-depth", "-rgb"),
                (".depth", ".color"),
                ("_depth", ""),
                ("_depth", "_depth_color"),
                ("_depth", "_x" * 200),
                ("_depth", "a/b"),
                ("_depth", "../up"),
                ("_depth", "_dépth"),
                ("_depth", "\u0000"),
                ("", "_color"),
                ("_depth", "_depth"),
                ("_depth", " "),
                ("_depth", "*"),
            ]
        )
        flags += [
            "--set",
            f"images.depth_suffix={json.dumps(depth_suffix)}",
            "--set",
            f"images.color_suffix={json.dumps(color_suffix)}",
        ]
        ctx.tag("suffixes")
        ctx.note(f"[images] depth_suffix {depth_suffix!r}, color_suffix {color_suffix!r}")
    depth_name = f"f{depth_suffix}.png"
    color_name = f"f{color_suffix}{ext}"
    if "/" in depth_name or "\x00" in depth_name or len(color_name) > 250 or "/" in color_name or "\x00" in color_name:
        color_name = f"f_color{ext}"
    depth = ctx.write(depth_name, ctx.mat.depth_bytes("png", size))
    ctx.write("camera_params.json", dump_mapping("camera_params.json", intrinsics_files(fr.k, size)["uois"][1]))
    mutation = (
        ctx.pick(
            {
                "valid": 0.04,
                "truncate": 0.15,
                "flip": 0.12,
                "ihdr_huge": 0.08,
                "ihdr_size": 0.06,
                "other_size": 0.12,
                "modes": 0.15,
                "empty": 0.03,
                "directory": 0.03,
                "fifo": 0.04,
                "wrong_content": 0.06,
                "bomb_idat": 0.01,
                "bomb_text": 0.02,
                "garbage_pixels": 0.05,
                "symlink_loop": 0.02,
                "dangling": 0.02,
            }
        )
        if not ctx.case.heavy
        else ctx.pick({"garbage_pixels": 0.5, "modes": 0.3, "other_size": 0.2})
    )
    ctx.tag(mutation, fmt)
    from PIL import Image

    by_flag = ctx.rng.random() < 0.3
    if color_name == depth_name and mutation in ("directory", "fifo", "symlink_loop", "dangling"):
        by_flag = True  # equal suffixes name the depth file itself, which cannot become a FIFO or a folder
    cpath = ctx.dir / ("given_colour" + ext if by_flag else color_name)
    if mutation == "valid":
        ctx.note(f"valid {fmt} colour")
    elif mutation == "truncate":
        data, off = truncate(data, ctx.rng)
        ctx.note(f"{fmt} colour truncated at {off}")
    elif mutation == "flip":
        data, how = flip_bytes(data, ctx.rng, ctx.rng.choice([1, 2, 8, 32]))
        ctx.note(f"{fmt} colour: {how}")
    elif mutation in ("ihdr_huge", "ihdr_size"):
        data = ctx.mat.color_bytes("png", size)
        cpath = cpath.with_suffix(".png")
        if mutation == "ihdr_huge":
            w, h = ctx.choice([(100000, 100000), (16385, 16385), (70000, 3), (2**31 - 1, 1), (30000, 30000)])
            ctx.tag("bomb")
        else:
            w, h = ctx.choice([(size[0] * 2, size[1]), (size[0], size[1] + 7), (1, 1), (0, 0)])
        data = png_set_ihdr(data, width=w, height=h)
        ctx.note(f"png colour, IHDR says {w}x{h} (CRC recomputed)")
    elif mutation == "other_size":
        w, h = ctx.choice(
            [(size[0] + 1, size[1]), (size[1], size[0]), (1, 1), (size[0] * 2, size[1] * 2), (size[0], size[1] - 1)]
        )
        img = Image.fromarray(fr.color).resize((w, h))
        buf = io.BytesIO()
        img.save(buf, format="PNG" if fmt == "png" else "JPEG")
        data = buf.getvalue()
        ctx.note(f"{fmt} colour of {w}x{h} for a {size[0]}x{size[1]} depth image")
    elif mutation == "modes":
        mode = ctx.choice(["L", "LA", "RGBA", "P", "1", "I;16", "I", "F", "CMYK", "RGB16", "YCbCr", "LAB", "I;16B"])
        buf = io.BytesIO()
        if mode == "RGB16":
            data = png_encode(fr.color.astype(np.uint16) * 257)
        elif mode == "I;16":
            data = png_encode(fr.color[:, :, 0].astype(np.uint16) * 257)
        else:
            img = Image.fromarray(fr.color)
            try:
                conv = img.convert(mode) if mode not in ("I;16B",) else Image.fromarray(fr.color[:, :, 0].astype(">u2"))
                target = {"CMYK": "JPEG", "YCbCr": "JPEG", "LAB": "TIFF", "F": "TIFF", "I;16B": "TIFF"}.get(
                    mode, "PNG" if fmt == "png" else "JPEG"
                )
                if target == "JPEG" and mode in ("LA", "RGBA", "P", "I", "F"):
                    target = "PNG"
                conv.save(buf, format=target)
                data = buf.getvalue()
            except Exception as exc:  # noqa: BLE001  (a mode PIL cannot write that way: keep the valid colour)
                ctx.note(f"(PIL could not write {mode}: {type(exc).__name__})")
        ctx.note(f"colour image in mode {mode}")
    elif mutation == "empty":
        data = b""
        ctx.note("empty colour file")
    elif mutation == "directory":
        cpath.mkdir()
        data = None
        ctx.note("the colour path is a directory")
    elif mutation == "fifo":
        os.mkfifo(cpath)
        data = None
        ctx.tag("fifo", "fifo-input")
        ctx.note("the colour path is a FIFO (nobody writes it)")
    elif mutation == "symlink_loop":
        cpath.symlink_to(cpath.name)
        data = None
        ctx.note("the colour path is a symlink to itself")
    elif mutation == "dangling":
        cpath.symlink_to("nowhere.png")
        data = None
        ctx.note("the colour path is a dangling symlink")
    elif mutation == "wrong_content":
        what = ctx.choice(["depth_png", "mcap", "text", "tiff_float", "npy"])
        data = {
            "depth_png": ctx.mat.depth_bytes("png", size),
            "mcap": ctx.mat.mcap_bytes(),
            "text": b"colour\n",
            "tiff_float": ctx.mat.depth_bytes("tiff", size),
            "npy": ctx.mat.depth_bytes("npy_f32", size),
        }[what]
        ctx.note(f"{what} given as the colour image")
    elif mutation == "bomb_idat":
        w, h = ctx.choice([(5000, 5000), (4096, 4096)])
        data = png_bomb(w, h, bitdepth=8, colortype=2)
        ctx.tag("bomb")
        ctx.note(f"colour png whose IDAT inflates to {w}x{h} RGB zeros")
    elif mutation == "bomb_text":
        chunks = png_chunks(ctx.mat.color_bytes("png", size))
        chunks.insert(1, (b"zTXt", b"Comment\x00\x00" + zlib.compress(b"\x00" * 2**26, 9)))
        data = png_build(chunks)
        ctx.tag("bomb")
        ctx.note("colour png with a zTXt chunk inflating to 64 MB")
    elif mutation == "garbage_pixels":
        noise = ctx.np.integers(0, 256, fr.color.shape, dtype=np.uint8)
        choice = ctx.choice(["noise", "black", "white", "one_colour"])
        pixels = {
            "noise": noise,
            "black": np.zeros_like(noise),
            "white": np.full_like(noise, 255),
            "one_colour": np.broadcast_to(noise[0, 0], noise.shape).copy(),
        }[choice]
        data = png_encode(pixels)
        ctx.note(f"colour of {choice} pixels")
    if data is not None and not cpath.exists() and not cpath.is_symlink():
        cpath.write_bytes(data)
    if by_flag:
        flags += ["--color", str(cpath)]
        ctx.note("given with --color")
    else:
        ctx.note(f"paired by the naming rule as {cpath.name!r} beside {depth.name!r} and camera_params.json")
    if ctx.case.heavy:
        ctx.run("segment", depth, *flags, "--json")
        ctx.case.timeout_s = HEAVY_TIMEOUT_S
    else:
        _command_for_image(ctx, depth, flags)


# --- intrinsics ---------------------------------------------------------------------------


def _set_path(data: Any, path: Sequence[Any], value: Any) -> None:
    for p in path[:-1]:
        data = data[p]
    data[path[-1]] = value


def _leaf_paths(data: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    out: list[tuple[Any, ...]] = []
    if isinstance(data, dict):
        for k, v in data.items():
            out.append(prefix + (k,))
            out += _leaf_paths(v, prefix + (k,))
    elif isinstance(data, list):
        for i, v in enumerate(data):
            out.append(prefix + (i,))
            out += _leaf_paths(v, prefix + (i,))
    return out


def gen_intrinsics(ctx: Ctx) -> None:
    """Intrinsics files (ROS YAML, CameraInfo, Open3D, camera_params.json) and strings, damaged."""
    size = PLAN if ctx.case.heavy else SMALL
    fr = ctx.mat.frames[size]
    depth = ctx.write("f_depth.png", ctx.mat.depth_bytes("png", size))
    ctx.write("f_color.png", ctx.mat.color_bytes("png", size))
    flags: list[str] = []
    how = ctx.pick({"file_beside": 0.45, "file_flag": 0.25, "string": 0.22, "several": 0.08})
    ctx.tag(how)
    if how == "string":
        fx, fy, cx, cy = fr.k
        parts = [repr(fx), repr(fy), repr(cx), repr(cy)]
        m = ctx.pick({"value": 0.6, "count": 0.15, "odd": 0.25})
        if m == "value":
            for _ in range(ctx.choice([1, 1, 2, 4])):
                parts[ctx.rng.randrange(4)] = odd_number(ctx)[0]
            text = ctx.choice([" ", ",", ", ", "\t", " ,"]).join(parts)
        elif m == "count":
            text = " ".join(parts[: ctx.choice([0, 1, 2, 3])] + ([] if ctx.rng.random() < 0.5 else parts + ["1"]))
        else:
            text = ctx.choice(
                [
                    "",
                    " ",
                    "fx fy cx cy",
                    "1,,2,3,4",
                    "1 2 3 4 5",
                    "١ ٢ ٣ ٤",
                    "1_0 1_0 5 5",
                    "0x1p4 16 8 8",
                    "nan",
                    "missing_file.yaml",
                    "-",
                    "/dev/null",
                    "~",
                    "1e5 1e5 1e5 1e5",
                    "5 5 -1e308 1e308",
                    "1e-300 1e-300 31.5 23.5",
                    "3e38 3e38 3e38 3e38",
                    "52.5 52.5 1e30 1e30",
                ]
            )
        ctx.note(f"--intrinsics {text!r}")
        flags = ["--intrinsics", text]
        ctx.case.allowed = DOCUMENTED
    else:
        layouts = intrinsics_files(fr.k, size)
        layout = ctx.choice(list(layouts))
        fname, mapping = layouts[layout]
        mapping = json.loads(json.dumps(mapping))
        if how == "file_flag":
            fname = ctx.choice([fname, "calib" + Path(fname).suffix, "calib.txt", "k"])
        if layout in ("camera_info", "ros_yaml") and ctx.rng.random() < 0.3:
            fname = ctx.choice(["camera_info.yml", "camera.yaml", "camera_info.json"])
        m = ctx.pick(
            {
                "value": 0.35,
                "missing_key": 0.08,
                "type": 0.1,
                "distortion": 0.12,
                "roi_binning": 0.08,
                "text_damage": 0.12,
                "whole": 0.1,
                "size": 0.08,
                "yaml_tricks": 0.07,
            }
        )
        ctx.tag(m, layout)
        text: str | bytes
        if m == "value":
            paths = [
                p
                for p in _leaf_paths(mapping)
                if not isinstance(p[-1], str) or p[-1] not in ("rows", "cols", "camera_name")
            ]
            for _ in range(ctx.choice([1, 1, 2])):
                p = ctx.choice(paths)
                tv, v = odd_number(ctx)
                try:
                    _set_path(mapping, p, v)
                except (TypeError, KeyError, IndexError):  # a parent already made a scalar by the first change
                    continue
                ctx.note(f"{fname} ({layout}) {'.'.join(map(str, p))} = {tv[:40]}")
                paths = [
                    q
                    for q in _leaf_paths(mapping)
                    if not isinstance(q[-1], str) or q[-1] not in ("rows", "cols", "camera_name")
                ]
            text = _dump_any(fname, mapping, ctx)
        elif m == "missing_key":
            key = ctx.choice(list(mapping))
            del mapping[key]
            ctx.note(f"{fname} ({layout}) without {key!r}")
            text = dump_mapping(fname, mapping)
        elif m == "type":
            p = ctx.choice(_leaf_paths(mapping))
            v = ctx.choice([None, "abc", [], {}, [[1, 2]], True, {"data": [1]}, "[1,2,3]", list(range(20)), [None] * 9])
            _set_path(mapping, p, v)
            ctx.note(f"{fname} ({layout}) {'.'.join(map(str, p))} = {json.dumps(v)[:40]}")
            text = dump_mapping(fname, mapping)
        elif m == "distortion":
            model = ctx.choice(
                ["plumb_bob", "rational_polynomial", "equidistant", "", "none", "fisheye", "PLUMB_BOB", 5, None]
            )
            n = ctx.choice([0, 1, 4, 5, 8, 12, 14])
            coeffs = [
                float(ctx.choice([0.0, 0.1, -0.4, 1e-3, 5.0, -50.0, 1e10, float("nan"), float("inf")]))
                for _ in range(n)
            ]
            if layout == "ros_yaml":
                mapping["distortion_model"] = model
                mapping["distortion_coefficients"] = {"rows": 1, "cols": n, "data": coeffs}
            elif layout == "camera_info":
                mapping["distortion_model"] = model
                mapping["d"] = coeffs
            else:  # layouts without distortion: put it in the CameraInfo form instead
                fname, mapping = layouts["camera_info"]
                mapping = json.loads(json.dumps(mapping))
                mapping["distortion_model"], mapping["d"] = model, coeffs
            ctx.note(f"{fname} distortion {model!r} with {coeffs}")
            text = _dump_any(fname, mapping, ctx)
        elif m == "roi_binning":
            fname, mapping = layouts["camera_info"]
            mapping = json.loads(json.dumps(mapping))
            for key in ctx.rng.sample(["binning_x", "binning_y", "roi"], ctx.choice([1, 2])):
                if key == "roi":
                    roi = {
                        k: ctx.choice([0, 1, 8, 16, 32, 48, 64, 1000, -1, 2**32])
                        for k in ("x_offset", "y_offset", "height", "width")
                    }
                    roi["do_rectify"] = ctx.choice([True, False])
                    mapping["roi"] = ctx.choice([roi, list(roi.values())[:4], "roi", [1, 2]])
                else:
                    mapping[key] = ctx.choice([0, 1, 2, 3, 4, 64, 65, 10**6, -2, 0.5])
            ctx.note(
                f"{fname} binning/roi: binning {mapping['binning_x']}x{mapping['binning_y']}, roi {mapping['roi']}"
            )
            text = dump_mapping(fname, mapping)
        elif m == "text_damage":
            raw = dump_mapping(fname, mapping).encode()
            sub = ctx.choice(["truncate", "flip", "latin1", "bom", "nul"])
            if sub == "truncate":
                raw, off = truncate(raw, ctx.rng)
                ctx.note(f"{fname} ({layout}) truncated at {off}")
            elif sub == "flip":
                raw, h = flip_bytes(raw, ctx.rng, ctx.choice([1, 2, 5]))
                ctx.note(f"{fname} ({layout}): {h}")
            elif sub == "latin1":
                raw = raw.replace(b"cam", "c\xe4m".encode("latin-1")) + b"\n# \xff\xfe\n"
                ctx.note(f"{fname} ({layout}) with latin-1 bytes")
            elif sub == "bom":
                raw = b"\xef\xbb\xbf" + raw
                ctx.note(f"{fname} ({layout}) with a UTF-8 BOM")
            else:
                raw = raw[: len(raw) // 2] + b"\x00" + raw[len(raw) // 2 :]
                ctx.note(f"{fname} ({layout}) with a NUL byte")
            text = raw
        elif m == "whole":
            text = ctx.choice(
                [
                    "",
                    "   \n",
                    "[]",
                    "[1, 2, 3]",
                    "5",
                    "null",
                    "~",
                    "'just a string'",
                    "{}",
                    '{"k": 1}',
                    "- a\n- b\n",
                    "\x00\x01\x02",
                    "{" * 3000,
                    "[" * 3000,
                    "a: &a [1,2]\nb: [*a, *a, *a]\nk: [*a, *a]\n",
                    "!!python/object/apply:os.system ['echo pwned']\n",
                    "fx: 1\n" * 3,
                    "%YAML 9.9\n---\nfx: 1\n",
                ]
            )
            ctx.note(f"{fname} holding {text[:40]!r}")
        elif m == "size":
            w, h = ctx.choice(
                [(size[0] * 2, size[1] * 2), (size[0] + 1, size[1]), (size[1], size[0]), (1, 1), (0, 0), (10**9, 10**9)]
            )
            for wk, hk in (("image_width", "image_height"), ("width", "height"), ("img_width", "img_height")):
                if wk in mapping:
                    mapping[wk], mapping[hk] = w, h
            ctx.note(f"{fname} ({layout}) for a {w}x{h} image, the depth is {size[0]}x{size[1]}")
            text = dump_mapping(fname, mapping)
        else:  # yaml_tricks: valid YAML that is not what JSON/YAML readers expect
            y = ctx.choice(
                [
                    "image_width: 64\nimage_height: 48\ncamera_matrix:\n  data: !!binary AAAA\n",
                    "width: 64\nheight: 48\nk: [52.5, 0, 31.5, 0, 52.5, 23.5, 0, 0, 1]\nk: [0, 0, 0, 0, 0, 0, 0, 0, 0]\n",
                    "width: 64\nheight: 48\nK: !!set {1, 2}\n",
                    "width: 0x40\nheight: 0o60\nk: [52.5, 0, 31.5, 0, 52.5, 23.5, 0, 0, 1]\n",
                    "width: 64\nheight: 48\nk: [.nan, 0, 31.5, 0, 52.5, 23.5, 0, 0, 1]\n",
                    "width: 64\nheight: 48\nk: [52.5, 0, 31.5, 0, 52.5, 23.5, 0, 0, 1]\nroi: {x_offset: 2012-01-01}\n",
                    "fx: 52.5\nfy: 52.5\nx_offset: 31.5\ny_offset: 23.5\nimg_width: 64\nimg_height: 48\n" * 1
                    + "? [a, b]\n: c\n",
                    '{"fx": 52.5, "fy": 52.5, "x_offset": 31.5, "y_offset": 23.5, "img_width": 64, "img_height": 48,}',
                    '{"fx": NaN, "fy": Infinity, "x_offset": 31.5, "y_offset": 23.5, "img_width": 64, "img_height": 48}',
                    '{"fx": 52.5, "fy": 52.5, "x_offset": 31.5, "y_offset": 23.5, "img_width": 64, "img_height": 4'
                    + "8" * 5000
                    + "}",
                ]
            )
            fname = "camera_info.yaml" if not y.startswith("{") else "camera_params.json"
            text = y
            ctx.note(f"{fname}: {y[:60]!r}")
        ipath = ctx.dir / fname
        if how in ("file_beside", "several") and fname not in (
            "camera_info.yaml",
            "camera_info.yml",
            "camera_params.json",
            "intrinsics.json",
            "camera.yaml",
            "camera.json",
        ):
            fname = "camera_info.yaml"
            ipath = ctx.dir / fname
        if m == "whole" and ctx.rng.random() < 0.15:
            ipath.mkdir()
            ctx.note(f"{fname} is a directory")
        elif m == "whole" and ctx.rng.random() < 0.1:
            os.mkfifo(ipath)
            ctx.tag("fifo", "fifo-input")
            ctx.note(f"{fname} is a FIFO")
        else:
            ipath.write_bytes(text if isinstance(text, bytes) else text.encode("utf-8", "surrogatepass"))
        if how == "file_flag":
            flags = ["--intrinsics", str(ipath)]
        if how == "several":
            other = ctx.choice([n for n in ("camera_params.json", "intrinsics.json", "camera.yaml") if n != fname])
            lay = {"camera_params.json": "uois", "intrinsics.json": "open3d", "camera.yaml": "ros_yaml"}[other]
            om = json.loads(json.dumps(layouts[lay][1]))
            if ctx.rng.random() < 0.5:  # disagreeing by a hair
                for k in ("fx", "image_width"):
                    if k in om:
                        om[k] = om[k] + 1e-9 if isinstance(om[k], float) else om[k]
            ctx.write(other, dump_mapping(other, om))
            ctx.note(f"and {other} beside it")
    if ctx.case.heavy:
        ctx.run("segment", depth, *flags, "--json")
        ctx.case.timeout_s = HEAVY_TIMEOUT_S
    else:
        _command_for_image(ctx, depth, flags)


def _dump_any(fname: str, mapping: Any, ctx: Ctx) -> str:
    """YAML or JSON of a mapping holding odd values (NaN, huge integers) the way a hand-edited file would."""
    if fname.endswith(".json"):
        return json.dumps(mapping, allow_nan=True, default=str)
    import yaml

    try:
        return yaml.safe_dump(mapping, sort_keys=False)
    except Exception:  # noqa: BLE001  (what YAML cannot say, JSON says)
        return json.dumps(mapping, allow_nan=True, default=str)


# --- image logs ---------------------------------------------------------------------------


def gen_log(ctx: Ctx) -> None:
    """MCAP logs of depth Image + CameraInfo (damaged messages or bytes), the shared RealSense
    recording truncated, rosbag2 folders with damaged metadata, ROS 1 bags cut short."""
    sub = ctx.pick({"mcap_msg": 0.42, "mcap_bytes": 0.25, "shared": 0.08, "rosbag2": 0.17, "ros1": 0.08})
    ctx.tag(sub)
    frame_flag = ["--frame", str(ctx.choice([0, 0, 0, 1, 2, 5]))]
    if sub == "mcap_msg":
        path = ctx.dir / "log.mcap"
        _mcap_messages(ctx, path)
    elif sub == "mcap_bytes":
        path = ctx.dir / "log.mcap"
        layout = ctx.choice(["zstd", "plain", "plain"])
        data = whole = ctx.mat.mcap_bytes(layout)
        if ctx.rng.random() < 0.6:
            data, off = truncate(data, ctx.rng)
            n = complete_depth_frames(data)
            ctx.tag("truncate", "mcap")
            ctx.note(
                f"3-frame 64x48 depth MCAP ({layout} chunks) truncated at {off} of {len(whole)} ({n} complete depth frames before)"
            )
            _truncation_oracle(ctx, n, frame_flag)
        else:
            data, how = flip_bytes(data, ctx.rng, ctx.choice([1, 2, 4, 16]), start=8)
            ctx.note(f"3-frame 64x48 depth MCAP ({layout} chunks): {how}")
        path.write_bytes(data)
    elif sub == "shared":
        if not SHARED_MCAP.is_file():
            ctx.case.runs = []
            ctx.note("SKIPPED: the shared RealSense MCAP is not here")
            return
        full = SHARED_MCAP.read_bytes()
        data, off = truncate(full, ctx.rng)
        n = complete_depth_frames(data)
        path = ctx.write("realsense.mcap", data)
        ctx.tag("truncate", "mcap")
        ctx.note(
            f"the shared uois_realsense_ros2.mcap truncated at {off} of {len(full)} ({n} complete depth frames before)"
        )
        _truncation_oracle(ctx, n, frame_flag, segment_share=0.15)
    elif sub == "rosbag2":
        path = ctx.dir / "bag2"
        shutil.copytree(ctx.mat.rosbag2_dir(), path)
        _rosbag2_damage(ctx, path)
    else:
        data = ctx.mat.ros1_bytes()
        if ctx.rng.random() < 0.6:
            data, off = truncate(data, ctx.rng)
            ctx.tag("truncate")
            ctx.note(f"2-frame ROS 1 bag truncated at {off} of {len(ctx.mat.ros1_bytes())}")
        else:
            data, how = flip_bytes(data, ctx.rng, ctx.choice([1, 4, 16]), start=13)
            ctx.note(f"2-frame ROS 1 bag: {how}")
        path = ctx.write("log.bag", data)
    if ctx.case.runs:
        return
    weights = {"info": 0.45, "segment": 0.48, "replay": 0.07}
    if "metadata-type" in ctx.case.tags:
        weights = {"info": 0.2, "segment": 0.5, "replay": 0.3}
    cmd = ctx.pick(weights)
    if "metadata-type" in ctx.case.tags and cmd != "info":
        # the first declared Image (the depth topic) or the camera info is not what its
        # messages are: reading frames from it is refused (3), or stops at it (9)
        ctx.case.expect = frozenset({3, 9})
    if cmd == "replay":
        ctx.run("replay", path, "--json")
    elif cmd == "info":
        ctx.run("info", path, *(["--json"] if ctx.rng.random() < 0.5 else []))
    else:
        ctx.run("segment", path, *frame_flag)


def _truncation_oracle(ctx: Ctx, complete: int, frame_flag: list[str], segment_share: float = 0.4) -> None:
    """What a truncated log must give: `info` 9 once a complete frame precedes the damage;
    a single frame that is whole is read (its own result, or 9), one beyond the damage 3 or 9."""
    cmd = ctx.pick({"info": 1.0 - segment_share, "segment": segment_share})
    path = ctx.dir / ("realsense.mcap" if "shared" in ctx.case.tags else "log.mcap")
    if cmd == "info":
        ctx.run("info", path, *(["--json"] if ctx.rng.random() < 0.5 else []))
        ctx.case.expect = frozenset({9}) if complete >= 1 else frozenset({3, 9})
    else:
        k = int(frame_flag[1])
        ctx.run("segment", path, "--frame", k)
        ctx.case.expect = frozenset({0, 4, 9}) if k < complete else frozenset({3, 9})
        if "shared" in ctx.case.tags:
            ctx.case.timeout_s = HEAVY_TIMEOUT_S


def _mcap_messages(ctx: Ctx, path: Path) -> None:
    from helpers.rgbd_logs import image_msg

    fr = ctx.mat.frames[SMALL]
    w, h = fr.size
    frames = [default_log_frame(fr, k) for k in range(ctx.choice([1, 2, 3]))]
    target = ctx.rng.randrange(len(frames))
    f = frames[target]
    m = ctx.pick(
        {
            "encoding": 0.14,
            "step": 0.12,
            "dims": 0.12,
            "data": 0.08,
            "info_k": 0.12,
            "info_d": 0.08,
            "info_size": 0.07,
            "no_info": 0.05,
            "colour": 0.1,
            "values": 0.06,
            "order": 0.04,
            "topic": 0.02,
        }
    )
    ctx.tag(m)
    depth = f["depth"]
    if m == "encoding":
        enc = ctx.choice(
            [
                "mono16",
                "32FC1",
                "8UC1",
                "mono8",
                "rgb8",
                "16SC1",
                "32FC2",
                "64FC1",
                "",
                "garbage",
                "16UC1; compressedDepth",
                "compressedDepth",
                "bgra8",
                "32SC1",
                "16UC3",
                "8UC4",
                "bayer_rggb16",
            ]
        )
        depth["encoding"] = enc
        if enc == "32FC1":
            raw = (fr.depth_mm.astype(np.float32) / 1000).tobytes()
            depth["data"], depth["step"] = raw, w * 4
        ctx.note(f"frame {target}: depth encoding {enc!r}")
    elif m == "step":
        depth["step"] = ctx.choice([0, 1, w, w * 2 - 1, w * 2 + 2, w * 4, 2**31, 2**32 - 1, w * 2 * h])
        ctx.note(f"frame {target}: depth step {depth['step']} (width {w}, 16UC1)")
    elif m == "dims":
        depth["height"], depth["width"] = ctx.choice(
            [
                (0, w),
                (h, 0),
                (0, 0),
                (h * 2, w),
                (h, w * 2),
                (1, w * h),
                (h // 2, w * 2),
                (2**31, w),
                (2**32 - 1, 2**32 - 1),
                (100000, 100000),
            ]
        )
        if ctx.rng.random() < 0.5:
            depth["step"] = depth["width"] * 2 % 2**32
        ctx.note(f"frame {target}: depth {depth['width']}x{depth['height']} step {depth['step']} over {w}x{h} data")
        ctx.tag("bomb" if depth["height"] * depth["width"] > 2**25 else "dims")
    elif m == "data":
        raw = depth["data"]
        depth["data"] = ctx.choice([b"", raw[:-1], raw[: len(raw) // 2], raw + b"\x00", raw * 2, b"\x00" * 7])
        ctx.note(f"frame {target}: depth data of {len(depth['data'])} bytes for {len(raw)}")
    elif m == "info_k":
        k = list(f["info"]["k"])
        which = ctx.choice([[0], [4], [2], [5], [0, 4], [8], [6], list(range(9))])
        tv, v = ctx.choice([(t, x) for t, x in SPECIAL_NUMBERS if isinstance(x, float) or abs(x) < 2**60])
        for i in which:
            k[i] = float(v)
        f["info"]["k"] = k
        ctx.note(f"frame {target}: camera info k[{which}] = {tv}")
    elif m == "info_d":
        model = ctx.choice(["plumb_bob", "rational_polynomial", "equidistant", "", "weird"])
        d = [
            ctx.choice([0.0, 0.1, -0.3, 5.0, 1e12, float("nan"), float("inf")])
            for _ in range(ctx.choice([0, 3, 5, 8, 14]))
        ]
        f["info"]["distortion_model"], f["info"]["d"] = model, d
        ctx.note(f"frame {target}: camera info distortion {model!r} {d}")
    elif m == "info_size":
        f["info"]["width"], f["info"]["height"] = ctx.choice([(w * 2, h * 2), (0, 0), (w + 1, h), (2**32 - 1, 1)])
        f["info"]["binning_x"] = ctx.choice([0, 0, 2, 1000])
        ctx.note(
            f"frame {target}: camera info {f['info']['width']}x{f['info']['height']} binning {f['info']['binning_x']}"
        )
    elif m == "no_info":
        for fr_ in frames:
            fr_["info"] = None
        ctx.note("no camera info at all")
    elif m == "colour":
        c = ctx.choice(["size", "frame_id", "empty_frame_id", "encoding", "data", "step"])
        col = f["color"]
        if c == "size":
            col.update(image_msg(fr.color[: h // 2, : w // 2].copy(), "rgb8", f["t"], col["header"]["frame_id"]))
        elif c == "frame_id":
            col["header"]["frame_id"] = "another_optical_frame"
        elif c == "empty_frame_id":
            col["header"]["frame_id"] = ""
            depth["header"]["frame_id"] = ""
        elif c == "encoding":
            col["encoding"] = ctx.choice(["bgr8", "mono8", "16UC1", "yuv422", "", "rgba8", "jpeg"])
        elif c == "data":
            col["data"] = col["data"][: ctx.rng.randrange(len(col["data"]))]
        else:
            col["step"] = ctx.choice([0, 1, w * 3 + 1, 2**32 - 1])
        ctx.note(f"frame {target}: colour image {c} changed")
    elif m == "values":
        v = ctx.choice(["zero", "max", "nan32", "neg32", "inf32"])
        if v in ("zero", "max"):
            depth["data"] = (np.zeros_like(fr.depth_mm) if v == "zero" else np.full_like(fr.depth_mm, 65535)).tobytes()
        else:
            a = fr.depth_mm.astype(np.float32) / 1000
            a[ctx.np.random(a.shape) < 0.5] = {"nan32": np.nan, "neg32": -1.0, "inf32": np.inf}[v]
            depth["encoding"], depth["data"], depth["step"] = "32FC1", a.tobytes(), w * 4
        ctx.note(f"frame {target}: depth values {v}")
    elif m == "order":
        for fr_ in frames:
            fr_["t"] = ctx.choice([0, 1, 2**63, 1_700_000_000_000_000_000])
        ctx.note(f"time stamps {[fr_['t'] for fr_ in frames]}")
    else:
        ctx.note("depth topic named without 'depth'")
    write_image_mcap(path, frames, depth_topic="/camera/aligned/image_raw" if m == "topic" else None)


def _rosbag2_damage(ctx: Ctx, bag: Path) -> None:
    meta = bag / "metadata.yaml"
    text = meta.read_text()
    m = ctx.pick({"type": 0.4, "yaml": 0.18, "fields": 0.17, "storage": 0.13, "missing": 0.07, "dir": 0.05})
    ctx.tag(m)
    if m == "type":
        ctx.tag("metadata-type")
        topics = re.findall(r"type: (\S+)", text)
        old = (
            "sensor_msgs/msg/Image"
            if ctx.rng.random() < 0.6
            else ctx.choice(sorted(set(topics)) or ["sensor_msgs/msg/Image"])
        )
        new = ctx.choice(
            ["sensor_msgs/msg/PointCloud2"] * 3
            + [
                "sensor_msgs/msg/CameraInfo",
                "std_msgs/msg/String",
                "sensor_msgs/msg/CompressedImage",
                "garbage/msg/Nope",
                "sensor_msgs/msg/Image",
                "",
                "std_msgs/msg/Float32",
            ]
        )
        if new == old:
            new = "sensor_msgs/msg/PointCloud2"
        which = ctx.choice(["first", "all"])
        text = text.replace(f"type: {old}", f"type: {new}", 1 if which == "first" else -1)
        ctx.note(f"rosbag2 metadata.yaml: {which} 'type: {old}' -> '{new}' (the storage file still says {old})")
    elif m == "yaml":
        raw = text.encode()
        if ctx.rng.random() < 0.5:
            raw, off = truncate(raw, ctx.rng)
            ctx.note(f"rosbag2 metadata.yaml truncated at {off}")
        else:
            raw, how = flip_bytes(raw, ctx.rng, ctx.choice([1, 3]))
            ctx.note(f"rosbag2 metadata.yaml: {how}")
        text = raw.decode("utf-8", "replace")
    elif m == "fields":
        key = ctx.choice(
            [
                "message_count",
                "version",
                "nanoseconds",
                "relative_file_paths",
                "serialization_format",
                "offered_qos_profiles",
                "topics_with_message_count",
                "name",
            ]
        )
        val = ctx.choice(["-1", "999999999999", "abc", "[]", "{}", "", "null", "1e400", "[nope.db3]"])
        text, n = re.subn(rf"^(\s*-?\s*{key}:)(.*)$", rf"\g<1> {val}", text, count=1, flags=re.MULTILINE)
        ctx.note(f"rosbag2 metadata.yaml: {key}: {val} ({n} replaced)")
    elif m == "storage":
        dbs = sorted(bag.glob("*.db3")) + sorted(bag.glob("*.mcap"))
        if dbs:
            db = dbs[0]
            raw = db.read_bytes()
            if ctx.rng.random() < 0.6:
                raw, off = truncate(raw, ctx.rng)
                ctx.note(f"rosbag2 storage {db.name} truncated at {off}")
            else:
                raw, how = flip_bytes(raw, ctx.rng, ctx.choice([1, 8, 64]), start=100)
                ctx.note(f"rosbag2 storage {db.name}: {how}")
            db.write_bytes(raw)
    elif m == "missing":
        for db in bag.glob("*.db3"):
            db.unlink()
        ctx.note("rosbag2 folder without its storage file")
    else:
        meta.unlink()
        meta.mkdir()
        ctx.note("rosbag2 metadata.yaml is a directory")
        return
    meta.write_text(text)


# --- URDFs --------------------------------------------------------------------------------


PANDA_LINKS = [f"panda_link{k}" for k in range(9)] + ["panda_hand", "panda_tcp"]


def _binary_stl(triangles: int = 4) -> bytes:
    tri = np.array([[0, 0, 0], [0.05, 0, 0], [0, 0.05, 0]], np.float32)
    body = b"".join(struct.pack("<3f", 0, 0, 1) + (tri + 0.01 * k).tobytes() + b"\x00\x00" for k in range(triangles))
    return b"\x00" * 80 + struct.pack("<I", triangles) + body


def gen_urdf(ctx: Ctx) -> None:
    """`[robot] urdf` = a damaged Panda description (XML, limits, joints, frames, meshes)."""
    text = ctx.mat.panda_urdf()
    sets: list[str] = []
    urdf = ctx.dir / "arm.urdf"
    m = ctx.pick(
        {
            "xml": 0.16,
            "limits": 0.18,
            "joint_type": 0.1,
            "axis_origin": 0.12,
            "structure": 0.1,
            "geometry": 0.08,
            "mesh": 0.1,
            "frames": 0.1,
            "path": 0.06,
        }
    )
    ctx.tag(m)
    joints = re.findall(r'<joint name="(\w+)" type="revolute"', text)
    if m == "xml":
        sub = ctx.choice(
            ["truncate", "flip", "unclosed", "root", "garbage", "empty", "binary", "entities", "no_joints", "bom"]
        )
        if sub == "truncate":
            raw, off = truncate(text.encode(), ctx.rng)
            text = raw.decode("utf-8", "replace")
            ctx.note(f"URDF truncated at {off}")
        elif sub == "flip":
            raw, how = flip_bytes(text.encode(), ctx.rng, ctx.choice([1, 2, 8]))
            text = raw.decode("latin-1")
            ctx.note(f"URDF: {how}")
        elif sub == "unclosed":
            text = text.replace("</joint>", "", 1)
            ctx.note("URDF with an unclosed <joint>")
        elif sub == "root":
            text = text.replace("<robot ", "<robt ", 1).replace("</robot>", "</robt>")
            ctx.note("URDF whose root is <robt>")
        elif sub == "garbage":
            text = text.replace("<link", "<<link", 1)
            ctx.note("URDF with '<<link'")
        elif sub == "empty":
            text = ctx.choice(["", "<robot/>", "<robot name='x'></robot>", "<?xml version='1.0'?>"])
            ctx.note(f"URDF {text!r}")
        elif sub == "binary":
            text = "\x00\x01\x89PNG garbage"
            ctx.note("URDF of binary junk")
        elif sub == "entities":
            text = (
                '<?xml version="1.0"?>\n<!DOCTYPE r [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">'
                '<!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;"><!ENTITY d "&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;">]>\n'
                + text.split("?>", 1)[1].replace('name="clear_panda"', 'name="&d;"')
            )
            ctx.note("URDF with nested entities in the robot's name")
        elif sub == "no_joints":
            text = re.sub(r"<joint .*?</joint>", "", text, flags=re.DOTALL)
            ctx.note("URDF without joints")
        else:
            text = "\ufeff" + text
            ctx.note("URDF with a BOM")
    elif m == "limits":
        j = ctx.choice(joints)
        sub = ctx.choice(["swap", "nan", "inf", "text", "equal", "huge", "missing", "empty", "effort_velocity"])
        block = re.search(rf'<joint name="{j}".*?</joint>', text, flags=re.DOTALL)
        assert block
        b = block.group(0)
        lim = re.search(r'lower="([^"]*)" upper="([^"]*)"', b)
        if lim and sub == "swap":
            lo, hi = float(lim.group(1)), float(lim.group(2))
            nb = b.replace(lim.group(0), f'lower="{hi + ctx.choice([0.0, 0.5])}" upper="{lo}"')
            ctx.tag("limit-lower>upper")
            ctx.note(f"{j}: lower {hi} > upper {lo}")
        elif lim and sub in ("nan", "inf", "text", "huge", "empty"):
            v = {
                "nan": "nan",
                "inf": ctx.choice(["inf", "-inf"]),
                "text": "abc",
                "huge": ctx.choice(["1e308", "-1e308", "1e6"]),
                "empty": "",
            }[sub]
            side = ctx.choice(["lower", "upper"])
            nb = re.sub(rf'{side}="[^"]*"', f'{side}="{v}"', b, count=1)
            ctx.note(f"{j}: {side}={v!r}")
            with contextlib.suppress(ValueError):
                lo, hi = float(lim.group(1)), float(lim.group(2))
                lo, hi = (float(v), hi) if side == "lower" else (lo, float(v))
                if lo > hi:
                    ctx.tag("limit-lower>upper")
        elif lim and sub == "equal":
            nb = b.replace(lim.group(0), f'lower="{lim.group(1)}" upper="{lim.group(1)}"')
            ctx.note(f"{j}: lower == upper == {lim.group(1)}")
        elif sub == "missing":
            nb = re.sub(r"<limit[^>]*/>", "", b)
            ctx.note(f"{j}: no <limit>")
        else:
            nb = re.sub(r'effort="[^"]*"', f'effort="{ctx.choice(["-1", "nan", "0"])}"', b)
            nb = re.sub(r'velocity="[^"]*"', f'velocity="{ctx.choice(["-1", "nan", "0"])}"', nb)
            ctx.note(f"{j}: odd effort/velocity")
        text = text.replace(b, nb)
    elif m == "joint_type":
        chosen = ctx.rng.sample(joints, ctx.choice([1, 1, 2, 3]))
        new = ctx.choice(["fixed", "continuous", "prismatic", "floating", "planar", "banana", ""])
        for j in chosen:
            text = text.replace(f'<joint name="{j}" type="revolute"', f'<joint name="{j}" type="{new}"')
        if new in ("fixed", "prismatic", "floating", "planar") and len(joints) - len(chosen) < 6:
            ctx.case.expect = frozenset({3})  # fewer than six revolute joints: refused before any frame
        ctx.note(f"joints {chosen} made {new!r}")
    elif m == "axis_origin":
        j = ctx.choice(joints)
        block = re.search(rf'<joint name="{j}".*?</joint>', text, flags=re.DOTALL)
        assert block
        b = block.group(0)
        what = ctx.choice(["axis", "xyz", "rpy"])
        v = ctx.choice(
            ["0 0 0", "nan 0 1", "1 0", "", "1e308 0 0", "inf 0 0", "0 0 -1", "a b c", "1 1 1 1", "0 0 1e-300"]
        )
        if what == "axis":
            nb = (
                re.sub(r'<axis xyz="[^"]*"', f'<axis xyz="{v}"', b)
                if "<axis" in b
                else b.replace("</joint>", f'<axis xyz="{v}"/></joint>')
            )
        else:
            nb = re.sub(rf'{what}="[^"]*"', f'{what}="{v}"', b, count=1)
        text = text.replace(b, nb)
        ctx.note(f"{j}: {what}={v!r}")
    elif m == "structure":
        sub = ctx.choice(
            ["child_missing", "parent_missing", "cycle", "dup_link", "dup_joint", "drop_link", "two_roots"]
        )
        if sub == "child_missing":
            text = text.replace('<child link="panda_link3"/>', '<child link="nowhere"/>', 1)
        elif sub == "parent_missing":
            text = text.replace('<parent link="panda_link4"/>', '<parent link="nowhere"/>', 1)
        elif sub == "cycle":
            text = text.replace(
                "</robot>",
                '<joint name="loop" type="revolute"><parent link="panda_link7"/><child link="panda_link0"/>'
                '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>',
            )
        elif sub == "dup_link":
            text = text.replace('<link name="panda_link5">', '<link name="panda_link4">', 1)
        elif sub == "dup_joint":
            text = text.replace('<joint name="panda_joint5"', '<joint name="panda_joint4"', 1)
        elif sub == "drop_link":
            text = re.sub(r'<link name="panda_link6">.*?</link>', "", text, count=1, flags=re.DOTALL)
        else:
            text = text.replace("</robot>", '<link name="floating_root"/></robot>')
        ctx.note(f"URDF structure: {sub}")
    elif m == "geometry":
        sub = ctx.choice(
            [
                '<cylinder radius="0" length="0"/>',
                '<cylinder radius="-1" length="0.1"/>',
                '<cylinder radius="nan" length="0.1"/>',
                '<sphere radius="inf"/>',
                "<sphere/>",
                '<box size="0 0 0"/>',
                '<box size="1 2"/>',
                '<capsule radius="0.1" length="-1"/>',
                '<cylinder radius="1e308" length="1e308"/>',
            ]
        )
        n = ctx.choice([1, 3])
        text = re.sub(r"<(cylinder|sphere)[^>]*/>", sub, text, count=n)
        ctx.note(f"collision shapes ({n}) made {sub}")
    elif m == "mesh":
        sub = ctx.choice(
            [
                "package_missing",
                "empty",
                "garbage",
                "binary_stl",
                "binary_stl_lies",
                "ascii_stl_damaged",
                "dae_garbage",
                "obj_garbage",
                "directory",
                "fifo",
                "shared_stl",
                "scale",
            ]
        )
        mesh_name = {"dae_garbage": "part.dae", "obj_garbage": "part.obj"}.get(sub, "part.stl")
        mesh = ctx.dir / mesh_name
        filename = str(mesh)
        if sub == "package_missing":
            filename = "package://nowhere_description/meshes/part.stl"
        elif sub == "empty":
            mesh.write_bytes(b"")
        elif sub == "garbage":
            mesh.write_bytes(ctx.np.integers(0, 256, 300, dtype=np.uint8).tobytes())
        elif sub == "binary_stl":
            mesh.write_bytes(_binary_stl())
        elif sub == "binary_stl_lies":
            raw = bytearray(_binary_stl())
            raw[80:84] = struct.pack("<I", ctx.choice([0, 10**6, 2**32 - 1]))
            mesh.write_bytes(bytes(raw))
        elif sub == "ascii_stl_damaged":
            mesh.write_bytes(b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex nan 0 0\nendloop\n")
        elif sub == "dae_garbage":
            mesh.write_bytes(b"<COLLADA><library_geometries><geometry><mesh>")
        elif sub == "obj_garbage":
            mesh.write_bytes(b"v 0 0 0\nv 1 1\nf 1 2 3 4 5\nf 9 9 9\n")
        elif sub == "directory":
            mesh.mkdir()
        elif sub == "fifo":
            os.mkfifo(mesh)
            ctx.tag("fifo", "fifo-input")
        elif sub == "shared_stl":
            shared = SHARED_DATA / "robots/robotiq_2f_85/meshes/collision/robotiq_arg2f_85_base_link.stl"
            filename = str(shared)
            if shared.is_file():
                ctx.case.watched.append(shared)
        else:
            mesh.write_bytes(_binary_stl())
        scale = ' scale="0 0 0"' if sub == "scale" else ""
        link = ctx.choice(PANDA_LINKS[1:9])
        text = text.replace(
            f'<link name="{link}">',
            f'<link name="{link}"><collision><geometry><mesh filename="{filename}"{scale}/></geometry></collision>',
            1,
        )
        ctx.note(f"{link} gets a collision mesh: {sub} ({Path(filename).name})")
    elif m == "frames":
        base = ctx.choice(PANDA_LINKS + ["", "nowhere", "panda_joint1", "world"])
        flange = base if ctx.rng.random() < 0.3 else ctx.choice(PANDA_LINKS + ["", "nowhere", "panda_joint7"])
        sets += ["--set", f"robot.base_frame={json.dumps(base)}", "--set", f"robot.flange_frame={json.dumps(flange)}"]
        ctx.note(f"base_frame {base!r}, flange_frame {flange!r}")
        if base and base == flange:
            ctx.tag("base==flange")
            ctx.case.expect = frozenset({3})
        elif base in ("nowhere", "world") or flange == "nowhere":  # (a joint's name is a frame of Pinocchio's model)
            ctx.case.expect = frozenset({3})
    else:
        sub = ctx.choice(["missing", "directory", "fifo", "symlink", "relative_dots", "tilde", "dev_null"])
        if sub == "missing":
            urdf = ctx.dir / "no_such.urdf"
            ctx.case.expect = frozenset({3})
        elif sub == "directory":
            urdf = ctx.dir / "arm_dir.urdf"
            urdf.mkdir()
            ctx.case.expect = frozenset({3})
        elif sub == "fifo":
            urdf = ctx.dir / "arm_fifo.urdf"
            os.mkfifo(urdf)
            ctx.tag("fifo", "fifo-input")
            ctx.case.expect = frozenset({3})
        elif sub == "symlink":
            (ctx.dir / "real.urdf").write_text(text)
            urdf.symlink_to("real.urdf")
        elif sub == "relative_dots":
            (ctx.dir / "sub").mkdir()
            urdf = ctx.dir / "sub" / ".." / "arm.urdf"
        elif sub == "tilde":
            urdf = Path("~/definitely_not_here_clear_harness.urdf")
            ctx.case.expect = frozenset({3})
        else:
            urdf = Path("/dev/null")
            ctx.case.expect = frozenset({3})
        ctx.note(f"[robot] urdf path: {sub}")
    arm = ctx.dir / "arm.urdf"
    if not arm.is_symlink():
        arm.write_bytes(text.encode("utf-8", "surrogateescape"))
    if ctx.rng.random() < 0.2:
        xyz = [round(ctx.rng.uniform(-0.3, 0.3), 3) for _ in range(3)]
        sets += [
            "--set",
            f"robot.tcp_xyz_m={json.dumps(xyz)}",
            "--set",
            f"robot.tcp_yaw_deg={ctx.choice([0, 90, -180, 45.5])}",
        ]
        ctx.note(f"tcp_xyz_m {xyz}")
    robot = ["--robot", ctx.choice(["panda", "ur5e", "wam"])] if ctx.rng.random() < 0.2 else []
    size = (
        PLAN if ctx.case.heavy and m in ("limits", "axis_origin", "geometry", "frames", "mesh", "joint_type") else SMALL
    )
    fr = ctx.mat.frames[size]
    depth = ctx.write("f_depth.png", ctx.mat.depth_bytes("png", size))
    argv = [
        "plan",
        str(depth),
        "--intrinsics",
        four_numbers(fr.k),
        "--set",
        f"robot.urdf={json.dumps(str(urdf))}",
        *sets,
        *robot,
    ]
    if size == PLAN:
        argv += ["--json", "--time-limit", "20"]
        ctx.case.timeout_s = HEAVY_TIMEOUT_S
    ctx.run(*argv)


# --- settings -----------------------------------------------------------------------------


GRASP_KINDS = ("pinch", "rim", "slide")


def _grasps_rule(value: str) -> bool | None:
    """Whether [plan] grasps must accept ``value`` (True), refuse it (False), or None when
    the README leaves it open (spaces, case, empty items)."""
    items = value.split(",")
    if any(i != i.strip() or not i for i in items) or value != value.strip():
        return None
    if any(i not in GRASP_KINDS for i in items):
        return None if any(i.lower() in GRASP_KINDS for i in items) else False
    if len(set(items)) != len(items):
        return None
    return "pinch" in items


def gen_settings(ctx: Ctx) -> None:
    """--set, --settings FILE, --robot and --grasps with odd values; flag aliases."""
    sub = ctx.pick({"set": 0.38, "file": 0.24, "grasps": 0.16, "robot": 0.07, "flags": 0.1, "malformed": 0.05})
    ctx.tag(sub)
    size = PLAN if ctx.case.heavy else SMALL
    fr = ctx.mat.frames[size]
    depth = ctx.write("f_depth.png", ctx.mat.depth_bytes("png", size))
    image = [str(depth), "--intrinsics", four_numbers(fr.k)]
    ranges = ctx.mat.settings_ranges()
    if sub == "grasps":
        value = ctx.choice(
            [",".join(p) for r in (1, 2, 3) for p in itertools.permutations(GRASP_KINDS, r)]
            + [
                "pinch,pinch",
                "rim",
                "",
                " ",
                "pinch, rim",
                "PINCH",
                "pinch,rim,slide,push",
                "pinch;rim",
                "pinch,",
                ",pinch",
                "pinch,rim,rim",
                "slide,rim",
                "all",
                "pinch\nrim",
            ]
        )
        ctx.tag("grasps")
        ctx.note(f"grasps {value!r} as --grasps, --set plan.grasps and a settings file")
        f = ctx.write("grasps.toml", f"[plan]\ngrasps = {json.dumps(value)}\n")
        ctx.run("plan", *image, "--grasps", value)
        ctx.run("plan", *image, "--set", f"plan.grasps={json.dumps(value)}")
        ctx.run("plan", *image, "--settings", f)
        ctx.case.consistent = True
        rule = _grasps_rule(value)
        if rule is not None:
            ctx.case.expect = frozenset({0, 4, 5, 10} if rule else {3})
        return
    if sub == "robot":
        name = ctx.choice(["panda", "ur5e", "wam", "WAM", "", "urdf", "../wam", "panda ", "kuka", "ur5e\t", "p" * 500])
        ctx.note(f"--robot {name!r}")
        known = name.strip() in ("panda", "ur5e", "wam")  # (read as a TOML bare word: spaces around do not count)
        ctx.case.expect = None if known else frozenset({3})
        ctx.run(ctx.choice(["plan", "predicates"]), *image, "--robot", name)
        return
    if sub == "flags":
        flag, cmd = ctx.choice(
            [
                ("--voxel-m", "segment"),
                ("--seed-m", "segment"),
                ("--concavity-deg", "segment"),
                ("--plane-distance-m", "segment"),
                ("--min-object-area-m2", "segment"),
                ("--outlier-method", "segment"),
                ("--time-limit", "plan"),
                ("--camera-pose", "plan"),
                ("--depth-scale", "info"),
                ("--frame", "segment"),
            ]
        )
        if flag == "--camera-pose":
            v = ctx.choice(
                [
                    "thesis",
                    "1 2 3 0 0 0 1",
                    "0 0 0 0 0 0 0",
                    "nan 0 0 0 0 0 1",
                    "1 2 3",
                    "",
                    "1e9 0 0 0 0 0 1",
                    "0 0 0 0 0 0 inf",
                    "a b c d e f g",
                    "0,0,0,0,0,0,1",
                    " 1 2 3 0 0 0 1 ",
                ]
            )
        elif flag == "--outlier-method":
            v = ctx.choice(["none", "statistical", "depth_radius", "", "NONE", "magic"])
        else:
            v = odd_number(ctx)[0]
        ctx.note(f"{cmd} {flag} {v!r}")
        ctx.case.allowed = DOCUMENTED | {USAGE}
        ctx.run(cmd, *image, flag, v)
        return
    if sub == "malformed":
        s = ctx.choice(
            [
                "segment.voxel_m",
                "voxel_m=1",
                "=1",
                "segment.=1",
                ".voxel_m=1",
                "segment.voxel_m==1",
                "a.b.c=1",
                "segment.voxel_m=",
                "nosuch.key=1",
                "segment.nosuch=1",
                "SEGMENT.voxel_m=0.005",
                " segment.voxel_m=0.005",
                "segment.voxel_m=0.005 # c",
                "segment.voxel_m=[",
                "plan.grasps=pinch",
                "robot.urdf=",
                "images.intrinsics=5",
            ]
        )
        ctx.note(f"--set {s!r}")
        if ctx.rng.random() < 0.5:
            ctx.run("segment", *image, "--set", s)
        else:
            ctx.run("settings", "--set", s)
        return
    if sub == "set":
        section, key, default, text = ctx.choice(ranges)
        value = _odd_setting_value(ctx, default, text, in_range=ctx.case.heavy)
        ctx.note(f"--set {section}.{key}={value}")
        ctx.tag(f"{section}.{key}")
        if ctx.case.heavy:
            ctx.run("plan", *image, "--set", f"{section}.{key}={value}", "--json", "--time-limit", "20")
            ctx.case.timeout_s = HEAVY_TIMEOUT_S
        else:
            cmd = ctx.pick({"settings": 0.5, "segment": 0.3, "plan": 0.2})
            ctx.run(cmd, *([] if cmd == "settings" else image), "--set", f"{section}.{key}={value}")
        return
    # a settings file: `clear settings` itself, then damaged
    toml = ctx.mat.settings_toml()
    m = ctx.pick({"value": 0.45, "truncate": 0.12, "flip": 0.1, "structure": 0.18, "whole": 0.1, "path": 0.05})
    ctx.tag(m)
    f = ctx.dir / "mine.toml"
    data: bytes | None
    if m == "value":
        lines = toml.splitlines()
        idx = [i for i, line in enumerate(lines) if " = " in line and not line.startswith("#")]
        for _ in range(ctx.choice([1, 1, 2, 3])):
            i = ctx.choice(idx)
            key, default = lines[i].split(" = ", 1)
            section = next((lines[j].strip("[]") for j in range(i, -1, -1) if lines[j].startswith("[")), "")
            rtext = next((t for s, k, d, t in ranges if s == section and k == key), "")
            value = _odd_setting_value(ctx, default.split("  #")[0], rtext, in_range=False)
            lines[i] = f"{key} = {value}"
            ctx.note(f"settings file [{section}] {key} = {value}")
        data = ("\n".join(lines) + "\n").encode()
    elif m == "truncate":
        data, off = truncate(toml.encode(), ctx.rng)
        ctx.note(f"`clear settings` output truncated at {off} as --settings")
    elif m == "flip":
        data, how = flip_bytes(toml.encode(), ctx.rng, ctx.choice([1, 2, 6]))
        ctx.note(f"`clear settings` output as --settings: {how}")
    elif m == "structure":
        extra = ctx.choice(
            [
                "[segment]\nvoxel_m = 0.005\n",
                "[nosuch]\nx = 1\n",
                "segment = 5\n",
                "[segment.sub]\nx = 1\n",
                "[[segment]]\nx = 1\n",
                '[plan]\ngrasps = ["pinch"]\n',
                "[robot]\ncamera_pose = [1, 2, 3]\n",
                "[robot]\ntcp_xyz_m = [0.6, 0, 0]\n",
                '[images]\ndepth_suffix = ""\n',
                "x = 1\n",
                "[segment]\nvoxel_m = 0.005\nvoxel_m = 0.006\n",
                "[robot]\nurdf = 5\n",
                '[gripper]\nopening_width_m = "7 cm"\n',
                "[robot]\nbase_min_object_distance_m = 1.5\nbase_max_object_distance_m = 1.0\n",
            ]
        )
        where = ctx.choice(["start", "end"])
        data = ((extra + toml) if where == "start" else (toml + extra)).encode()
        ctx.note(f"settings file with {extra!r} at its {where}")
    elif m == "whole":
        data = ctx.choice(
            [
                b"",
                b"\n",
                b"\x00\xff",
                b"\xef\xbb\xbf[segment]\nvoxel_m = 0.005\n",
                b"= = =",
                b"[" * 5000,
                b"a = " + b"[" * 2000 + b"]" * 2000,
                b"# only a comment\n",
                "[segment]\nvoxel_m = ٠.005\n".encode(),
            ]
        )
        ctx.note(f"settings file {data[:30]!r}")
    else:
        data = None
        kind = ctx.choice(["missing", "directory", "fifo"])
        if kind == "directory":
            f.mkdir()
        elif kind == "fifo":
            os.mkfifo(f)
            ctx.tag("fifo", "fifo-input")
        ctx.case.expect = frozenset({3})
        ctx.note(f"--settings is {kind}")
    if data is not None:
        f.write_bytes(data)
    cmd = ctx.pick({"settings": 0.4, "segment": 0.4, "plan": 0.2})
    ctx.run(cmd, *([] if cmd == "settings" else image), "--settings", f)


def _odd_setting_value(ctx: Ctx, default: str, range_text: str, in_range: bool) -> str:
    """A TOML value for a setting: in range (its bounds, or a value between) or odd."""
    default = default.strip()
    bounds = [float(x) for x in re.findall(r"[<>]=? (-?[\d.e+-]+)", range_text)]
    if in_range and bounds and not default.startswith(("[", '"')) and default not in ("true", "false"):
        lo, hi = (bounds + [bounds[0]])[:2]
        lo, hi = min(lo, hi), max(lo, hi)
        if default.lstrip("-").isdigit():
            return str(ctx.choice([math.ceil(lo), math.floor(hi), int(ctx.rng.uniform(lo, hi))]))
        eps = 1e-9 if ">" in range_text and ">=" not in range_text else 0
        return repr(ctx.choice([lo + eps, hi, ctx.rng.uniform(lo, hi)]))
    if default.startswith("["):
        return ctx.choice(
            [
                "[]",
                "[nan]",
                "[1, 2, 3]",
                "[1e9, 0, 0]",
                "[0, 0, 0, 0, 0, 0, 0]",
                '["a"]',
                "[[1]]",
                "1",
                "[inf, 0, 0, 0, 0, 0, 1]",
                "[" + ", ".join(["0.1"] * 11) + "]",
                "[-1]",
                "[0.0, 0.0, 0.0]",
            ]
        )
    if default.startswith('"'):
        return ctx.choice(
            [
                '""',
                '"x"',
                '"none"',
                "5",
                "true",
                '"' + "a" * 3000 + '"',
                '"/dev/null"',
                '"~"',
                '"\\u0000"',
                '["pinch"]',
                '"pinch, rim"',
                '"-"',
                '"../../etc/passwd"',
            ]
        )
    if default in ("true", "false"):
        return ctx.choice(["1", "0", '"true"', "yes", "nan", "[]", "TRUE"])
    return ctx.choice(
        [
            "nan",
            "inf",
            "-inf",
            "+nan",
            "0",
            "-0.0",
            "-1",
            "1e9",
            "1e308",
            "1e-320",
            "1" + "0" * 30,
            "9223372036854775807",
            "-9223372036854775808",
            "0.5",
            '"1"',
            "[1]",
            "true",
            "abc",
            "0x10",
            "1_000",
            "1e400",
            "",
            "1979-05-27",
        ]
    )


# --- outputs onto odd files ---------------------------------------------------------------


OUTPUT_FLAGS = {
    "segment": [("-o", "labels.pcd", "pcd"), ("--png", "seg.png", "png")],
    "predicates": [("-o", "problem.pddl", "pddl"), ("--png", "pred.png", "png")],
    "plan": [
        ("-o", "plan.txt", "text"),
        ("--problem", "problem.pddl", "pddl"),
        ("--domain", "domain.pddl", "pddl"),
        ("--png", "plan.png", "png"),
    ],
}


def gen_outputs(ctx: Ctx) -> None:
    """-o / --png / --problem / --domain / --out / --out-dir onto a FIFO, a character device, a
    symlink to an input, a paired input, a missing folder, an existing file, a folder."""
    # The small frame fails (exit 4) before anything is written: it tests the refusals made
    # before the work. Targets where the write itself is the question (a device, a FIFO, a
    # link, --force over a file or an input) mostly get the frame that segments and plans.
    # Which frame is chosen last (the files are rewritten then); the names are fixed now.
    heavy = ctx.case.heavy
    depth = ctx.write("x_depth.png", b"")
    colour = ctx.write("x_color.png", b"")
    intr_name = ctx.choice(["camera_info.yaml", "camera_params.json"])
    intr = ctx.write(intr_name, b"")
    sets_file = ctx.write("mine.toml", "[segment]\nvoxel_m = 0.005\n")

    def frame_files(heavy: bool) -> None:
        size = PLAN if heavy else SMALL
        f = ctx.mat.frames[size]
        depth.write_bytes(ctx.mat.depth_bytes("png", size))
        colour.write_bytes(ctx.mat.color_bytes("png", size))
        layout = "ros_yaml" if intr_name.endswith(".yaml") else "uois"
        intr.write_bytes(dump_mapping(intr_name, intrinsics_files(f.k, size)[layout][1]).encode())
        if heavy:
            ctx.case.timeout_s = HEAVY_TIMEOUT_S
            ctx.note(f"the frame is {size[0]}x{size[1]} (it segments)")

    sub = ctx.pick({"single": 0.8, "replay": 0.08, "batch": 0.12})
    ctx.tag(sub)
    if sub != "single":
        frame_files(False)
    if sub == "replay":
        log = ctx.write("log.mcap", ctx.mat.mcap_bytes())
        force = ctx.rng.random() < 0.5
        target, desc, must_refuse = _odd_target(ctx, "annotated.mcap", {"log": log}, force)
        ctx.case.outputs.append(Output(target, "mcap", must_refuse))
        ctx.note(f"replay --out onto {desc}{' --force' if force else ''}")
        ctx.run("replay", log, "--out", target, *(["--force"] if force else []))
        if must_refuse:
            ctx.case.expect = frozenset({8})
        return
    if sub == "batch":
        folder = ctx.dir / "frames"
        folder.mkdir()
        for k in range(2):
            (folder / f"p{k}_depth.png").write_bytes(ctx.mat.depth_bytes("png", SMALL))
        (folder / "camera_params.json").write_text(
            dump_mapping("camera_params.json", intrinsics_files(ctx.mat.frames[SMALL].k, SMALL)["uois"][1])
        )
        kind = ctx.choice(
            [
                "file",
                "fifo",
                "missing_parent",
                "input_folder",
                "chardev",
                "symlink_to_input_folder",
                "fresh",
                "input_file",
            ]
        )
        out = ctx.dir / "out"
        if kind == "file":
            out.write_text("x")
            ctx.case.expect = frozenset({3, 8})
        elif kind == "fifo":
            os.mkfifo(out)
            ctx.tag("fifo")
            ctx.case.expect = frozenset({3, 8})
        elif kind == "missing_parent":
            out = ctx.dir / "no" / "such" / "out"
        elif kind == "input_folder":
            out = folder
        elif kind == "chardev":
            _mknod_null(out)
            ctx.tag("chardev")
            ctx.case.expect = frozenset({3, 8})
        elif kind == "symlink_to_input_folder":
            out.symlink_to("frames")
            ctx.case.outputs.append(Output(folder, "dir"))
        elif kind == "input_file":
            out = folder / "p0_depth.png"
            ctx.case.expect = frozenset({3, 8})
        ctx.case.outputs.append(Output(out, "dir"))
        cmd = ctx.choice(["segment", "plan", "predicates"])
        outputs = {"segment": "labels,png", "plan": "plan,problem", "predicates": "problem"}[cmd]
        ctx.note(f"batch {cmd} of a folder with --out-dir onto {kind}")
        ctx.run(
            cmd,
            folder,
            "--out-dir",
            out,
            "--jobs",
            "1",
            *(["--outputs", outputs] if outputs else []),
            *(["--force"] if ctx.rng.random() < 0.3 else []),
        )
        return
    cmd = ctx.choice(["segment", "segment", "predicates", "plan"])
    flags = OUTPUT_FLAGS[cmd]
    chosen = ctx.rng.sample(flags, ctx.choice([1, 1, 2]))
    argv: list[Any] = [cmd, depth]
    inputs = {"depth": depth, "colour": colour, "intrinsics": intr}  # the intrinsics file is read from beside the image
    if ctx.rng.random() < 0.3:
        argv += ["--settings", sets_file]
        inputs["settings"] = sets_file
    if ctx.rng.random() < 0.2:
        argv += ["--intrinsics", intr]
    force = ctx.rng.random() < 0.5
    refused = False
    same = len(chosen) == 2 and ctx.rng.random() < 0.15
    for n, (flag, default_name, okind) in enumerate(chosen):
        if same and n == 1:
            first = ctx.case.outputs[0]
            target, desc, must_refuse = first.path, "the same path as the other output", first.must_refuse
            ctx.tag("same-target")
        else:
            target, desc, must_refuse = _odd_target(ctx, default_name, inputs, force)
        refused |= must_refuse
        required = cmd != "plan" or flag != "--domain"
        ctx.case.outputs.append(Output(target, okind, must_refuse, required))
        argv += [flag, target]
        ctx.note(f"{cmd} {flag} onto {desc}")
    if force:
        argv.append("--force")
        ctx.note("with --force")
    if refused:
        ctx.case.expect = frozenset({8})
    writes = {
        "fifo",
        "chardev",
        "symlink_input",
        "paired_input",
        "existing",
        "dangling",
        "hardlink_input",
        "odd_name",
        "fresh",
        "same-target",
    } & ctx.case.tags
    heavy = heavy or (
        bool(writes) and (force or not ({"fifo", "chardev", "existing"} >= writes)) and ctx.rng.random() < 0.6
    )
    frame_files(heavy)
    if cmd == "plan" and heavy:
        argv += ["--time-limit", "20"]
    ctx.run(*argv)


def _mknod_null(path: Path) -> None:
    """A character device with /dev/null's numbers at ``path`` (root only; else a FIFO)."""
    st = os.stat("/dev/null")
    try:
        os.mknod(path, stat.S_IFCHR | 0o666, st.st_rdev)
    except (PermissionError, OSError):
        os.mkfifo(path)


def _odd_target(ctx: Ctx, default_name: str, inputs: dict[str, Path], force: bool) -> tuple[Path, str, bool]:
    """(path, how it was made, whether the run must refuse it) for an output flag."""
    kind = ctx.pick(
        {
            "fresh": 0.15,
            "fifo": 0.1,
            "chardev": 0.12,
            "symlink_input": 0.12,
            "paired_input": 0.14,
            "missing_dir": 0.07,
            "existing": 0.1,
            "folder": 0.05,
            "too_long": 0.03,
            "dangling": 0.04,
            "odd_name": 0.04,
            "hardlink_input": 0.04,
        }
    )
    ctx.tag(kind)
    if kind == "fresh":
        return ctx.dir / default_name, f"a new file {default_name}", False
    if kind == "fifo":
        p = ctx.dir / f"fifo_{default_name}"
        os.mkfifo(p)
        ctx.tag("fifo")
        return p, "a FIFO", False
    if kind == "chardev":
        p = ctx.dir / f"null_{default_name}"
        _mknod_null(p)
        return p, "a character device twin of /dev/null", False
    if kind == "symlink_input":
        what = ctx.choice(list(inputs))
        p = ctx.dir / f"link_{default_name}"
        p.symlink_to(inputs[what].name)
        ctx.tag("symlink-input", f"paired-{what}")
        return p, f"a symlink to the {what} input {inputs[what].name}", True
    if kind == "paired_input":
        what = ctx.choice(list(inputs))
        ctx.tag(f"paired-{what}")
        return inputs[what], f"the {what} input {inputs[what].name} itself", True
    if kind == "missing_dir":
        return ctx.dir / "no_such_dir" / default_name, "a path in a missing folder", True
    if kind == "existing":
        p = ctx.write(f"old_{default_name}", b"precious old content\n")
        return p, "an existing file", not force
    if kind == "folder":
        p = ctx.dir / f"dir_{default_name}"
        p.mkdir()
        return p, "a folder", True
    if kind == "too_long":
        return ctx.dir / ("n" * 300 + default_name), "a name of 300+ bytes", True
    if kind == "dangling":
        p = ctx.dir / f"dangling_{default_name}"
        p.symlink_to("nowhere/at/all")
        return p, "a dangling symlink", False
    if kind == "hardlink_input":
        what = ctx.choice(list(inputs))
        p = ctx.dir / f"hard_{default_name}"
        os.link(inputs[what], p)
        ctx.tag("hardlink-input")
        return p, f"a hard link to the {what} input", not force
    ctx.tag("odd_name")
    name = ctx.choice(
        [
            "with space.png",
            "new\nline.png",
            "ünïcode.png",
            "-o.png",
            ".hidden.png",
            "a*b?.png",
            "x.part",
            ".x.abcdefgh.part",
        ]
    )
    if not name.endswith(Path(default_name).suffix):
        name += Path(default_name).suffix
    return ctx.dir / name, f"an odd name {name!r}", False


# --- point clouds (PCD) ---------------------------------------------------------------------


def _table_cloud(ctx: Ctx, w: int, h: int) -> tuple[np.ndarray, np.ndarray]:
    """An organized (h*w, 3) float32 cloud of a table 1 m below a camera looking down, a
    box on it (so a valid cloud segments to one object), and (h*w,) packed grey colours."""
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    f_px = 0.9 * w
    box = (np.abs(u - w / 2) < w / 8) & (np.abs(v - h / 2) < h / 8)
    z = np.where(box, 0.9, 1.0) + ctx.np.normal(0.0, 0.0005, (h, w))
    pts = np.stack([(u - w / 2) / f_px * z, (v - h / 2) / f_px * z, z], axis=-1).reshape(-1, 3)
    return pts.astype(np.float32), np.full(h * w, 0x806040, dtype=np.uint32)


def gen_cloud(ctx: Ctx) -> None:
    """PCD point clouds: ASCII, binary and LZF-compressed, their header lines and values
    damaged (FIELDS/SIZE/TYPE/COUNT/WIDTH/HEIGHT/POINTS/VIEWPOINT/DATA), absurd coordinates
    (NaN, inf, 1e38), and the data block truncated, flipped or followed by junk."""
    import lzf

    w, h = ctx.choice([(48, 36), (64, 48), (160, 120)]) if not ctx.case.heavy else (320, 240)
    pts, rgb = _table_cloud(ctx, w, h)
    if ctx.rng.random() < 0.15:  # unorganized: one row, or one column
        w, h = (w * h, 1) if ctx.rng.random() < 0.7 else (1, w * h)
    n = pts.shape[0]
    data = ctx.pick({"ascii": 0.3, "binary": 0.35, "binary_compressed": 0.35})
    ctx.tag(data)
    fields, size, typ, count = ["x", "y", "z", "rgb"], ["4"] * 4, ["F", "F", "F", "U"], ["1"] * 4
    coord = "<f4"
    if ctx.rng.random() < 0.15:  # float64 coordinates
        size[:3], coord = ["8"] * 3, "<f8"
        ctx.note("x/y/z as float64")
    if ctx.rng.random() < 0.3:
        value = ctx.choice([float("nan"), float("inf"), float("-inf"), 1e38, -3e38, 1e300, 0.0, 1e-45, 1e19])
        share = ctx.choice([0.01, 0.3, 1.0])
        rows = ctx.np.random(n) < share
        cols = ctx.choice([[0], [1], [2], [0, 1, 2]])
        wide = pts.astype(np.float64)
        for c in cols:
            wide[rows, c] = value
        with np.errstate(over="ignore"):
            pts = wide.astype(np.float32) if coord == "<f4" else wide  # type: ignore[assignment]
        ctx.note(f"{value} in {int(rows.sum())} points' {'xyz'[cols[0]] if len(cols) == 1 else 'xyz'}")
        ctx.tag("values")
    header: dict[str, str] = {
        "VERSION": "0.7",
        "FIELDS": " ".join(fields),
        "SIZE": " ".join(size),
        "TYPE": " ".join(typ),
        "COUNT": " ".join(count),
        "WIDTH": str(w),
        "HEIGHT": str(h),
        "VIEWPOINT": "0 0 0 1 0 0 0",
        "POINTS": str(n),
        "DATA": data,
    }
    mutation = ctx.pick(
        {
            "none": 0.3,
            "FIELDS": 0.07,
            "SIZE": 0.06,
            "TYPE": 0.06,
            "COUNT": 0.06,
            "WIDTH": 0.06,
            "HEIGHT": 0.04,
            "POINTS": 0.06,
            "VIEWPOINT": 0.06,
            "DATA": 0.04,
            "VERSION": 0.03,
            "missing": 0.05,
            "duplicate": 0.03,
            "crlf": 0.03,
            "junk_line": 0.03,
            "order": 0.02,
        }
    )
    ctx.tag("header_" + mutation)
    odd = {
        "FIELDS": [
            "x y",
            "x x z rgb",
            "a b c d",
            "X Y Z RGB",
            "x y z normal_x",
            "",
            "x y z rgb label extra",
            "x\ty z rgb",
        ],
        "SIZE": ["4 4 4", "8 8 8 8", "2 2 2 4", "4 4 4 0", "4 4 4 -4", "4 4 4 99999999999", "a b c d", "1 1 1 1"],
        "TYPE": ["F F F", "I I I U", "U U U U", "F F F F", "Q F F U", "f f f u", "F F F I"],
        "COUNT": ["1 1 1", "0 1 1 1", "2 1 1 1", "-1 1 1 1", "1 1 1 1000000000", "1.5 1 1 1", "1 1 1 300"],
        "WIDTH": ["0", str(w + 1), str(w * 2), "-5", str(10**12), str(2**31), "1e3", "0x10"],
        "HEIGHT": ["0", str(h + 1), "-1", str(2**63), "nan"],
        "POINTS": ["0", str(n - 1), str(n + 1), "-1", str(10**15), "abc"],
        "VIEWPOINT": [
            "0 0 0 0 0 0 0",
            "nan 0 0 1 0 0 0",
            "0 0 0 1 0 0",
            "1e308 1e308 1e308 1 0 0 0",
            "0 0 0 inf 0 0 0",
            "a b c d e f g",
            "0 0 0 1e-300 0 0 0",
            "0 0 0 2 0 0 0",
            "0 0 0 1 0 0 0 0",
        ],
        "DATA": ["binaryx", "ASCII", "", "binary_compressed extra", "ascii binary"],
        "VERSION": ["9", ".7", "0.6", "", "0.7.1"],
    }
    if mutation in odd:
        header[mutation] = ctx.choice(odd[mutation])
        ctx.note(f"{mutation} {header[mutation]!r}")
    elif mutation == "missing":
        gone = ctx.choice(list(header))
        del header[gone]
        ctx.note(f"no {gone} line")
    else:
        ctx.note(f"header: {mutation}")
    lines = ["# .PCD v0.7 - made by clear's harness"] + [f"{k} {v}".rstrip() for k, v in header.items()]
    if mutation == "duplicate":
        k = ctx.rng.randrange(1, len(lines))
        lines.insert(k, lines[k].split(" ")[0] + " 3")
    elif mutation == "junk_line":
        lines.insert(ctx.rng.randrange(1, len(lines)), ctx.choice(["FOO bar", "\udcff\udcfe junk", "x" * 5000, "   "]))
    elif mutation == "order":
        body_lines = lines[1:-1]
        ctx.rng.shuffle(body_lines)
        lines = lines[:1] + body_lines + lines[-1:]
    head = ("\r\n" if mutation == "crlf" else "\n").join(lines) + ("\r\n" if mutation == "crlf" else "\n")
    head_bytes = head.encode("utf-8", "surrogateescape")
    rec = np.zeros(n, dtype=[("x", coord), ("y", coord), ("z", coord), ("rgb", "<u4")])
    for k, name in enumerate("xyz"):
        rec[name] = pts[:, k]
    rec["rgb"] = rgb
    encoding = data if mutation != "DATA" else ctx.choice(["ascii", "binary"])
    if encoding == "ascii":
        body = "".join(f"{a!r} {b!r} {c!r} {d}\n" for a, b, c, d in rec.tolist()).encode()
        if ctx.rng.random() < 0.15:
            body = body.replace(b"1", ctx.choice([b"x", b"1.2.3", b"", b"1e999"]), 3)
            ctx.note("odd tokens in the ASCII rows")
    elif encoding == "binary":
        body = rec.tobytes()
    else:
        columns = b"".join(rec[name].tobytes() for name in ("x", "y", "z", "rgb"))
        block = lzf.compress(columns) or columns
        body = struct.pack("<II", len(block), len(columns)) + block
    damage = ctx.pick({"none": 0.6, "truncate": 0.15, "flip": 0.15, "junk": 0.05, "sizes": 0.05})
    ctx.tag("data_" + damage)
    if damage == "truncate":
        body, off = truncate(body, ctx.rng)
        ctx.note(f"data truncated at byte {off}")
    elif damage == "flip":
        body, how = flip_bytes(body, ctx.rng, ctx.rng.choice([1, 4, 64]))
        ctx.note(f"data: {how}")
    elif damage == "junk":
        body += bytes(ctx.np.integers(0, 256, ctx.choice([1, 7, 1000]), dtype=np.uint8))
        ctx.note("junk after the data")
    elif damage == "sizes" and encoding == "binary_compressed":
        sizes = ctx.choice([(0, 0), (2**32 - 1, 2**32 - 1), (len(body), 2**31), (8, len(body))])
        body = struct.pack("<II", *sizes) + body[8:]
        ctx.note(f"compressed sizes {sizes}")
    path = ctx.write("cloud.pcd", head_bytes + body)
    ctx.note(f"{data} PCD {w}x{h}")
    if ctx.case.heavy:
        ctx.run(ctx.choice(["segment", "plan"]), path, "--json")
        ctx.case.timeout_s = HEAVY_TIMEOUT_S
    else:
        _command_for_image(ctx, path)


GENERATORS: dict[str, Callable[[Ctx], None]] = {
    "depth": gen_depth,
    "color": gen_color,
    "intrinsics": gen_intrinsics,
    "log": gen_log,
    "urdf": gen_urdf,
    "settings": gen_settings,
    "outputs": gen_outputs,
    "cloud": gen_cloud,
}


def build_case(seed: int, index: int, kind: str, folder: Path, mat: Materials) -> Case:
    """Case ``index`` of ``seed`` (its inputs written into ``folder``, which must be empty)."""
    folder.mkdir(parents=True, exist_ok=True)
    case = Case(kind=kind, seed=seed, index=index, dir=folder)
    ctx = Ctx(case, mat)
    case.heavy = ctx.rng.random() < HEAVY_SHARE
    if case.heavy:
        case.tags.add("heavy")
    GENERATORS[kind](ctx)
    if "fifo-input" in case.tags:
        case.timeout_s = FIFO_TIMEOUT_S
    if not case.outputs:  # exit 8 is about outputs: a case that asks for none cannot get it
        case.allowed = case.allowed - {8}
    return case


def kind_of(index: int, kinds: Sequence[str]) -> str:
    return kinds[index % len(kinds)]


# ----------------------------------------------------------------------------- checking


@dataclass
class Entry:
    kind: str  # file | dir | fifo | chr | link | other
    digest: str = ""
    rdev: int = 0
    target: str = ""


def snapshot(folder: Path) -> dict[str, Entry]:
    """Every entry under ``folder`` by relative path (files hashed, links not followed)."""
    out: dict[str, Entry] = {}
    for root, dirs, files in os.walk(folder, followlinks=False):
        for name in dirs + files:
            p = Path(root) / name
            rel = str(p.relative_to(folder))
            try:
                st = os.lstat(p)
            except OSError:
                continue
            if stat.S_ISLNK(st.st_mode):
                out[rel] = Entry("link", target=os.readlink(p))
            elif stat.S_ISREG(st.st_mode):
                out[rel] = Entry("file", sha256(p))
            elif stat.S_ISDIR(st.st_mode):
                out[rel] = Entry("dir")
            elif stat.S_ISFIFO(st.st_mode):
                out[rel] = Entry("fifo")
            elif stat.S_ISCHR(st.st_mode):
                out[rel] = Entry("chr", rdev=st.st_rdev)
            else:
                out[rel] = Entry("other")
    return out


@dataclass
class Problem:
    symptom: (
        str  # exit1 | traceback | undocumented-exit | expected-code | stderr-lines | input-changed | special-replaced |
    )
    #               output-broken | output-missing | temporary-left | unexpected-file | timeout | inconsistent | json-stdout |
    #               self-contradiction | misattributed-error | same-target |
    #               python-warning (soft: reported as a note, not a failure)
    detail: str

    @property
    def soft(self) -> bool:
        return self.symptom in SOFT_SYMPTOMS


# Not a broken promise, but worth a look: a Python warning (file:line: RuntimeWarning ...)
# printed on stderr beside `clear`'s own lines.
SOFT_SYMPTOMS = frozenset({"python-warning"})


def _validate_output(path: Path, kind: str) -> str | None:
    """Why ``path`` is not a whole output of ``kind`` (or of one of "a|b"), or None."""
    if "|" in kind:
        whys = [_validate_output(path, k) for k in kind.split("|")]
        return None if any(w is None for w in whys) else "; ".join(w for w in whys if w)
    try:
        if kind == "png":
            from PIL import Image

            with Image.open(path) as im:
                im.load()
        elif kind == "pcd":
            from clearcli.io.pcd import read_pcd

            read_pcd(path)
        elif kind == "json":
            json.loads(path.read_text())
        elif kind in ("text", "pddl"):
            t = path.read_text()
            if kind == "pddl" and (t.count("(") != t.count(")") or "(define" not in t):
                return "unbalanced or not a PDDL define"
        elif kind == "mcap":
            from mcap.reader import make_reader

            with open(path, "rb") as fp:
                for _ in make_reader(fp).iter_messages():
                    pass
    except Exception as exc:  # noqa: BLE001 - any failure to read back is the finding
        return f"{type(exc).__name__}: {str(exc)[:120]}"
    return None


def _unblock_fifos(folder: Path) -> None:
    """Open every FIFO of the case both ways without blocking, so that a reader or writer
    `clear` left waiting on it (a case that timed out) gets its end and goes on."""
    for root, _dirs, files in os.walk(folder):
        for name in files:
            p = os.path.join(root, name)
            with contextlib.suppress(OSError):
                if stat.S_ISFIFO(os.lstat(p).st_mode):
                    for flags in (os.O_RDONLY | os.O_NONBLOCK, os.O_WRONLY | os.O_NONBLOCK):
                        with contextlib.suppress(OSError):
                            os.close(os.open(p, flags))


class _FifoDrain:
    """A reader on every FIFO of the case while it runs: a `clear` that writes into a FIFO
    (as a shell's `>(...)` would take it) is read, not left blocked."""

    def __init__(self, folder: Path) -> None:
        self.fds: list[int] = []
        self.stop = False
        for root, _dirs, files in os.walk(folder):
            for name in files:
                p = os.path.join(root, name)
                with contextlib.suppress(OSError):
                    if stat.S_ISFIFO(os.lstat(p).st_mode):
                        self.fds.append(os.open(p, os.O_RDONLY | os.O_NONBLOCK))
        self.thread = threading.Thread(target=self._drain, daemon=True) if self.fds else None
        if self.thread:
            self.thread.start()

    def _drain(self) -> None:
        import select

        while not self.stop:
            try:
                ready, _, _ = select.select(self.fds, [], [], 0.05)
            except (OSError, ValueError):
                return
            for fd in ready:
                with contextlib.suppress(OSError):
                    os.read(fd, 1 << 16)

    def close(self) -> None:
        self.stop = True
        if self.thread:
            self.thread.join(1.0)
        for fd in self.fds:
            with contextlib.suppress(OSError):
                os.close(fd)


def check_run(
    case: Case,
    argv: list[str],
    run: Run,
    before: dict[str, Entry],
    after: dict[str, Entry],
    watched_before: dict[Path, str],
) -> list[Problem]:
    problems: list[Problem] = []
    code = run.code
    last_err = next((line for line in reversed(run.stderr.splitlines()) if line.strip()), "")
    if code == "timeout":
        problems.append(Problem("timeout", f"ran past {case.timeout_s:.0f} s"))
    elif code == 1:
        problems.append(Problem("exit1", last_err[:300]))
    elif code not in case.allowed:
        problems.append(Problem("undocumented-exit", f"exit {code}: {last_err[:300]}"))
    elif code == 9 and not _is_log(argv):
        problems.append(
            Problem("expected-code", f"exit 9 (a log read in part) for an input that is no log: {last_err[:300]}")
        )
    elif code == 11 and not _is_batch(argv):
        problems.append(Problem("expected-code", f"exit 11 (a batch) for one frame: {last_err[:300]}"))
    elif case.expect is not None and code not in case.expect and not case.consistent:
        problems.append(Problem("expected-code", f"exit {code}, expected {sorted(case.expect)}: {last_err[:300]}"))
    if "Traceback (most recent call last)" in run.stderr or "Traceback (most recent call last)" in run.stdout:
        problems.append(
            Problem("traceback", run.stderr.strip().splitlines()[-1][:200] if run.stderr.strip() else "in stdout")
        )
    err_lines = [line for line in run.stderr.splitlines() if line.startswith("clear: error:")]
    if isinstance(code, int) and code in ONE_LINE_ERRORS:
        if len(err_lines) != 1 or not last_err.startswith("clear: error:"):
            problems.append(
                Problem(
                    "stderr-lines",
                    f"exit {code} with {len(err_lines)} error line(s); stderr: {run.stderr.strip()[-300:]!r}",
                )
            )
    elif isinstance(code, int) and code in (0, 5, 10, 11) and len(err_lines) > 1:
        problems.append(Problem("stderr-lines", f"exit {code} with {len(err_lines)} error lines"))
    if any("\n" in line for line in err_lines):
        problems.append(Problem("stderr-lines", "an error line holds a newline"))
    if "clear: internal error" in run.stderr and code != 1:
        problems.append(Problem("exit1", f"an internal error with exit {code}"))
    if "cannot write the results to stdout" in run.stderr:
        # stdout is a file of the harness here, which takes every byte: another error said as this one
        problems.append(Problem("misattributed-error", last_err[:300]))
    targets = [str(o.path) for o in case.outputs if o.kind != "dir"]
    doubled = {t for t in targets if targets.count(t) > 1}
    if code == 0 and any(os.path.isfile(t) for t in doubled):  # (into a device or FIFO both may go)
        problems.append(
            Problem(
                "same-target",
                "two outputs named the same file and the run said nothing: the later replaced the earlier",
            )
        )
    said = re.search(r"--frame (\d+) does not exist: .*? has (\d+) frames", run.stderr)
    if said and int(said.group(1)) < int(said.group(2)):
        problems.append(Problem("self-contradiction", said.group(0)[:200]))
    w = _PY_WARNING.search(run.stderr)
    if w:
        line = run.stderr[w.start() :].splitlines()[0]
        problems.append(Problem("python-warning", line[:200]))
    if "--json" in argv and code in (0, 5, 10) and run.stdout.strip():
        for line in run.stdout.strip().splitlines():
            try:
                json.loads(line)
            except ValueError:
                problems.append(Problem("json-stdout", f"stdout line is not JSON: {line[:80]!r}"))
                break
    # --- the case folder: inputs unchanged, outputs whole or absent, nothing else new
    out_paths: dict[str, Output] = {}
    for o in case.outputs:
        with contextlib.suppress(ValueError):
            rel = str(o.path.relative_to(case.dir))
            if rel in out_paths and out_paths[rel].kind != o.kind:  # two flags, one file: either kind is whole
                o = dataclasses.replace(
                    o, kind=f"{out_paths[rel].kind}|{o.kind}", must_refuse=o.must_refuse or out_paths[rel].must_refuse
                )
            out_paths[rel] = o
    for rel, e in before.items():
        a = after.get(rel)
        o = out_paths.get(rel)
        if e.kind in ("fifo", "chr"):
            if a is None or a.kind != e.kind or a.rdev != e.rdev:
                problems.append(Problem("special-replaced", f"{rel}: was a {e.kind}, now {a.kind if a else 'gone'}"))
            continue
        if o is not None and not o.must_refuse:
            continue  # an output the run may replace
        if a is None:
            problems.append(Problem("input-changed", f"{rel}: removed"))
        elif (a.kind, a.digest, a.target) != (e.kind, e.digest, e.target):
            problems.append(
                Problem(
                    "input-changed",
                    f"{rel}: its {'content' if a.kind == e.kind else 'type'} changed"
                    f"{' (an output target that had to be refused)' if o else ''}",
                )
            )
    for rel, a in after.items():
        name = Path(rel).name
        if rel in before:
            e = before[rel]
            o = out_paths.get(rel)
            if o is not None and a.kind == "file" and (e.kind, e.digest) != (a.kind, a.digest):
                why = _validate_output(case.dir / rel, o.kind)
                if why:
                    problems.append(Problem("output-broken", f"{rel} ({o.kind}): {why}"))
            continue
        if _TEMPORARY.match(name) and not any(rel == r for r in out_paths):
            problems.append(Problem("temporary-left", rel))
            continue
        o = out_paths.get(rel)
        if o is not None:
            if a.kind == "file":
                why = _validate_output(case.dir / rel, o.kind)
                if why:
                    problems.append(Problem("output-broken", f"{rel} ({o.kind}): {why}"))
            continue
        if any(rel.startswith(r + "/") for r, oo in out_paths.items() if oo.kind == "dir"):
            continue  # inside a batch's --out-dir
        if any(r.startswith(rel + "/") for r, oo in out_paths.items() if oo.kind == "dir"):
            continue  # a parent of a batch's --out-dir, made with it
        if any(
            oo.kind == "dir" and Path(rel).parent == oo.path.relative_to(case.dir)
            for oo in case.outputs
            if _is_within(oo.path, case.dir)
        ):
            continue
        problems.append(Problem("unexpected-file", f"{rel} ({a.kind}) appeared"))
    for o in case.outputs:  # the batch folder's own files: whole, no temporaries
        if o.kind == "dir" and o.path.is_dir() and not o.path.is_symlink():
            for p in o.path.iterdir():
                if _TEMPORARY.match(p.name):
                    problems.append(Problem("temporary-left", str(p)))
                elif p.suffix == ".json" and p.is_file():
                    why = _validate_output(p, "json")
                    if why:
                        problems.append(Problem("output-broken", f"{p.name}: {why}"))
                elif (
                    p.suffix == ".png"
                    and p.is_file()
                    and not p.name.endswith("_depth.png")
                    and not p.name.endswith("_color.png")
                ):
                    why = _validate_output(p, "png")
                    if why:
                        problems.append(Problem("output-broken", f"{p.name}: {why}"))
    if code == 0:
        for rel, o in out_paths.items():
            if o.kind != "dir" and o.required and not o.must_refuse and rel not in before and rel not in after:
                problems.append(Problem("output-missing", f"exit 0 but {rel} was not written"))
    for p, digest in watched_before.items():
        if p.is_file() and sha256(p) != digest:
            problems.append(Problem("input-changed", f"{p} (outside the case) changed"))
    return problems


def _frame_arg(argv: list[str]) -> Path | None:
    """The first FRAME argument of a frame-reading command, if any."""
    if len(argv) > 1 and argv[0] in ("info", "segment", "predicates", "plan", "replay") and not argv[1].startswith("-"):
        return Path(argv[1])
    return None


def _is_log(argv: list[str]) -> bool:
    frame = _frame_arg(argv)
    if frame is None:
        return False
    if frame.is_dir():
        return True
    with contextlib.suppress(OSError):
        if stat.S_ISREG(os.stat(frame).st_mode):
            with open(frame, "rb") as fp:
                head = fp.read(8)
            return head.startswith((b"\x89MCAP", b"#ROSBAG", b"SQLite f"))
    return False


def _is_batch(argv: list[str]) -> bool:
    frame = _frame_arg(argv)
    return frame is not None and (frame.is_dir() or "--out-dir" in argv or "--every" in argv)


def _is_within(p: Path, folder: Path) -> bool:
    try:
        p.relative_to(folder)
        return True
    except ValueError:
        return False


def known_fault(case: Case, problem: Problem, code: int | str) -> str | None:
    """Which of KNOWN_FAULTS a problem is, by the case's tags and the symptom, or None (new)."""
    t = case.tags
    if "bomb" in t and (
        problem.symptom == "timeout"
        or (
            problem.symptom == "exit1"
            and any(w in problem.detail for w in ("DecompressionBomb", "MemoryError", "exceeds limit", "too large"))
        )
    ):
        return "K1"
    if case.kind == "log" and "truncate" in t and "mcap" in t and problem.symptom == "expected-code" and code == 3:
        return "K2"
    if (
        case.kind == "outputs"
        and ({"paired-colour", "paired-intrinsics"} & t)
        and problem.symptom in ("input-changed", "expected-code")
    ):
        return "K3"
    if "chardev" in t and problem.symptom == "special-replaced" and "chr" in problem.detail:
        return "K4"
    if "limit-lower>upper" in t and problem.symptom == "exit1":
        return "K5"
    if "base==flange" in t and problem.symptom == "expected-code":
        return "K6"
    if "metadata-type" in t and problem.symptom in ("expected-code", "self-contradiction"):
        return "K7"
    if "grasps" in t and problem.symptom in ("inconsistent", "expected-code"):
        return "K8"
    return None


@dataclass
class Failure:
    kind: str
    index: int
    seed: int
    symptom: str
    known: str | None
    line: str  # the one-line repro


@dataclass
class Report:
    seed: int
    cases: dict[str, int] = field(default_factory=dict)
    skipped: dict[str, int] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)
    codes: dict[str, dict[str, int]] = field(default_factory=dict)
    failures: list[Failure] = field(default_factory=list)
    notes: list[Failure] = field(default_factory=list)  # soft findings (SOFT_SYMPTOMS)
    wall_s: float = 0.0
    stopped_early: bool = False

    @property
    def total(self) -> int:
        return sum(self.cases.values())

    def summary(self) -> str:
        lines = [
            f"seed {self.seed}: {self.total} cases in {self.wall_s:.1f} s"
            + (" (stopped at the time budget)" if self.stopped_early else "")
        ]
        for k in self.cases:
            codes = ", ".join(f"{c}:{n}" for c, n in sorted(self.codes.get(k, {}).items(), key=lambda x: str(x[0])))
            nf = sum(1 for f in self.failures if f.kind == k)
            lines.append(
                f"  {k:11s} {self.cases[k]:5d} cases {self.seconds.get(k, 0):7.1f} s  failures {nf:3d}  exits {{{codes}}}"
                + (f"  skipped {self.skipped[k]}" if self.skipped.get(k) else "")
            )
        known = [f for f in self.failures if f.known]
        lines.append(
            f"  failures: {len(self.failures)} ({len(known)} known, {len(self.failures) - len(known)} new); "
            f"notes (Python warnings on stderr): {len(self.notes)}"
        )
        return "\n".join(lines)


def _repro(case: Case, problem: Problem, code: int | str) -> str:
    cmds = " ; ".join(case.command_lines())
    line = (
        f"[{case.kind}#{case.index} seed={case.seed}] {problem.symptom}: {problem.detail} | exit {code} | "
        f"made: {'; '.join(case.recipe)} | cmd: {cmds} | rebuild: python benchmarks/fuzz.py --seed {case.seed} "
        f"--case {case.index} --kinds {case.kind} --keep DIR"
    )
    return line.replace("\r", "\\r").replace("\n", "\\n")


def execute_case(
    case: Case, mat: Materials | None = None
) -> tuple[list[tuple[Problem, int | str]], list[int | str], float]:
    """Run every command of ``case`` and check it: (problems with the exit they came with,
    the exit codes, seconds)."""
    found: list[tuple[Problem, int | str]] = []
    codes: list[int | str] = []
    seconds = 0.0
    watched = {p: sha256(p) for p in case.watched if p.is_file()}
    for argv in case.runs:
        before = snapshot(case.dir)
        drain = _FifoDrain(case.dir)
        try:
            run = run_inprocess(argv, case.timeout_s)
        finally:
            drain.close()
            _unblock_fifos(case.dir)
        after = snapshot(case.dir)
        seconds += run.seconds
        codes.append(run.code)
        for p in check_run(case, argv, run, before, after, watched):
            found.append((p, run.code))
    if case.consistent and len(set(codes)) > 1:
        found.append((Problem("inconsistent", f"the same value said {len(codes)} ways gave exits {codes}"), codes[0]))
    if case.consistent and case.expect is not None:
        bad = [c for c in codes if c not in case.expect]
        if bad:
            found.append((Problem("expected-code", f"exits {codes}, expected {sorted(case.expect)}"), bad[0]))
    return found, codes, seconds


def confirm_in_subprocess(seed: int, index: int, kind: str, folder: Path, mat: Materials) -> str:
    """The failing case rebuilt and run as its own process (a fresh interpreter, fresh
    imports): what it gives, for the repro line."""
    case = build_case(seed, index, kind, folder, mat)
    try:
        codes = [run_subprocess(argv, case.timeout_s + 15).code for argv in case.runs]
    finally:
        _unblock_fifos(folder)
        shutil.rmtree(folder, ignore_errors=True)
    return f"own process: exit {codes[0] if len(codes) == 1 else codes}"


def run_cases(
    seed: int,
    n: int,
    kinds: Sequence[str] = KINDS,
    *,
    budget_s: float | None = None,
    start: int = 0,
    progress: Callable[[str], None] | None = None,
    mat: Materials | None = None,
    confirm: int = 25,
) -> Report:
    """``n`` cases of ``seed`` (indices start..start+n-1, kinds in turn), each checked;
    stops starting new ones past ``budget_s``. The first ``confirm`` failing cases are run
    again as their own process, and their lines say what that gave (an in-process run can
    only differ from it through state left by earlier cases, or a tree edited meanwhile)."""
    own = mat is None
    mat = mat or Materials()
    report = Report(seed)
    root = Path(tempfile.mkdtemp(prefix=f"clear-harness-{seed}-"))
    t0 = time.perf_counter()
    try:
        for index in range(start, start + n):
            if budget_s is not None and time.perf_counter() - t0 > budget_s:
                report.stopped_early = True
                break
            kind = kind_of(index, kinds)
            folder = root / f"c{index:06d}"
            try:
                case = build_case(seed, index, kind, folder, mat)
            except Exception as exc:  # noqa: BLE001  (a generator's own bug: said, and the run goes on)
                import traceback

                where = traceback.extract_tb(exc.__traceback__)[-1]
                report.failures.append(
                    Failure(
                        kind,
                        index,
                        seed,
                        "harness-error",
                        None,
                        f"[{kind}#{index} seed={seed}] harness-error: the case could not be made: "
                        f"{type(exc).__name__}: {exc} at {Path(where.filename).name}:{where.lineno}",
                    )
                )
                shutil.rmtree(folder, ignore_errors=True)
                continue
            report.cases[kind] = report.cases.get(kind, 0) + 1
            if not case.runs:
                report.skipped[kind] = report.skipped.get(kind, 0) + 1
                shutil.rmtree(folder, ignore_errors=True)
                continue
            found, codes, secs = execute_case(case, mat)
            report.seconds[kind] = report.seconds.get(kind, 0.0) + secs
            hist = report.codes.setdefault(kind, {})
            for c in codes:
                hist[str(c)] = hist.get(str(c), 0) + 1
            seen: set[tuple[str, str]] = set()
            also = ""
            if confirm > 0 and any(not p.soft for p, _ in found):
                confirm -= 1
                also = " | " + confirm_in_subprocess(seed, index, kind, root / f"c{index:06d}-own", mat)
            for problem, code in found:
                key = (problem.symptom, problem.detail)
                if key in seen:
                    continue
                seen.add(key)
                f = Failure(
                    kind,
                    index,
                    seed,
                    problem.symptom,
                    known_fault(case, problem, code),
                    _repro(case, problem, code) + ("" if problem.soft else also),
                )
                (report.notes if problem.soft else report.failures).append(f)
                if progress:
                    progress(("note " if problem.soft else "") + f.line)
            _unblock_fifos(folder)
            shutil.rmtree(folder, ignore_errors=True)
    finally:
        report.wall_s = time.perf_counter() - t0
        shutil.rmtree(root, ignore_errors=True)
        if own:
            mat.close()
    return report


def compare_with_subprocess(seed: int, index: int, kind: str, mat: Materials, folder: Path) -> tuple[Run, Run, Case]:
    """Case (seed, index) run in this process, then rebuilt in the same folder and run as
    its own process: (in-process run, subprocess run, the case)."""
    case = build_case(seed, index, kind, folder, mat)
    inproc = run_inprocess(case.args, case.timeout_s)
    _unblock_fifos(folder)
    shutil.rmtree(folder)
    case = build_case(seed, index, kind, folder, mat)
    sub = run_subprocess(case.args)
    _unblock_fifos(folder)
    return inproc, sub, case
