"""The pass value type (wirecut.cut.cutpath): its path parameter and ``locate`` against a
linear search, the target frames, feasibility from its motion."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ruledrobot.wirecut.cut.cutpath import CutPath


def _path(m: int, param=None, surface=None, feasible=True) -> CutPath:
    F = np.tile(np.eye(4), (m, 1, 1))
    F[:, 0, 3] = np.arange(m)
    return CutPath(F, SimpleNamespace(feasible=feasible), 0, (0, 0), m,
                   surface_frames=surface, param=param)  # fmt: skip


def test_the_default_parameter_counts_the_rulings():
    cp = _path(5)
    np.testing.assert_array_equal(cp.s, [0.0, 1.0, 2.0, 3.0, 4.0])
    assert cp.s.dtype == np.float64
    p = np.array([0.0, 0.5, 2.0, 2.25, 7.0])
    np.testing.assert_array_equal(_path(5, param=p).s, p)


@settings(max_examples=80, deadline=None)
@given(
    st.lists(st.floats(1e-3, 1.0), min_size=1, max_size=12),
    st.lists(st.floats(-0.5, 1.5), min_size=1, max_size=20),
)
def test_locate_finds_the_interval_and_the_fraction(steps, where):
    p = np.r_[0.0, np.cumsum(steps)]
    cp = _path(len(p), param=p)
    s = np.asarray(where) * p[-1]
    i0, frac = cp.locate(s)
    assert i0.dtype.kind == "i" and ((0 <= i0) & (i0 <= len(p) - 2)).all()
    assert ((0.0 <= frac) & (frac <= 1.0)).all()
    for k, sk in enumerate(s):
        # the ruling before: the last but one ruling at most, with p <= s (the first
        # before the start)
        expect = 0
        for i in range(len(p) - 1):
            if p[i] <= sk:
                expect = i
        assert i0[k] == expect
        back = p[i0[k]] + frac[k] * (p[i0[k] + 1] - p[i0[k]])
        assert np.isclose(back, np.clip(sk, p[0], p[-1]), rtol=0, atol=1e-12)


def test_target_frames_are_the_surface_when_compensated_and_feasible_is_the_motions():
    cp = _path(3)
    assert cp.target_frames is cp.frames
    S = cp.frames.copy()
    S[:, 2, 3] = -0.0004
    comp = _path(3, surface=S, feasible=False)
    assert comp.target_frames is S
    assert cp.feasible and not comp.feasible
