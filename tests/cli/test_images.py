"""Depth images on the command line: single frames, folders of pairs, `info`, bad flags."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from helpers import run_clear as clear
from helpers import shared_path


def test_a_folder_of_pairs_is_a_batch_named_by_the_pairs_stems(tmp_path: Path) -> None:
    folder = shared_path("rgbd/uois")
    out = tmp_path / "out"
    res = clear("segment", folder, "--json", "--out-dir", out, "--jobs", "2")
    assert res.returncode == 0, res.stderr
    lines = [json.loads(x) for x in res.stdout.splitlines()]
    frames, summary = lines[:-1], lines[-1]
    # nine depth images; the colour images go with them, never frames of their own
    assert [f["name"] for f in frames] == [f"uois_{k:04d}" for k in range(9)]
    assert all(f["source"].endswith("_depth.png") for f in frames) and summary["done"] == 9
    assert sorted(p.name for p in out.glob("*.json")) == [f"uois_{k:04d}.json" for k in range(9)]
    # the same objects as the point clouds of the same frames
    pcds = clear("segment", shared_path("scenes/uois_realsense"), "--json", "--jobs", "2")
    by_pcd = [len(json.loads(x)["document"]["objects"]) for x in pcds.stdout.splitlines()[:-1]]
    assert [len(f["document"]["objects"]) for f in frames] == by_pcd


def test_color_with_several_frames_points_at_the_naming_rule(tmp_path: Path) -> None:
    folder = shared_path("rgbd/uois")
    res = clear("plan", folder, "--color", folder / "uois_0000_color.png")
    assert res.returncode == 3 and "naming rule" in res.stderr and len(res.stderr.strip().splitlines()) == 1


def test_info_says_size_depth_range_intrinsics_and_colour() -> None:
    depth = shared_path("rgbd/uois/uois_0003_depth.png")
    res = clear("info", depth, "--json")
    assert res.returncode == 0, res.stderr
    doc = json.loads(res.stdout)
    image = doc["image"]
    assert doc["format"] == "depth-image" and (image["width"], image["height"]) == (640, 480)
    assert 0.3 < image["depth_min_m"] < image["depth_max_m"] < 5.0
    assert image["intrinsics"]["fx"] == 612.937 and image["color"].endswith("uois_0003_color.png")
    assert doc["frame"]["organized"] and doc["frame"]["has_colors"]


def test_single_frame_flags_intrinsics_color_and_depth_scale(tmp_path: Path) -> None:
    src = shared_path("rgbd/uois")
    depth = tmp_path / "frame.png"  # no naming rule, no intrinsics file beside it
    shutil.copy(src / "uois_0003_depth.png", depth)
    res = clear("segment", depth, "--json")
    assert res.returncode == 3 and "--intrinsics" in res.stderr
    res = clear(
        "segment",
        depth,
        "--json",
        "--intrinsics",
        "612.937 613.173 322.549 248.158",
        "--color",
        src / "uois_0003_color.png",
    )
    assert res.returncode == 0, res.stderr
    want = clear("segment", shared_path("scenes/uois_realsense/uois_image_0003.pcd"), "--json")
    assert json.loads(res.stdout)["objects"] == json.loads(want.stdout)["objects"]
    for bad in (
        ("--intrinsics", "0 613 322 248"),
        ("--intrinsics", "nope.yaml"),
        ("--depth-scale", "0"),
        ("--depth-scale", "nan"),
        ("--depth-scale", "5e-324"),  # before: an internal OverflowError (1 / scale is inf)
    ):
        res = clear("segment", depth, *bad)
        assert res.returncode == 3 and len(res.stderr.strip().splitlines()) == 1, (bad, res.stderr)
    res = clear(
        "segment", shared_path("scenes/uois_realsense/uois_image_0003.pcd"), "--color", src / "uois_0003_color.png"
    )
    assert res.returncode == 3 and "only a depth image takes a colour image" in res.stderr


def test_plan_and_replay_read_the_rgbd_recording() -> None:
    log = shared_path("rgbd/uois_realsense_ros2.mcap")
    res = clear("plan", log, "--frame", "3", "--json")
    want = clear("plan", shared_path("scenes/uois_realsense/uois_image_0003.pcd"), "--json")
    assert res.returncode == want.returncode, res.stderr
    got, expected = json.loads(res.stdout), json.loads(want.stdout)
    assert got["actions"] == expected["actions"] and got["left"] == expected["left"]
    res = clear("replay", log, "--json")
    assert res.returncode == 0, res.stderr
    lines = [json.loads(x) for x in res.stdout.splitlines()]
    assert lines[-1]["frames"] == 9 and len(lines) == 10
    res = clear("info", log, "--json")
    streams = json.loads(res.stdout)["mcap"]["image_streams"]
    assert {(s["encoding"], s["depth"]) for s in streams} == {("16UC1", True), ("rgb8", False)}


def test_bad_colour_is_geometry_alone_and_said_so(tmp_path: Path) -> None:
    # colour of another size, all black, all saturated, none: segmentation runs on the
    # depth alone (no flat objects found by colour), exit 0, no traceback, and --json
    # says why colour was not used
    import numpy as np
    from PIL import Image

    src = shared_path("rgbd/uois")
    shutil.copy(src / "uois_0006_depth.png", tmp_path / "f_depth.png")
    shutil.copy(src / "camera_params.json", tmp_path / "camera_params.json")
    good = Image.open(src / "uois_0006_color.png")
    cases = {
        "none": None,
        "size": good.resize((320, 240)),
        "black": Image.fromarray(np.zeros((480, 640, 3), np.uint8)),
        "saturated": Image.fromarray(np.full((480, 640, 3), 255, np.uint8)),
    }
    docs, errs = {}, {}
    for case, image in cases.items():
        colour = tmp_path / "f_color.png"
        colour.unlink(missing_ok=True)
        if image is not None:
            image.save(colour)
        res = clear("segment", tmp_path / "f_depth.png", "--json")
        assert res.returncode == 0 and "Traceback" not in res.stderr, (case, res.stderr)
        docs[case], errs[case] = json.loads(res.stdout), res.stderr
        assert docs[case]["color"]["used"] is False, case
    assert "no colour" in docs["none"]["color"]["note"]
    # the size mismatch is also a warning on stderr, one line
    assert "320 x 240" in docs["size"]["color"]["note"] and "320 x 240" in errs["size"]
    assert "all black" in docs["black"]["color"]["note"]
    assert "saturated" in docs["saturated"]["color"]["note"]
    # geometry alone: the same objects whatever the bad colour was
    assert len({len(d["objects"]) for d in docs.values()}) == 1
    # and with the good colour, colour is read: the two flat markers of this frame (the
    # black one, and the green one lying against a container: flat.py, 2.) are two more
    # objects, and two strips of depth smeared over the table beside objects are seen to
    # have the table's colour, excluded as fringes (with their reason)
    good.save(tmp_path / "f_color.png")
    res = clear("segment", tmp_path / "f_depth.png", "--json")
    doc = json.loads(res.stdout)
    fringes = [e for e in doc["excluded"] if e["reason"].startswith("a fringe of the support's colour")]
    assert not any(e["reason"].startswith("a fringe") for e in docs["none"]["excluded"])
    assert doc["color"]["used"] is True and len(fringes) == 2
    # ... and the LCCP colour cue (lccp.py) parts one pair of touching objects of
    # different colours that geometry alone joins (the R2-D2 tin from its neighbour)
    assert len(doc["objects"]) == len(docs["none"]["objects"]) + 2 - 2 + 1
