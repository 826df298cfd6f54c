"""Resampling against numpy's interp and against cubics that Hermite reproduces exactly."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ruledrobot.geometry.interp import interp_hermite, interp_linear


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(2, 40), m=st.integers(1, 60))
def test_linear_equals_numpy_interp_per_column(seed, n, m):
    rng = np.random.default_rng(seed)
    xp = np.sort(rng.uniform(-3, 3, n)) + np.arange(n) * 1e-3
    fp = rng.normal(size=(n, 4))
    x = rng.uniform(-4, 4, m)
    got = interp_linear(x, xp, fp)
    want = np.stack([np.interp(x, xp, fp[:, j]) for j in range(4)], axis=1)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(interp_linear(xp, xp, fp), fp)  # exact on the samples


def test_linear_keeps_trailing_shapes():
    xp = np.array([0.0, 1.0, 2.0])
    fp = np.arange(3 * 2 * 3, dtype=float).reshape(3, 2, 3)
    out = interp_linear([0.5, 1.5], xp, fp)
    np.testing.assert_allclose(out, 0.5 * (fp[:-1] + fp[1:]))


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000))
def test_hermite_reproduces_cubics_and_their_slopes(seed):
    rng = np.random.default_rng(seed)
    c = rng.normal(size=(4, 3))
    xp = np.sort(rng.uniform(0, 2, 7)) + np.arange(7) * 0.05
    f = lambda x: c[0] + np.outer(x, c[1]) + np.outer(x**2, c[2]) + np.outer(x**3, c[3])  # noqa: E731
    df = lambda x: c[1] + np.outer(2 * x, c[2]) + np.outer(3 * x**2, c[3])  # noqa: E731
    x = rng.uniform(xp[0], xp[-1], 50)
    v, d = interp_hermite(x, xp, f(xp), df(xp))
    np.testing.assert_allclose(v, f(x), atol=1e-11)
    np.testing.assert_allclose(d, df(x), atol=1e-10)
