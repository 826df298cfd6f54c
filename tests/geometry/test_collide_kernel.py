"""The compiled clearance kernels against their numpy formulas (the oracles).

:func:`ruledrobot.geometry._collide_kernel.pairs_within` decides, per configuration and
group, whether a pair of capsules is nearer than its reach; the oracle computes every
pair's distance with :func:`ruledrobot.geometry.segments.segment_distance` (tested
against dense sampling in test_segments.py) and no broad phase.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ruledrobot.geometry._collide_kernel import pairs_within, segment_distance
from ruledrobot.geometry.box import Box
from ruledrobot.geometry.segments import segment_distance as segment_distance_numpy
from tests.conftest import random_rotations


def _segments(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 4, 3) random segment pairs with points, parallels and touching ends mixed in."""
    P = rng.normal(size=(n, 4, 3))
    k = n // 6
    P[:k, 1] = P[:k, 0]  # first a point
    P[k:2 * k, 3] = P[k:2 * k, 2]  # second a point
    par = slice(2 * k, 3 * k)
    P[par, 3] = P[par, 2] + 0.7 * (P[par, 1] - P[par, 0])  # parallel
    P[3 * k:4 * k, 2] = P[3 * k:4 * k, 1]  # touching ends
    return P


def test_one_pair_distance_is_the_numpy_paths():
    P = _segments(np.random.default_rng(7), 600)
    want = segment_distance_numpy(P[:, 0], P[:, 1], P[:, 2], P[:, 3])
    got = np.array([segment_distance(*p) for p in P])
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 60), C=st.integers(2, 9),
       scale=st.floats(0.05, 2.0))
def test_pairs_within_is_the_brute_force_answer(seed: int, n: int, C: int, scale: float):
    rng = np.random.default_rng(seed)
    E = np.ascontiguousarray(rng.normal(size=(n, C, 2, 3)))
    E[:, 0, 1] = E[:, 0, 0]  # a point capsule
    I, J = np.triu_indices(C, 1)
    I, J = I.astype(np.int64), J.astype(np.int64)
    reach = rng.uniform(0.0, scale, size=len(I))
    group = rng.random(len(I)) < 0.5
    half = 0.5 * np.linalg.norm(E[0, :, 1] - E[0, :, 0], axis=-1)
    # rigid capsules (the kernel's broad phase assumes each keeps its length): rebuild
    # every configuration's capsules with the first's lengths about random centres
    d = rng.normal(size=(n, C, 3))
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    c = rng.normal(size=(n, C, 3))
    E = np.ascontiguousarray(np.stack([c - half[None, :, None] * d, c + half[None, :, None] * d],
                                      axis=2))  # fmt: skip
    out = np.zeros((n, 2), dtype=bool)
    pairs_within(E, I, J, reach, half, group, out)
    dist = segment_distance_numpy(E[:, I, 0], E[:, I, 1], E[:, J, 0], E[:, J, 1])  # (n, P)
    hit = dist < reach
    want = np.stack([hit[:, ~group].any(axis=1), hit[:, group].any(axis=1)], axis=1)
    np.testing.assert_array_equal(out, want)


def _segment_hits_numpy(box: Box, a: np.ndarray, b: np.ndarray, margin) -> np.ndarray:
    """The numpy formula: :meth:`Box.clip_lines`' chord met by [0, 1], or the point inside."""
    d = b - a
    point = np.all(d == 0.0, axis=-1)
    t_in, t_out, hit = box.clip_lines(a, np.where(point[..., None], 1.0, d), margin)
    return np.where(point, box.contains(a, margin), hit & (t_out >= 0.0) & (t_in <= 1.0))


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 40), S=st.integers(1, 6))
def test_segment_hits_is_the_slab_formula(seed: int, n: int, S: int):
    rng = np.random.default_rng(seed)
    box = Box(rng.normal(size=3) * 0.1, rng.uniform(0.05, 0.3, size=3),
              random_rotations(rng, 1)[0])  # fmt: skip
    a = box.centre + rng.normal(size=(n, S, 3)) * 0.2
    b = a + rng.normal(size=(n, S, 3)) * 0.2
    b[:, 0] = a[:, 0]  # point segments
    b[: n // 2, -1] = a[: n // 2, -1] + np.array([0.3, 0.0, 0.0]) @ box.rotation.T  # along an axis
    margin = rng.uniform(-0.01, 0.02, size=(S, 1))
    np.testing.assert_array_equal(box.segment_hits(a, b, margin),
                                  _segment_hits_numpy(box, a, b, margin))  # fmt: skip
    np.testing.assert_array_equal(box.segment_hits(a, b, 0.01),
                                  _segment_hits_numpy(box, a, b, 0.01))  # fmt: skip
