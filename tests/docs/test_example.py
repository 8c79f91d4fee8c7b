"""The Python API's worked example (docs/examples/first_plan.py, shown on docs/api.md)
runs, and prints the objects and the plan `clear plan --json` gives for the same frame."""

from __future__ import annotations

import json
import subprocess
import sys

from tests.helpers import REPO, run_clear

EXAMPLE = REPO / "docs" / "examples" / "first_plan.py"
FRAME = "fixtures/clutter10.pcd"  # the example's default frame


def test_the_example_prints_what_clear_plan_json_says() -> None:
    out = subprocess.run([sys.executable, str(EXAMPLE)], capture_output=True, text=True, cwd=REPO, timeout=600)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    cli = run_clear("plan", FRAME, "--json")
    doc = json.loads(cli.stdout)
    n_objects = len(doc["goal"]) + len(doc["left"])  # every object is removed or left
    assert lines[0].startswith(f"{n_objects} objects on a table of ")
    assert len([x for x in lines if x.startswith("  object ")]) == n_objects
    assert f"plan: {doc['status']}, {len(doc['actions'])} actions" in lines
    steps = [x.split(". ", 1)[1] for x in lines if x.startswith("  ") and x.strip()[:1].isdigit()]
    assert steps == doc["actions"]
    assert [x.removeprefix("  left: ") for x in lines if x.startswith("  left: ")] == [x["object"] for x in doc["left"]]
    shown = [list(map(float, x.strip(" []").split())) for x in lines[-4:]]
    assert shown == [[round(v, 3) + 0.0 for v in row] for row in doc["T_base_camera"]]
