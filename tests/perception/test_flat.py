"""Flat objects' colour test: each distinct colour judged once gives the per-pixel
answer, bit for bit."""

from __future__ import annotations

import numpy as np

from clearcli.perception.flat import _far_from, lab_of


def test_far_from_judges_each_colour_as_every_pixel_would() -> None:
    gen = np.random.default_rng(5)
    # a table's few colours, repeated, and a scatter of others
    palette = gen.integers(0, 256, size=(40, 3), dtype=np.uint8)
    rgb = np.concatenate([palette[gen.integers(0, 40, 20000)], gen.integers(0, 256, size=(3000, 3), dtype=np.uint8)])
    centre = np.median(lab_of(rgb), axis=0)
    for threshold in (5.0, 20.0, 47.5):
        diff = lab_of(rgb) - centre.astype(np.float32)
        want = np.einsum("ij,ij->i", diff, diff) > threshold * threshold
        got = _far_from(rgb, centre, threshold)
        assert np.array_equal(got, want)
        assert 0 < got.sum() < got.size


def test_the_rows_filled_as_met_are_the_whole_tables_bit_for_bit() -> None:
    """Issue 39: a cold call converts only the colours it meets (`_lab_rows`); every row,
    met in scattered batches of every size, is the whole table's row."""
    from clearcli.perception.flat import _lab_cache, _lab_rows, _lab_table

    _lab_cache.cache_clear()
    gen = np.random.default_rng(7)
    order = gen.permutation(1 << 18)
    start = 0
    while start < order.size:
        n = int(gen.integers(1, 4000))
        keys = order[start : start + n]
        got = _lab_rows(np.concatenate([keys, keys[: n // 3]]))  # repeats, and met twice
        assert got.shape == (keys.size + n // 3, 3)
        start += n
    table, filled = _lab_cache()
    assert filled.all()
    assert np.array_equal(table.view(np.uint32), _lab_table().view(np.uint32))


def test_differing_shares_are_each_groups_own_mean_bit_for_bit() -> None:
    """Issue 39: every object's off-colour share from one `_far_from` over all their
    pixels is ``differs_from(colors[group]).mean()`` of the group alone, as a float."""
    from clearcli.perception.flat import differing_shares, differs_from

    gen = np.random.default_rng(11)
    palette = gen.integers(0, 256, size=(12, 3), dtype=np.uint8)
    # half the pixels the table's colour, half scattered over the palette
    colors = palette[np.where(gen.random(5000) < 0.5, 0, gen.integers(0, 12, 5000))]
    centre = lab_of(palette[:1])[0]
    # sizes 1 to thousands, a group of one repeated pixel, groups sharing pixels, in any order
    groups = [gen.choice(5000, size=n, replace=False) for n in (1, 2, 3, 7, 333, 4999)]
    groups += [np.full(9, 17), groups[4][::-1].copy()]
    for threshold in (5.0, 20.0):
        got = differing_shares(colors, groups, centre, threshold)
        want = [float(differs_from(colors[g], centre, threshold).mean()) for g in groups]
        assert got == want
        assert all(type(v) is float for v in got)
        assert 0.0 < got[5] < 1.0  # a mixed group, not all or nothing
    assert differing_shares(colors, [], centre, 20.0) == []


def test_support_colour_samples_the_table_pixels_on_the_image_lattice() -> None:
    # 200 x 100 pixels: every 2nd pixel of the image is on the lattice. The table's pixels
    # on it are grey (120, 120, 120), those off it a strong red: the centre is grey's
    # CIELAB, the spread 0 (the threshold the minimum); a table of only off-lattice pixels
    # has no sample but its one lattice pixel
    from clearcli.perception.flat import support_colour

    shape = (200, 100)
    colors = np.zeros((200 * 100, 3), dtype=np.uint8)
    colors[0::2] = (120, 120, 120)
    colors[1::2] = (230, 20, 20)
    table = np.arange(4000, 16000)  # lattice and off-lattice pixels alike
    centre, threshold = support_colour(colors, shape, table, 20.0)
    assert np.array_equal(centre, lab_of(np.array([[120, 120, 120]], dtype=np.uint8))[0])
    assert threshold == 20.0
    odd = np.append(np.arange(4001, 16000, 2), 16000)  # off the lattice, but 16000
    centre, _ = support_colour(colors, shape, odd, 20.0)
    assert np.array_equal(centre, lab_of(np.array([[120, 120, 120]], dtype=np.uint8))[0])
    # unordered pixels: the same sample
    shuffled = np.random.default_rng(2).permutation(table)
    assert np.array_equal(support_colour(colors, shape, shuffled, 20.0)[0], centre)
