"""The garbage-input harness (tests/helpers/harness.py): one quick seed of >= 500 damaged
inputs, odd settings and odd output targets, every one keeping the promises of the
README's "Exit codes" and "Reliability" (a documented exit code, never a traceback, one
error line, outputs whole or absent, no temporaries left, inputs unchanged).

The long run is `benchmarks/fuzz.py` (several seeds, thousands of cases). A failure's
message holds one line per failed case with its command and how its input was made;
`python benchmarks/fuzz.py --seed S --case I --kinds K --keep DIR` rebuilds it.

CLEAR_HARNESS_SEED / CLEAR_HARNESS_CASES change the quick run's seed and size.
"""

from __future__ import annotations

import json
import os
import re
import shutil
from pathlib import Path

import pytest
from helpers import SHARED_DATA
from helpers import harness as H

QUICK_SEED = int(os.environ.get("CLEAR_HARNESS_SEED", "1"))
QUICK_CASES = int(os.environ.get("CLEAR_HARNESS_CASES", "576"))  # 72 of each of the 8 kinds
# The whole run's bound: at ~9 cases/s on 2 shared cores a quick run takes about a minute.
QUICK_BUDGET_S = float(os.environ.get("CLEAR_HARNESS_BUDGET_S", "300"))


@pytest.fixture(scope="module")
def materials():  # type: ignore[no-untyped-def]
    mat = H.Materials()
    yield mat
    mat.close()


def test_garbage_inputs_keep_the_promises(materials: H.Materials) -> None:
    if not H.SHARED_MCAP.is_file() and os.environ.get("CLEAR_REQUIRE_SHARED") == "1":
        pytest.fail(f"shared data {H.SHARED_MCAP} is not here and CLEAR_REQUIRE_SHARED=1")
    report = H.run_cases(QUICK_SEED, QUICK_CASES, H.KINDS, budget_s=QUICK_BUDGET_S, mat=materials)
    print("\n" + report.summary())
    for f in report.notes[:10]:
        print("note: " + f.line)
    assert not report.stopped_early, f"the run passed its {QUICK_BUDGET_S:.0f} s budget after {report.total} cases"
    assert report.total >= min(QUICK_CASES, 500)
    assert set(report.cases) == set(H.KINDS)
    if report.skipped:
        print(f"skipped (shared data absent: {SHARED_DATA}): {report.skipped}")
    lines = [("" if not f.known else f"(known {f.known}) ") + f.line for f in report.failures]
    assert not report.failures, f"{len(lines)} case(s) broke a promise:\n" + "\n".join(lines)


# ----------------------------------------------------------------------------- the harness itself


def _normalised_stdout(text: str) -> str:
    """stdout without what differs between two runs of the same command (times)."""
    out = []
    for line in text.splitlines():
        try:
            doc = json.loads(line)
        except ValueError:
            out.append(re.sub(r"\d+(\.\d+)? ?(ms|s)\b", "T", line))
            continue

        def drop(x):  # type: ignore[no-untyped-def]
            if isinstance(x, dict):
                return {
                    k: drop(v)
                    for k, v in x.items()
                    if "timing" not in k and not k.endswith("time_s") and k != "seconds"
                }
            if isinstance(x, list):
                return [drop(v) for v in x]
            return x

        out.append(json.dumps(drop(doc), sort_keys=True))
    return "\n".join(out)


# (seed, index, kind): cases whose in-process runs give exit 0, 3, 4, 8 and 11 between them:
# an info table, JSON documents, a warning beside a result, one-line errors, a batch's table,
# written outputs
SAME_BOTH_WAYS = [
    (11, 7, "depth"),
    (11, 0, "depth"),
    (11, 8, "color"),
    (11, 3, "intrinsics"),
    (11, 6, "log"),
    (11, 10, "log"),
    (11, 1, "urdf"),
    (11, 1, "settings"),
    (11, 1, "outputs"),
    (11, 10, "outputs"),
]


@pytest.mark.parametrize("seed,index,kind", SAME_BOTH_WAYS)
def test_in_process_runs_are_what_a_process_gives(
    tmp_path: Path, materials: H.Materials, seed: int, index: int, kind: str
) -> None:
    folder = tmp_path / "case"
    inproc, sub, case = H.compare_with_subprocess(seed, index, kind, materials, folder)
    what = f"{'; '.join(case.recipe)} | {' ; '.join(case.command_lines())}"
    assert inproc.code == sub.code, what
    assert inproc.stderr == sub.stderr, what
    assert _normalised_stdout(inproc.stdout) == _normalised_stdout(sub.stdout), what


def test_the_in_process_runner_catches_exit_codes_streams_and_time(tmp_path: Path) -> None:
    ok = H.run_inprocess(["settings"])
    assert ok.code == 0 and "[segment]" in ok.stdout and ok.stderr == ""
    bad = H.run_inprocess(["segment", str(tmp_path / "missing.pcd")])
    assert bad.code == 3 and bad.stdout == "" and bad.stderr.startswith("clear: error:") and bad.stderr.count("\n") == 1
    usage = H.run_inprocess(["segment", "--no-such-flag"])
    assert usage.code == 2 and "No such option" in usage.stderr
    own = H.run_subprocess(["segment", "--no-such-flag"])
    assert (usage.code, usage.stderr) == (own.code, own.stderr)
    slow = H.run_inprocess(["plan", str(tmp_path / "missing.pcd")], timeout_s=1e-6)
    assert slow.code == "timeout"
    assert H.run_inprocess(["settings"]).code == 0  # and the next run is whole again


def test_cases_are_rebuilt_exactly_from_seed_and_index(tmp_path: Path, materials: H.Materials) -> None:
    for index, kind in enumerate(H.KINDS):
        a = H.build_case(5, index, kind, tmp_path / f"a{index}", materials)
        b = H.build_case(5, index, kind, tmp_path / f"b{index}", materials)
        assert a.recipe == b.recipe and a.tags == b.tags and a.expect == b.expect
        assert [[x.replace(f"/a{index}", f"/b{index}") for x in r] for r in a.runs] == b.runs
        sa, sb = H.snapshot(a.dir), H.snapshot(b.dir)
        assert {k: (e.kind, e.digest) for k, e in sa.items()} == {k: (e.kind, e.digest) for k, e in sb.items()}
        H._unblock_fifos(a.dir)
        H._unblock_fifos(b.dir)


def test_a_png_header_lie_keeps_its_crc_valid() -> None:
    import io
    import zlib

    import numpy as np
    from PIL import Image

    data = H.png_encode(np.arange(12, dtype=np.uint16).reshape(3, 4))
    assert Image.open(io.BytesIO(data)).size == (4, 3)
    big = H.png_set_ihdr(data, width=100000, height=100000)
    kind, body = H.png_chunks(big)[0]
    crc = int.from_bytes(big[8 + 8 + 13 : 8 + 8 + 13 + 4], "big")
    assert kind == b"IHDR" and crc == zlib.crc32(b"IHDR" + body)
    Image.MAX_IMAGE_PIXELS = None
    assert Image.open(io.BytesIO(big)).size == (100000, 100000)  # only the size lies


def test_the_checks_see_a_changed_input_a_left_temporary_and_a_broken_output(tmp_path: Path) -> None:
    case = H.Case(kind="outputs", seed=0, index=0, dir=tmp_path)
    (tmp_path / "in.png").write_bytes(b"input")
    out = tmp_path / "out.png"
    case.outputs.append(H.Output(out, "png"))
    before = H.snapshot(tmp_path)
    (tmp_path / "in.png").write_bytes(b"changed")
    (tmp_path / ".out.png.abcd1234.part").write_bytes(b"half")
    out.write_bytes(b"\x89PNG\r\n\x1a\nhalf a picture")
    run = H.Run(0, "", "", 0.0)
    symptoms = {p.symptom for p in H.check_run(case, ["segment"], run, before, H.snapshot(tmp_path), {})}
    assert {"input-changed", "temporary-left", "output-broken"} <= symptoms
    run = H.Run(3, "", "clear: error: one\nclear: error: two\n", 0.0)
    assert "stderr-lines" in {p.symptom for p in H.check_run(case, ["segment"], run, before, before, {})}
    run = H.Run(1, "", "Traceback (most recent call last):\n  ...\nValueError: x\n", 0.0)
    assert {"exit1", "traceback"} <= {p.symptom for p in H.check_run(case, ["segment"], run, before, before, {})}
    shutil.rmtree(tmp_path)


@pytest.mark.parametrize("suffix", ["a/b", "../up", "_x" * 40])
def test_a_naming_rule_suffix_that_is_no_name_ending_is_a_settings_error(tmp_path: Path, suffix: str) -> None:
    # found by the harness (color cases with [images] color_suffix "a/b": exit 1, ValueError
    # "Invalid name"; 400 characters: exit 8 "cannot write the results to stdout")
    depth = tmp_path / "f_depth.png"
    depth.write_bytes(b"\x89PNG\r\n\x1a\n")
    for key in ("color_suffix", "depth_suffix"):
        run = H.run_inprocess(
            [
                "segment",
                str(depth),
                "--intrinsics",
                "52.5 52.5 31.5 23.5",
                "--set",
                f"images.{key}={json.dumps(suffix)}",
            ]
        )
        assert run.code == 3, run.stderr
        assert run.stderr.count("\n") == 1 and run.stderr.startswith(f"clear: error: settings: [images] {key}")


@pytest.mark.parametrize("cy, code", [("-9223372036854775809", 4), ("-1e300", 3), ("1e12", 4)])
def test_a_principal_point_far_outside_the_image_is_no_table_not_a_crash(
    tmp_path: Path, materials: H.Materials, cy: str, code: int
) -> None:
    # found by the harness (intrinsics "52.5,52.5,31.5,-9223372036854775809": exit 1, "array is
    # too big" in the table's occupancy grid, whose size overflowed int64)
    depth = tmp_path / "f_depth.png"
    depth.write_bytes(materials.depth_bytes("png", H.PLAN))
    fx, fy, cx, _ = materials.frames[H.PLAN].k
    run = H.run_inprocess(["segment", str(depth), "--intrinsics", f"{fx} {fy} {cx} {cy}"])
    # beyond float32's range (-1e300) the intrinsics themselves are refused (exit 3);
    # within it, the frame has no table in view (exit 4)
    assert run.code == code, run.stderr
    assert run.stderr.strip().splitlines()[-1].startswith("clear: error:")
