"""`clear segment` on the command line, as a user or a script runs it."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from helpers import run_clear_as_user
from helpers.segment import box_frame  # noqa: F401  (fixtures)
from helpers.segment_bad_input import (
    LOW_AREA_M2,
    SPANNING,
    S,
    _tiny_scene,
    _two_boxes,
    _unorganized,
)

from clearcli.errors import EXIT_OK
from clearcli.io.frames import Frame
from clearcli.io.pcd import write_pcd
from clearcli.io.read import read_frame
from clearcli.perception.segment import segment
from clearcli.sim.camera import render


# ------------------------------------------------------------------ CLI
def test_cli_segment_json_labels_png_and_evaluate(tmp_path, box_frame: Frame) -> None:  # type: ignore[no-untyped-def]
    from typer.testing import CliRunner

    from clearcli.cli import app
    from clearcli.io.pcd import write_pcd
    from clearcli.io.read import read_frame

    src = tmp_path / "box.pcd"
    write_pcd(src, box_frame)  # keeps the ground-truth labels as `label`
    out = tmp_path / "labels.pcd"
    png = tmp_path / "seg.png"
    runner = CliRunner()
    res = runner.invoke(app, ["segment", str(src), "--json", "-o", str(out), "--png", str(png)])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout.strip().splitlines()[-1])
    assert doc["schema"] == "clear.segmentation" and doc["version"] == 3
    assert len(doc["objects"]) == 1
    o = doc["objects"][0]
    assert (o["id"], o["label"]) == (0, 10)
    assert sorted(o["obb"]["extents"][:2]) == pytest.approx([0.04, 0.05], abs=0.01)
    assert len(doc["table"]["normal"]) == 3 and len(doc["table"]["polygon"]) >= 3
    assert png.stat().st_size > 10_000
    written = read_frame(out)
    assert written.shape == box_frame.shape
    assert set(np.unique(written.fields["label"]).tolist()) == {0, 1, 10}
    # scoring the written labels against the truth
    res = runner.invoke(app, ["evaluate", "segmentation", str(out), str(src), "--json"])
    assert res.exit_code == 0, res.output
    ev = json.loads(res.stdout.strip().splitlines()[-1])
    assert ev["f1"] == 1.0 and ev["n_true"] == 1
    # settings flags override
    res = runner.invoke(app, ["segment", str(src), "--json", "--min-object-area-m2", "0.05"])
    assert res.exit_code == 0 and json.loads(res.stdout.strip().splitlines()[-1])["objects"] == []


def test_cli_segment_errors_exit_codes(tmp_path, box_frame: Frame) -> None:  # type: ignore[no-untyped-def]
    from clearcli.io.pcd import write_pcd

    src = tmp_path / "nan.pcd"
    write_pcd(src, Frame(points=np.full((480 * 640, 3), np.nan, np.float32), shape=(480, 640)))
    res = _clear("segment", str(src))
    assert res.returncode == 4, res.stderr
    assert "Traceback" not in res.stderr and "no finite points" in res.stderr
    box = tmp_path / "box.pcd"
    write_pcd(box, box_frame)
    out = tmp_path / "l.pcd"
    out.write_bytes(b"x")
    res = _clear("segment", str(box), "-o", str(out))
    assert res.returncode == 8 and out.read_bytes() == b"x"


def _clear(*args: str) -> subprocess.CompletedProcess[str]:
    return run_clear_as_user(*args, timeout=120)


def _json(res: subprocess.CompletedProcess[str]) -> dict[str, Any]:
    return json.loads(res.stdout.strip().splitlines()[-1])


def test_cli_tiny_objects(tmp_path: Path) -> None:
    tiny = render(_tiny_scene(), seed=0)
    src = tmp_path / "tiny.pcd"
    write_pcd(src, tiny)
    res = _clear("segment", str(src), "--json")
    assert res.returncode == EXIT_OK, res.stderr
    assert len(_json(res)["objects"]) == len(segment(tiny, S).objects) >= 1
    res = _clear("segment", str(src), "--json", "--min-object-area-m2", str(LOW_AREA_M2))
    assert res.returncode == EXIT_OK and len(_json(res)["objects"]) == 5, res.stderr


def test_cli_object_as_big_as_the_table(tmp_path: Path) -> None:
    scene, height = SPANNING["board"]
    board = tmp_path / "board.pcd"
    write_pcd(board, render(scene, seed=0))
    tall_scene, tall_height = SPANNING["tall_box"]
    tall = tmp_path / "tall_unorganized.pcd"
    write_pcd(tall, _unorganized(render(tall_scene, seed=0), 0))
    for path, sc, h in ((board, scene, height), (tall, tall_scene, tall_height)):
        res = _clear("segment", str(path), "--json")
        assert res.returncode == EXIT_OK, res.stderr
        doc = _json(res)
        assert doc["objects"] == []
        up = sc.T_camera_table[:3, 2]
        assert float(np.dot(doc["table"]["normal"], up)) > 0.995
        assert doc["table"]["offset"] == pytest.approx(-(up @ sc.T_camera_table[:3, 3]) - h, abs=0.01)


def test_cli_unorganized_cloud(tmp_path: Path) -> None:
    """Written as a PCD of HEIGHT 1, segmented and scored by the CLI: both objects found."""
    flat = _unorganized(render(_two_boxes(), seed=0), 0)
    src = tmp_path / "flat.pcd"
    write_pcd(src, flat)
    back = read_frame(src)
    assert back.shape is None and back.n_points == flat.n_points
    out = tmp_path / "labels.pcd"
    res = _clear("segment", str(src), "--json", "-o", str(out))
    assert res.returncode == EXIT_OK, res.stderr
    assert len(_json(res)["objects"]) == 2
    res = _clear("evaluate", "segmentation", str(out), str(src), "--json")
    assert res.returncode == EXIT_OK, res.stderr
    ev = _json(res)
    assert (ev["n_true"], ev["true_positives"], ev["f1"]) == (2, 2, 1.0)
