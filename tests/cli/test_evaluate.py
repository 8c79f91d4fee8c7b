"""`clear evaluate` on the command line, as a user or a script runs it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import shared_path
from helpers.batch import clear, lines_of
from helpers.evaluate import _labels


def test_evaluate_dataset_on_the_given_mosd_frames(tmp_path: Path) -> None:
    mosd = shared_path("mosd")
    res = clear(
        "evaluate",
        "dataset",
        mosd,
        "--groups",
        "mosd",
        "--json",
        "--jobs",
        "2",
        "--csv",
        tmp_path / "scores.csv",
        "--png",
        tmp_path / "f1.png",
    )
    assert res.returncode == 0, res.stderr
    rows, summary = lines_of(res.stdout)
    assert len(rows) == 50 and summary["failed"] == 0
    docs = [r["document"] for r in rows]
    assert all(d["schema"] == "clear.evaluate.frame" for d in docs)
    ev = summary["evaluation"]
    assert ev["all"]["frames"] == 50 and ev["all"]["mean_f1"] >= 0.95
    assert {g: m["frames"] for g, m in ev["groups"].items()} == {
        "boxes": 17,
        "stacked": 8,
        "occluded": 8,
        "cylindrical": 12,
        "mixed (test)": 3,
        "complex (test)": 2,
    }
    assert len((tmp_path / "scores.csv").read_text().splitlines()) == 51
    assert (tmp_path / "f1.png").read_bytes()[:4] == b"\x89PNG"
    # a frame's score equals `segment -o` + `evaluate segmentation` on it
    frame = mosd / "test" / "test57.pcd"
    labels = tmp_path / "test57.labels.pcd"
    assert clear("segment", frame, "-o", labels).returncode == 0
    single = json.loads(clear("evaluate", "segmentation", labels, frame, "--json").stdout)
    doc = next(d for d in docs if d["source"].endswith("test57.pcd"))
    for key in ("n_true", "n_pred", "true_positives", "precision", "recall", "f1", "mean_best_iou"):
        assert doc[key] == single[key], key
    # --pred: the label files of a batch's --out-dir, scored without segmenting
    out = tmp_path / "labels"
    assert clear("segment", mosd / "test", "--out-dir", out, "--outputs", "labels", "--json").returncode == 0
    pred = clear("evaluate", "dataset", mosd / "test", "--pred", out, "--json")
    prow, psummary = lines_of(pred.stdout)
    assert [r["document"]["f1"] for r in prow] == [d["f1"] for d in docs if "/test/" in d["source"]]
    assert all(r["document"]["time_s"] == 0 for r in prow)


def _clear(*args: str) -> subprocess.CompletedProcess[str]:
    exe = Path(sys.executable).parent / "clear"
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "clearcli.cli"]
    return subprocess.run([*cmd, *args], capture_output=True, text=True, timeout=120)


def test_cli_evaluate_segmentation(tmp_path: Path) -> None:
    from clearcli.io.frames import Frame
    from clearcli.io.pcd import write_pcd

    rng = np.random.default_rng(0)
    pts = rng.normal(size=(40, 3)).astype(np.float32)
    truth = _labels((20, 10), (30, 30))
    pred = _labels((10, 40))
    write_pcd(tmp_path / "t.pcd", Frame(points=pts), truth)
    write_pcd(tmp_path / "p.pcd", Frame(points=pts), pred)
    res = _clear("evaluate", "segmentation", str(tmp_path / "p.pcd"), str(tmp_path / "t.pcd"), "--json")
    assert res.returncode == 0, res.stderr
    doc = json.loads(res.stdout.strip().splitlines()[-1])
    assert doc["schema"] == "clear.evaluate.segmentation" and doc["version"] == 1
    assert doc["f1"] == pytest.approx(2 / 3) and doc["under_segmented"] == 1
    res = _clear("evaluate", "segmentation", str(tmp_path / "p.pcd"), str(tmp_path / "t.pcd"))
    assert res.returncode == 0 and "F1 0.667" in res.stdout
    # different point counts: a bad input, one line
    write_pcd(tmp_path / "short.pcd", Frame(points=pts[:20]), truth[:20])
    res = _clear("evaluate", "segmentation", str(tmp_path / "p.pcd"), str(tmp_path / "short.pcd"))
    assert res.returncode == 3 and "Traceback" not in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    # no label field
    write_pcd(tmp_path / "plain.pcd", Frame(points=pts))
    res = _clear("evaluate", "segmentation", str(tmp_path / "plain.pcd"), str(tmp_path / "t.pcd"))
    assert res.returncode == 3 and "label" in res.stderr


def test_dataset_reports_the_osd_metrics_per_frame_and_in_the_means() -> None:
    import json

    from helpers import run_clear, shared_path

    from clearcli.evaluate.osd import OSD_KEYS

    frames = [shared_path("mosd/test/test57.pcd"), shared_path("mosd/learn/learn0.pcd")]
    res = run_clear("evaluate", "dataset", *frames, "--json", "--jobs", "1")
    assert res.returncode == 0, res.stderr
    lines = [json.loads(x) for x in res.stdout.splitlines()]
    docs, summary = [ln["document"] for ln in lines[:-1]], lines[-1]["evaluation"]["all"]
    assert len(OSD_KEYS) == 7  # Overlap's and Boundary's precision, recall and F; objects_f75
    for d in docs:
        for k in OSD_KEYS:
            assert 0.0 <= d[k] <= 1.0, (k, d[k])  # organized mOSD frames: Boundary too
    assert summary["mean_boundary_f"] == round(sum(d["boundary_f"] for d in docs) / 2, 4)
    assert summary["mean_overlap_f"] == round(sum(d["overlap_f"] for d in docs) / 2, 4)
