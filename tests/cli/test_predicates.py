"""`clear predicates` on the command line, as a user or a script runs it."""

from __future__ import annotations

import json

import numpy as np
from helpers import shared_path


# ------------------------------------------------------------------------------ CLI
def test_cli_predicates_json_problem_png_and_domain(tmp_path) -> None:
    from typer.testing import CliRunner

    from clearcli.cli import app
    from clearcli.planning.pddl import domain_text

    pcd = shared_path("mosd/learn/learn17.pcd")
    runner = CliRunner()
    out = tmp_path / "p.pddl"
    png = tmp_path / "p.png"
    res = runner.invoke(app, ["predicates", str(pcd), "--ground-truth", "--json", "-o", str(out), "--png", str(png)])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout.strip().splitlines()[-1])
    assert doc["schema"] == "clear.predicates" and doc["version"] == 2
    assert "(on o1 o0)" in doc["facts"]
    obj = doc["objects"][0]
    assert set(obj["directions"]) == {"dir1", "dir2", "dir3", "dir4"}
    assert np.allclose(np.linalg.norm(obj["directions"]["dir1"]), 1.0, atol=1e-5)
    # the two half-turns, then IK fallbacks (another yaw, off-centre grasps)
    assert len(obj["grasp_poses"]) >= 2 and len(obj["grasp_poses"]) % 2 == 0
    assert np.array(obj["grasp_poses"][0]).shape == (4, 4)
    assert "(on o1 o0)" in out.read_text()
    assert png.read_bytes()[:4] == b"\x89PNG"
    # no clobbering without --force
    res2 = runner.invoke(app, ["predicates", str(pcd), "--ground-truth", "-o", str(out)])
    from clearcli.errors import OutputError

    assert isinstance(res2.exception, OutputError)  # main() maps it to exit code 8
    res3 = runner.invoke(app, ["domain"])
    assert res3.exit_code == 0 and res3.stdout == domain_text(kinds=("pinch", "rim", "slide"))
    assert "(:action grasp_rim" in res3.stdout and "(:action slide_grasp" in res3.stdout
    # the thesis's domain alone: the shipped file, pddl/domain.pddl
    res4 = runner.invoke(app, ["domain", "--grasps", "pinch"])
    assert res4.exit_code == 0 and res4.stdout == domain_text() and "grasp_rim" not in res4.stdout
