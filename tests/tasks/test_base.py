"""Tests of clearcli/tasks/base.py: what every task shares (Source, Outcome, Outputs, the
output files of a batch), and the contract the batch relies on: every frame task's
Request is frozen, plain and picklable, carries its outputs, and names only output kinds
that have a file name."""

from __future__ import annotations

import dataclasses
import pickle
from pathlib import Path

import pytest

from clearcli import tasks
from clearcli.settings import Settings, settings_from_dict
from clearcli.tasks.base import NO_OUTPUTS, OUTPUT_FILES, Outcome, Outputs, Source


def test_a_source_is_a_frozen_frame_reference_with_defaults() -> None:
    s = Source(Path("a.pcd"))
    assert (s.index, s.topic, s.name, s.color) == (0, None, "", None)
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.index = 3  # type: ignore[misc]
    assert Source(Path("a.mcap"), 2, "/points", "a_f2") == Source(Path("a.mcap"), 2, "/points", "a_f2")
    assert pickle.loads(pickle.dumps(s)) == s


def test_an_outcome_defaults_to_success_with_nothing_written() -> None:
    o = Outcome("segmentation", 2, {"objects": []})
    assert (o.exit_code, o.written) == (0, ())
    with pytest.raises(dataclasses.FrozenInstanceError):
        o.exit_code = 5  # type: ignore[misc]


def test_outputs_keep_the_kinds_given_in_order_and_drop_none(tmp_path: Path) -> None:
    out = Outputs.of(labels=tmp_path / "a.labels.pcd", png=None, problem=str(tmp_path / "a.problem.pddl"))
    assert out.paths == (("labels", tmp_path / "a.labels.pcd"), ("problem", tmp_path / "a.problem.pddl"))
    assert isinstance(out.get("problem"), Path)  # a str given becomes a Path
    assert out.get("png") is None and out.get("plan") is None
    assert out.all() == (tmp_path / "a.labels.pcd", tmp_path / "a.problem.pddl")
    assert NO_OUTPUTS.all() == () and NO_OUTPUTS == Outputs() == Outputs.of()
    assert pickle.loads(pickle.dumps(out)) == out


def test_each_output_kind_has_its_own_file_name_carrying_the_frame_name() -> None:
    names = {kind: pattern.format(name="learn3_f2") for kind, pattern in OUTPUT_FILES.items()}
    assert all(n.startswith("learn3_f2.") for n in names.values())
    assert len(set(names.values())) == len(names)  # no two kinds write one file
    assert names["labels"].endswith(".pcd") and names["png"].endswith(".png") and names["plan"].endswith(".plan")
    assert names["problem"].endswith(".pddl") and names["domain"].endswith(".pddl")


def _request(module, settings: Settings):  # type: ignore[no-untyped-def]
    fields = {f.name for f in dataclasses.fields(module.Request)}
    return module.Request(settings=settings) if "settings" in fields else module.Request()


@pytest.mark.parametrize("command", sorted(tasks.TASKS))
def test_every_frame_task_honours_the_batch_contract(command: str, tmp_path: Path) -> None:
    module = tasks.load(command)
    assert module.__name__ == tasks.TASKS[command]
    assert callable(module.run)
    assert dataclasses.is_dataclass(module.Request) and module.Request.__dataclass_params__.frozen
    assert set(module.OUTPUTS) <= set(OUTPUT_FILES)
    settings = settings_from_dict({"robot": {"name": "panda"}, "segment": {"voxel_m": 0.004}})
    request = _request(module, settings)
    # the batch sets each frame's outputs with dataclasses.replace and pickles the request
    given = {kind: tmp_path / OUTPUT_FILES[kind].format(name="f") for kind in module.OUTPUTS}
    framed = dataclasses.replace(request, outputs=Outputs.of(**given))
    assert framed.outputs.all() == tuple(given.values())
    back = pickle.loads(pickle.dumps(framed))
    assert back == framed
    if hasattr(back, "settings") and back.settings is not None:
        assert back.settings.robot.name == "panda" and back.settings.segment.voxel_m == 0.004


def test_the_closed_loop_requests_are_frozen_and_picklable() -> None:
    from clearcli.tasks import replay, simulate

    settings = Settings()
    for request in (replay.Request(settings, every=2, from_s=0.5), simulate.Request(settings, scene="box_on_box")):
        assert pickle.loads(pickle.dumps(request)) == request
        with pytest.raises(dataclasses.FrozenInstanceError):
            request.settings = settings  # type: ignore[misc]
