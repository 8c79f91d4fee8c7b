"""`not_standing` (clearcli/perception/exclude.py) over a flat support made by hand: the
plane z = 0 seen everywhere in a 40 cm square, the exclusion tests' common stage."""

from __future__ import annotations

import numpy as np

from clearcli.perception.exclude import not_standing


def flat_support_verdicts(
    objects: list[np.ndarray], outside: np.ndarray | None = None, off_colour: list[float] | None = None
) -> list[str]:
    """ "index: reason" of each object `not_standing` excludes over a support z = 0 seen
    everywhere in a 40 cm square (no outline crossed: every point lies well inside);
    ``outside``: points beyond the support's outline (none by default); ``off_colour``:
    each object's share of pixels off the support's colour (None: not known)."""
    g = np.arange(-0.2, 0.2, 0.005)
    support = np.stack(np.meshgrid(g, g, [0.0]), -1).reshape(-1, 3)
    none = np.zeros((0, 3))
    found = not_standing(
        objects,
        none if outside is None else outside,
        none,
        support[:, :2],  # in-plane: the support lies in z = 0
        lambda p: p[:, 2],
        lambda p: p[:, :2],
        lambda p: np.ones(p.shape[0], dtype=bool),
        lambda p: 0.013,
        off_colour=off_colour,
    )
    return [f"{v.index}: {v.reason}" for v in found]
