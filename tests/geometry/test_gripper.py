"""Tests of clearcli/geometry/gripper.py."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.geometry import one_box

from clearcli.errors import SettingsError
from clearcli.geometry.gripper import gripper_model, load_gripper_settings
from clearcli.predicates.synthetic import Box
from clearcli.settings import settings_from_dict
from clearcli.settings.geometry import GripperSettings


# ------------------------------------------------------------------------------ gripper
def test_gripper_model_dimensions() -> None:
    g = gripper_model()
    corners = g.boxes(closed=False).corners()
    fingers = corners[:2]
    # inner faces at +/- opening / 2, outer at + thickness; tips at +closing_region / 2
    assert sorted(np.abs(fingers[..., 0]).min(axis=1)) == pytest.approx([0.035, 0.035])
    assert np.abs(fingers[..., 0]).max() == pytest.approx(0.045)
    assert fingers[..., 2].max() == pytest.approx(0.0225)
    assert fingers[..., 2].min() == pytest.approx(0.0225 - 0.06)
    closed = g.boxes(closed=True).corners()[:2]
    assert np.abs(closed[..., 0]).min() == pytest.approx(0.015)
    base = corners[2]
    assert base[:, 2].max() == pytest.approx(0.0225 - 0.06) and base[:, 2].min() == pytest.approx(0.0225 - 0.115)
    mesh = g.mesh(closed=False)
    assert mesh.bounds[1][2] == pytest.approx(0.0225)


def test_gripper_from_toml_file(tmp_path) -> None:
    path = tmp_path / "wide.toml"
    path.write_text("[gripper]\nopening_width_m = 0.12\nfinger_thickness_m = 0.015\n")
    s = load_gripper_settings(path)
    assert s.opening_width_m == 0.12 and s.closing_width_m == GripperSettings().closing_width_m
    g = gripper_model(s)
    assert np.abs(g.boxes(False).corners()[:2, :, 0]).max() == pytest.approx(0.075)
    # top-level keys work too; unknown keys and impossible values do not
    (tmp_path / "flat.toml").write_text("opening_width_m = 0.09\n")
    assert load_gripper_settings(tmp_path / "flat.toml").opening_width_m == 0.09
    (tmp_path / "typo.toml").write_text("[gripper]\nopening_widht_m = 0.09\n")
    with pytest.raises(SettingsError):
        load_gripper_settings(tmp_path / "typo.toml")
    (tmp_path / "bad.toml").write_text("[gripper]\nclosing_width_m = 0.2\n")
    with pytest.raises(SettingsError):
        load_gripper_settings(tmp_path / "bad.toml")


def test_wider_gripper_makes_a_wide_box_graspable() -> None:
    wide = Box((0.0, 0.0), (0.15, 0.09, 0.04))
    state, _ = one_box(wide)
    assert ("ungraspable", "o0") in state.facts
    cfg = settings_from_dict({"gripper": {"opening_width_m": 0.12}})
    state2, _ = one_box(wide, cfg)
    assert ("ungraspable", "o0") not in state2.facts
