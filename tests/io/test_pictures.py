"""The thinned series of a picture (ruledrobot.io.pictures): every kept point is a
sample, in time order, with each bucket's first, last, lowest and highest kept, so the
line crosses the same pixels."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ruledrobot.io.pictures import thinned_series


@settings(max_examples=40, deadline=None)
@given(n=st.integers(2, 40_000), j=st.integers(1, 4), buckets=st.integers(1, 500),
       seed=st.integers(0, 2**32 - 1))  # fmt: skip
def test_kept_points_are_samples_in_order_with_every_extreme(n, j, buckets, seed):
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.001, 0.01, n))
    y = np.cumsum(rng.normal(size=(n, j)), axis=0)
    tk, yk = thinned_series(t, y, buckets)
    if tk.ndim == 1:  # short enough: the input itself
        assert tk is t or np.array_equal(tk, t)
        assert np.array_equal(yk, y)
        return
    assert len(tk) <= 4 * buckets + 4
    for c in range(j):
        i = np.searchsorted(t, tk[:, c])
        assert np.array_equal(t[i], tk[:, c]) and np.array_equal(y[i, c], yk[:, c])
        assert np.all(np.diff(i) >= 0)
        assert i[0] == 0 and i[-1] == n - 1
        size = -(-n // buckets)
        for b0 in range(0, n, size):  # each bucket's extremes are kept
            seg = y[b0 : b0 + size, c]
            kept = yk[(i >= b0) & (i < b0 + size), c]
            assert kept.min() == seg.min() and kept.max() == seg.max()


def test_one_series_stays_one_dimensional_and_gaps_stay():
    t = np.linspace(0.0, 1.0, 50_000)
    y = np.sin(40 * t)
    tk, yk = thinned_series(t, y)
    assert tk.ndim == yk.ndim == 1 and len(tk) < 13_000
    assert yk.max() == y.max() and yk.min() == y.min()
    y[100] = np.nan
    assert thinned_series(t, y)[1] is not None and len(thinned_series(t, y)[0]) == len(t)


def test_write_png_keeps_the_figures_pixels(tmp_path):
    """The PNG (compressed at PNG_COMPRESS_LEVEL, lossless) holds the pixels Agg drew."""
    pytest.importorskip("matplotlib")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from PIL import Image

    from ruledrobot.io.pictures import write_png

    fig = Figure(figsize=(2, 1.5), dpi=50)
    FigureCanvasAgg(fig)
    fig.add_subplot().plot([0, 1, 0.3], "r-")
    path = write_png(fig, tmp_path / "f.png")
    fig.canvas.draw()
    drawn = np.asarray(fig.canvas.buffer_rgba())
    with Image.open(path) as im:
        assert im.format == "PNG" and im.size == (100, 75)
        np.testing.assert_array_equal(np.asarray(im.convert("RGBA")), drawn)
