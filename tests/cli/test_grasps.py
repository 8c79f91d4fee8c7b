"""`--grasps` on the command line: the kinds the planner may use, checked before any
frame is read."""

from __future__ import annotations

import json

from helpers import run_clear as clear


def test_a_bad_grasps_list_is_one_line_and_exit_3() -> None:
    for bad in ("bowl", "rim", "pinch,,lid", ""):
        res = clear("plan", "fixtures/clutter10.pcd", "--grasps", bad)
        assert res.returncode == 3, (bad, res.stderr)
        assert len(res.stderr.strip().splitlines()) == 1 and "Traceback" not in res.stderr
        assert "grasps" in res.stderr


def test_kinds_in_any_order() -> None:
    res = clear("plan", "fixtures/clutter10.pcd", "--grasps", "slide, pinch", "--json")
    # 10: a partial plan (clutter10's touching pair is one segment, too wide to grasp)
    assert res.returncode in (0, 10), res.stderr
    assert json.loads(res.stdout)["steps"]


def test_pinch_only_names_every_grasp_a_pinch() -> None:
    res = clear("plan", "fixtures/clutter10.pcd", "--grasps", "pinch", "--json")
    assert res.returncode in (0, 10), res.stderr
    doc = json.loads(res.stdout)
    grasps = [s for s in doc["steps"] if s["kind"] == "grasp"]
    assert grasps and all(s["grasp_kind"] == "pinch" for s in grasps)
    assert all(s["grasp_kind"] is None for s in doc["steps"] if s["kind"] == "push")


def test_plan_files_with_a_rim_grasp_validate_and_pinch_only_files_are_the_thesis_model(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from helpers.validate import plan_files, validate_files, validate_files_second

    from clearcli.io.pcd import write_pcd
    from clearcli.sim import scene as S
    from clearcli.sim.camera import render

    bowl = S.Cylinder(0, 0.07, 0.06, -0.10, 0.05, wall_m=0.005)
    box = S.Box(1, 0.04, 0.04, 0.06, 0.15, -0.10)
    pcd = tmp_path / "bowl.pcd"
    write_pcd(pcd, render(S.make_scene("bowl", [bowl, box]), seed=0))
    for grasps, rim in (("pinch,rim,slide", True), ("pinch", False)):
        out = tmp_path / grasps.replace(",", "_")
        out.mkdir()
        res, files = plan_files(pcd, out, "--robot", "panda", "--grasps", grasps)
        doc = json.loads(res.stdout)
        assert ("(grasp_rim o0)" in doc["actions"] or "(grasp_rim o1)" in doc["actions"]) == rim, doc["actions"]
        assert ("grasp_rim" in files[0].read_text()) == rim
        assert ("rim_graspable" in files[1].read_text()) == rim
        assert doc["unit_cost"] == (not rim)
        if rim:
            assert "(general cost)" in files[2].read_text()
            assert validate_files(*files) and validate_files_second(*files)
        else:
            assert res.returncode == 10 and "(unit cost)" in files[2].read_text()  # the bowl left


def test_predicates_json_tells_every_kind_offered_and_why_not(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from clearcli.io.pcd import write_pcd
    from clearcli.sim import scene as S
    from clearcli.sim.camera import render

    flat = S.Box(0, 0.20, 0.14, 0.03, 0.25, -0.15)
    bowl = S.Cylinder(1, 0.07, 0.06, -0.10, 0.05, wall_m=0.005)
    pcd = tmp_path / "wide.pcd"
    write_pcd(pcd, render(S.make_scene("wide", [flat, bowl]), seed=0))
    res = clear("predicates", str(pcd), "--robot", "panda", "--json")
    assert res.returncode == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["version"] == 2
    by_kind = {k: o for o in doc["objects"] for k in o["grasp_kinds"]}
    slide, rim = by_kind["slide"]["grasp_kinds"]["slide"], by_kind["rim"]["grasp_kinds"]["rim"]
    # the flat box: slid 5 cm to the right edge and 3.5 cm over it; every seen side a candidate
    assert abs(slide["slide_m"] - 0.085) < 0.006 and len(slide["slides"]) >= 2 and slide["grasp_poses"]
    assert abs(rim["wall_m"] - 0.005) < 0.002 and len(rim["grasp_poses"]) >= 1
    assert "closed" in by_kind["slide"]["not_offered"]["rim"]
    assert "(slidable" in " ".join(doc["facts"]) and "(rim_graspable" in " ".join(doc["facts"])
    png = tmp_path / "plan.png"
    res = clear("plan", str(pcd), "--robot", "panda", "--json", "--png", str(png))
    assert res.returncode in (0, 10) and png.stat().st_size > 10000
    kinds = {s["grasp_kind"] for s in json.loads(res.stdout)["steps"] if s["kind"] == "grasp"}
    assert kinds == {"rim", "slide"}, kinds
