"""The labelled frames of other labs (benchmarks/foreign/*.toml, read by
benchmarks/foreign.py): a frame segmented with some settings, judged object by object."""

from __future__ import annotations

import functools
import tomllib
from types import ModuleType

from helpers import REPO, load_script, shared_path


@functools.cache
def tool() -> ModuleType:
    """benchmarks/foreign.py as a module (it is a script, not part of the package)."""
    return load_script("benchmarks/foreign.py")


@functools.cache
def labelled(name: str):  # -> (Frame, labels, spec)
    spec = tomllib.loads((REPO / "benchmarks" / "foreign" / f"{name}.toml").read_text(encoding="utf-8"))
    shared_path(spec["source"])  # skips (or fails under CLEAR_REQUIRE_SHARED) without the data
    return tool().load(name)


def judged(name: str, **segment_settings):  # -> (verdict by object name, ExactReport, Segmentation)
    """Segment the labelled frame ``name`` with [segment] values changed as given."""
    from clearcli import pipeline
    from clearcli.evaluate.exact import exact_report
    from clearcli.settings import Settings, override

    frame, truth, spec = labelled(name)
    settings = override(Settings(), "segment", **segment_settings)
    seg = pipeline.segmented(frame, settings)
    report = exact_report(seg.labels(), truth)
    names = [obj["name"] for obj in spec["object"]]
    return dict(zip(names, report.verdicts)), report, seg
