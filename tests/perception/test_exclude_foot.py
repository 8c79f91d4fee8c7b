"""What comes down to the support's level only beyond its outline does not stand on it
(issue 37, perception/exclude.py `_FOOT_INSIDE_SHARE`): a chair's back or a box standing on
the floor just behind the table rises into the prism (which reaches ``hull_margin_m``
beyond the support's outline), and its lowest points lie out there, where the support is
not; an object standing on the support rests on it inside the outline, even where the hull
ends at its foot (the table behind it hidden). Self-made points: a support z = 0 seen over
an 80 x 60 cm table, the prism's side 3 cm beyond its edges (as segment.py's
``hull_margin_m`` less 2 cm)."""

from __future__ import annotations

import numpy as np
import pytest

from clearcli.perception import exclude
from clearcli.perception.exclude import not_standing

HALF_X_M, EDGE_M = 0.4, 0.3  # the support: |x| <= HALF_X_M, |y| <= EDGE_M (its far edge)
SIDE_M = 0.03  # the prism's side this far beyond the support's edges
RESTS_M = 0.013  # resting height (the prism's floor 1 cm plus the noise)


def _face(x0: float, x1: float, y: float, z0: float, z1: float, step: float = 0.004) -> np.ndarray:
    """An upright face along x at ``y``, from ``z0`` to ``z1`` (m) above the support."""
    xs, zs = np.meshgrid(np.arange(x0, x1 + 1e-9, step), np.arange(z0, z1 + 1e-9, step))
    return np.column_stack([xs.ravel(), np.full(xs.size, y), zs.ravel()])


def _box(x0: float, x1: float, y0: float, y1: float, z1: float, step: float = 0.004) -> np.ndarray:
    """A box's top and front face (towards -y) as a camera on the near side sees them,
    standing on the support (its lowest seen points 1.1 cm up: the prism's floor)."""
    xs, ys = np.meshgrid(np.arange(x0, x1 + 1e-9, step), np.arange(y0, y1 + 1e-9, step))
    top = np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, z1)])
    return np.vstack([top, _face(x0, x1, y0, 0.011, z1, step)])


def _verdicts(objects: list[np.ndarray]) -> list[str]:
    gx, gy = np.arange(-HALF_X_M, HALF_X_M + 1e-9, 0.01), np.arange(-EDGE_M, EDGE_M + 1e-9, 0.01)
    support = np.stack(np.meshgrid(gx, gy, [0.0]), -1).reshape(-1, 3)
    none = np.zeros((0, 3))
    found = not_standing(
        objects,
        none,
        none,
        support[:, :2],  # in-plane: the support lies in z = 0
        lambda p: p[:, 2],
        lambda p: p[:, :2],
        lambda p: (np.abs(p[:, 0]) <= HALF_X_M + SIDE_M) & (np.abs(p[:, 1]) <= EDGE_M + SIDE_M),
        lambda p: RESTS_M,
    )
    return [f"{v.index}: {v.reason}" for v in found]


@pytest.mark.parametrize("beyond_m", [0.035, 0.045])
def test_a_board_rising_just_beyond_the_support_is_excluded_the_objects_at_the_edge_kept(
    beyond_m: float, monkeypatch: pytest.MonkeyPatch
) -> None:
    # a chair's back 30 cm wide (too small for a wall: 37 % of the table's edge), its face
    # ``beyond_m`` behind the support's far edge (inside the prism, beyond its side), from
    # the prism's floor to 10 cm above the support
    board = _face(-0.15, 0.15, EDGE_M + beyond_m, 0.011, 0.10)
    # a box standing at the far edge, the hull ending at its foot (its back 4 cm beyond it,
    # the table behind it hidden), and one well inside
    at_edge = _box(-0.10, -0.02, EDGE_M - 0.04, EDGE_M + 0.04, 0.08)
    inside = _box(0.0, 0.08, -0.1, -0.02, 0.06)
    verdicts = _verdicts([at_edge, board, inside])
    assert len(verdicts) == 1, verdicts
    assert verdicts[0].startswith("1: stands beyond the support's edge: it comes down to the support's level only")
    assert "(0 of its " in verdicts[0]  # none of its resting points within the outline
    # the rule off: the board is an object (a plan would try to grasp it)
    monkeypatch.setattr(exclude, "_FOOT_INSIDE_SHARE", -np.inf)
    assert _verdicts([at_edge, board, inside]) == []


def test_an_object_resting_mostly_inside_the_outline_is_kept() -> None:
    # a box straddling the prism's side: its front face (its resting points) 2 cm inside
    # the side, its back beyond it: it rests on the support
    straddling = _box(-0.05, 0.05, EDGE_M + SIDE_M - 0.02, EDGE_M + SIDE_M + 0.02, 0.05)
    assert _verdicts([straddling]) == []
