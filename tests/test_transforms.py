"""Tests of clearcli/transforms.py's cross3 (the planes', the objects' and the poses'
cross products): np.cross's floats to the bit, so the speed-up changed no output."""

from __future__ import annotations

import numpy as np

from clearcli.transforms import cross3


def test_cross3_is_numpys_to_the_bit() -> None:
    gen = np.random.default_rng(3)
    a = gen.normal(size=(500, 3)) * 10 ** gen.uniform(-4, 1, size=(500, 1))
    b = gen.normal(size=(500, 3))
    assert np.array_equal(cross3(a, b), np.cross(a, b))  # rows of vectors
    for k in range(50):  # one vector
        assert np.array_equal(cross3(a[k], b[k]), np.cross(a[k], b[k]))
    # by hand: x cross y = z, y cross z = x
    assert cross3(np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])).tolist() == [0.0, 0.0, 1.0]
    assert cross3(np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])).tolist() == [1.0, 0.0, 0.0]
