"""Tests of clearcli/tasks/predicates.py: the symbolic state of a frame, through the task.

Which object is which comes from the fixtures' ground truth (labels read with pypcd4,
sizes and poses from fixtures/README.md); the facts are checked against the geometry
the README states (who stands on whom, which pushes run into the neighbour)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from helpers import FIXTURES
from helpers.tasks import truth_centroids

from clearcli.errors import InputError
from clearcli.settings import Settings
from clearcli.tasks import predicates as task
from clearcli.tasks.base import Outputs, Source

# fixtures/README.md: the table's x axis (first column of T_camera_table) in the camera frame
TABLE_X = np.array([1.0, 0.0, 0.0])


def _by_label(payload: dict, pcd: Path) -> dict[int, dict]:
    """The payload's objects by the true label of the nearest true object."""
    truth = truth_centroids(pcd)
    found = {}
    for obj in payload["objects"]:
        c = np.asarray(obj["centroid"])
        label = min(truth, key=lambda k: float(np.linalg.norm(truth[k] - c)))
        assert np.linalg.norm(truth[label] - c) < 0.03
        found[label] = obj
    assert len(found) == len(payload["objects"]) == len(truth)
    return found


def _facts(payload: dict) -> set[tuple[str, ...]]:
    return {tuple(f.strip("()").split()) for f in payload["facts"]}


@pytest.mark.parametrize("ground_truth", [False, True])
def test_the_upper_box_is_on_the_lower_one(ground_truth: bool, tmp_path: Path) -> None:
    frame = FIXTURES / "box_on_box.pcd"
    outcome = task.run(task.Request(Settings(), ground_truth=ground_truth), Source(frame))
    assert (outcome.schema, outcome.version, outcome.exit_code) == ("predicates", 2, 0)
    objects = _by_label(outcome.payload, frame)
    lower, upper = objects[10]["name"], objects[20]["name"]
    assert _facts(outcome.payload) == {("on", upper, lower)}
    # fixtures/README.md: the lower box 5 cm tall, the upper 4 cm on top of it: 9 cm
    assert objects[20]["height_m"] == pytest.approx(0.09, abs=0.01)
    assert objects[10]["height_m"] == pytest.approx(0.05, abs=0.015)
    json.dumps(outcome.payload, allow_nan=False)


def test_touching_boxes_block_the_pushes_into_and_away_from_each_other() -> None:
    frame = FIXTURES / "two_touching_boxes.pcd"
    payload = task.run(task.Request(Settings()), Source(frame)).payload
    objects = _by_label(payload, frame)
    tall, short = objects[10], objects[20]  # 10 cm and 6 cm tall, touching along the table's x axis
    assert tall["height_m"] == pytest.approx(0.10, abs=0.01) and short["height_m"] == pytest.approx(0.06, abs=0.01)
    facts = _facts(payload)
    assert not any(f[0] == "on" for f in facts)
    blocked = {(f[1], f[2], f[3]) for f in facts if f[0] == "block_dir"}
    assert blocked
    for obj, other in ((tall, short), (short, tall)):
        for d, vector in obj["directions"].items():
            along_x = abs(float(np.asarray(vector) @ TABLE_X)) > 0.95
            along_y = abs(float(np.asarray(vector) @ TABLE_X)) < 0.3
            assert along_x or along_y  # both boxes are at yaw 0 on the table
            # a push across the touching faces (either way) is blocked by the other box,
            # one along them is not
            assert ((other["name"], obj["name"], d) in blocked) == along_x, (obj["name"], d)
    # the taller neighbour is in the way of the open gripper over the shorter box
    assert ("block_grasp", tall["name"], short["name"]) in facts
    assert ("block_grasp", short["name"], tall["name"]) not in facts


def test_a_lone_box_has_no_facts_and_its_own_size(tmp_path: Path) -> None:
    problem, png = tmp_path / "p.pddl", tmp_path / "p.png"
    outcome = task.run(
        task.Request(Settings(), outputs=Outputs.of(problem=problem, png=png)), Source(FIXTURES / "isolated_box.pcd")
    )
    payload = outcome.payload
    assert payload["facts"] == [] and payload["skipped"] == []
    (box,) = payload["objects"]
    # fixtures/README.md: 5.00 x 4.00 x 8.00 cm; the gripper closes across its narrower side
    assert sorted(box["extents_m"]) == pytest.approx([0.04, 0.05, 0.08], abs=0.006)
    assert box["grasp_width_m"] == pytest.approx(0.04, abs=0.006)
    assert outcome.written == (problem, png)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "(:objects o0 - obj)" in problem.read_text()


def test_the_problem_written_holds_the_facts_and_parses(tmp_path: Path) -> None:
    from clearcli.tasks.domain import domain_text
    from pddl import parse_domain, parse_problem

    problem = tmp_path / "p.pddl"
    outcome = task.run(
        task.Request(Settings(), outputs=Outputs.of(problem=problem)), Source(FIXTURES / "two_touching_boxes.pcd")
    )
    text = problem.read_text()
    init = text[text.index("(:init") : text.index("(:goal")]
    for fact in outcome.payload["facts"]:
        assert fact in init
    assert set(re.findall(r"\(removed (o\d+)\)", text)) == {o["name"] for o in outcome.payload["objects"]}
    domain = tmp_path / "d.pddl"
    domain.write_text(domain_text())
    parse_domain(domain)
    parsed = parse_problem(problem)
    assert {str(o) for o in parsed.objects} >= {"o0", "o1"}


def test_ground_truth_needs_a_label_field(tmp_path: Path) -> None:
    from pypcd4 import PointCloud

    xyz = PointCloud.from_path(FIXTURES / "isolated_box.pcd").numpy(("x", "y", "z"))
    bare = tmp_path / "bare.pcd"
    PointCloud.from_xyz_points(xyz).save(bare)
    with pytest.raises(InputError, match="label"):
        task.run(task.Request(Settings(), ground_truth=True), Source(bare))
