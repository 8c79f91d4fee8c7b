"""The committed fixtures are what `fixtures/make_fixtures.py` makes, and hold what the
README says they hold."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

from clearcli.errors import InputError
from clearcli.io.frames import Frame
from clearcli.io.read import read_frame
from utils import FIXTURES

PCD_NAMES = ["isolated_box", "two_touching_boxes", "box_on_box", "clutter10"]
SESSION_TOPIC = "/camera/depth_registered/points"
N_SESSION_FRAMES = 4


def _load_script() -> ModuleType:
    spec = importlib.util.spec_from_file_location("make_fixtures", FIXTURES / "make_fixtures.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def regenerated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("fixtures")
    written = _load_script().generate(out)
    assert set(written) == set(PCD_NAMES) | {"session", "simulated_session"}
    return out


def _committed(name: str) -> Path:
    path = FIXTURES / name
    assert path.exists(), f"{path} is missing: run `python fixtures/make_fixtures.py`"
    return path


def _assert_close(committed: Frame, fresh: Frame) -> None:
    assert committed.shape == fresh.shape == (480, 640)
    assert committed.n_points == fresh.n_points
    lab_a = committed.fields["label"].astype(np.int64)
    lab_b = fresh.fields["label"].astype(np.int64)
    values = np.union1d(np.unique(lab_a), np.unique(lab_b))
    for value in values:
        count_a, count_b = int((lab_a == value).sum()), int((lab_b == value).sum())
        assert abs(count_a - count_b) <= 0.01 * max(count_a, count_b), f"label {value}: {count_a} vs {count_b}"
    both = committed.finite_mask & fresh.finite_mask
    assert both.sum() >= 0.99 * max(committed.finite_mask.sum(), fresh.finite_mask.sum())
    np.testing.assert_allclose(committed.points[both], fresh.points[both], atol=0.001, rtol=0)
    assert committed.colors is not None and fresh.colors is not None
    assert np.abs(committed.colors[both].astype(int) - fresh.colors[both].astype(int)).max() <= 2


@pytest.mark.parametrize("name", PCD_NAMES)
def test_pcd_fixture_matches_regeneration(name: str, regenerated: Path) -> None:
    _assert_close(read_frame(_committed(f"{name}.pcd")), read_frame(regenerated / f"{name}.pcd"))


def test_session_fixture_matches_regeneration(regenerated: Path) -> None:
    for i in range(N_SESSION_FRAMES):
        committed = read_frame(_committed("session.mcap"), SESSION_TOPIC, i)
        fresh = read_frame(regenerated / "session.mcap", SESSION_TOPIC, i)
        _assert_close(committed, fresh)
        assert committed.stamp_s == pytest.approx(fresh.stamp_s, abs=1e-6)


def test_simulated_session_fixture_matches_regeneration(regenerated: Path) -> None:
    from clearcli.io.read import iter_frames

    committed = list(iter_frames(_committed("simulated_session.mcap")))
    fresh = list(iter_frames(regenerated / "simulated_session.mcap"))
    assert len(committed) == len(fresh) >= 3
    for a, b in zip(committed, fresh):
        _assert_close(a, b)
    # and the robot's place (/tf_static), which the placement rule decides
    from clearcli.io.tf import read_transforms

    tf_committed = read_transforms(_committed("simulated_session.mcap"))
    tf_fresh = read_transforms(regenerated / "simulated_session.mcap")
    assert tf_committed.keys() == tf_fresh.keys() and tf_committed
    for key in tf_committed:
        np.testing.assert_allclose(tf_committed[key], tf_fresh[key], atol=1e-6)


# ---- what the README promises ---------------------------------------------------------


@pytest.mark.parametrize(
    "name, labels",
    [
        ("isolated_box", {0, 1, 10}),
        ("two_touching_boxes", {0, 1, 10, 20}),
        ("box_on_box", {0, 1, 10, 20}),
        ("clutter10", {0, 1} | {10 * k for k in range(1, 11)}),
    ],
)
def test_pcd_fixture_contents(name: str, labels: set[int]) -> None:
    frame = read_frame(_committed(f"{name}.pcd"))
    assert frame.shape == (480, 640)
    label = frame.fields["label"]
    assert set(np.unique(label).tolist()) == labels
    assert (label[~frame.finite_mask] == 0).all()
    assert (frame.fields["label"] == 1).sum() > 80_000  # the table fills a third of the image
    assert _committed(f"{name}.pcd").stat().st_size < 2_000_000


def test_session_fixture_contents() -> None:
    path = _committed("session.mcap")
    frames = [read_frame(path, SESSION_TOPIC, i) for i in range(N_SESSION_FRAMES)]
    with pytest.raises(InputError):
        read_frame(path, SESSION_TOPIC, N_SESSION_FRAMES)
    stamps = np.array([f.stamp_s for f in frames])
    np.testing.assert_allclose(np.diff(stamps), 0.5, atol=1e-6)
    labels = [set(np.unique(f.fields["label"]).tolist()) for f in frames]
    everything = {0, 1} | {10 * k for k in range(1, 11)}
    assert labels[0] == labels[1] == everything
    assert labels[2] == everything - {70}  # object 6 picked
    assert labels[3] == everything - {70, 30}  # then object 2
    # Frame 1: object 6 (label 70) was pushed 4 cm; its points' centroid moved about that.
    moved = [f.points[f.fields["label"] == 70].astype(float).mean(axis=0) for f in frames[:2]]
    assert 0.025 < np.linalg.norm(moved[1] - moved[0]) < 0.055
    # Objects that did not move stay put between frames (only noise differs).
    still = [f.points[f.fields["label"] == 10].astype(float).mean(axis=0) for f in frames]
    assert max(np.linalg.norm(s - still[0]) for s in still) < 0.002
    assert path.stat().st_size < 4_000_000


def test_fixtures_stay_small() -> None:
    total = sum(p.stat().st_size for p in FIXTURES.iterdir() if p.is_file())
    assert total < 15_000_000
