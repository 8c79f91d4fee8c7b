"""Tests of clearcli/perception/exclude.py's per-object work done for all objects at once
(issue 39): the same answers as object by object."""

from __future__ import annotations

import numpy as np

from clearcli.perception import exclude


def test_at_image_border_marks_the_pixels_within_three_of_the_edge() -> None:
    """A 10 x 20 frame: pixels in rows 0-2 and 7-9 or columns 0-2 and 17-19 are at the
    border, each object's own split back in its order; an object of no pixels has none."""
    shape = (10, 20)
    a = np.array([0 * 20 + 5, 3 * 20 + 3, 3 * 20 + 2, 6 * 20 + 16, 7 * 20 + 10])
    b = np.array([5 * 20 + 17, 5 * 20 + 16, 2 * 20 + 19])
    empty = np.zeros(0, dtype=np.int64)
    out = exclude.at_image_border([a, empty, b], shape)
    assert out is not None and len(out) == 3
    assert out[0].tolist() == [True, False, True, False, True]
    assert out[1].tolist() == []
    assert out[2].tolist() == [True, False, True]
    assert exclude.at_image_border([a], None) is None
    assert exclude.at_image_border([], shape) == []


def test_faces_finds_the_thin_footprints_with_their_sizes() -> None:
    """A line of points 0.4 m long along x, 1 cm across in y (uniform: 5th to 95th
    percentile 0.9 cm), 0.2 m of height: a face, its normal along y; a square footprint
    10 cm across: none; the one left out: not looked at."""
    rng = np.random.default_rng(3)
    m = 4001
    line = np.column_stack([np.linspace(-0.2, 0.2, m), rng.permutation(np.linspace(-0.005, 0.005, m))])
    h_line = rng.permutation(np.linspace(0.0, 0.2, m))
    square = rng.uniform(-0.05, 0.05, size=(2000, 2)) + [1.0, 1.0]
    h_square = rng.uniform(0.0, 0.1, size=2000)
    faces = exclude._faces([line, square, line], [h_line, h_square, h_line], [0, 1])
    assert list(faces) == [0]
    mid, normal, thick, length, tall = faces[0]
    assert np.allclose(mid, [0.0, 0.0], atol=1e-12)
    assert abs(abs(float(normal[1])) - 1.0) < 1e-6  # (the shuffles correlate x and y a little)
    assert abs(thick - 0.009) < 1e-4  # the 5th to 95th percentile of a uniform 1 cm
    assert abs(length - 0.384) < 1e-3  # the 2nd to 98th of 0.4 m
    assert abs(tall - 0.192) < 1e-3  # the 2nd to 98th of 0.2 m
    assert exclude._faces([line], [h_line], []) == {}


def test_reached_samples_every_chunk_across_all_the_points() -> None:
    """`_reached` queries every n-th point per chunk: of 1207 points (3 chunks of at most
    512), the 7 within reach come last, at rows 1200-1206, and rows 1200, 1203 and 1206
    fall in the first chunk (rows 0, 3, 6, ...): one query finds 3 of them; the count
    over every chunk is the whole query's (7 and not 8)."""
    from scipy.spatial import cKDTree

    class Counting(cKDTree):  # type: ignore[misc]
        calls = 0

        def query(self, x, *args, **kwargs):  # type: ignore[no-untyped-def]
            Counting.calls += 1
            return super().query(x, *args, **kwargs)

    tree = Counting(np.zeros((1, 3)))
    pts = np.vstack([np.tile([0.05, 0.0, 0.0], (1200, 1)), np.tile([0.0, 0.01, 0.0], (7, 1))])
    assert exclude._reached(tree, pts, 0.015, 3)
    assert Counting.calls == 1
    Counting.calls = 0
    assert exclude._reached(tree, pts, 0.015, 4)
    assert Counting.calls == 2  # rows 1201 and 1204 in the second chunk
    assert exclude._reached(tree, pts, 0.015, 7) and not exclude._reached(tree, pts, 0.015, 8)
