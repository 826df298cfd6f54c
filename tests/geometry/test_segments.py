"""Segment-segment distance against brute force and closed cases."""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.geometry.segments import segment_distance


def test_against_dense_sampling(rng):
    P = rng.normal(size=(300, 4, 3))
    P[:20, 1] = P[:20, 0]  # first segment a point
    P[20:40, 3] = P[20:40, 2]  # second a point
    P[40:60, 3] = P[40:60, 2] + (P[40:60, 1] - P[40:60, 0])  # parallel
    d = segment_distance(P[:, 0], P[:, 1], P[:, 2], P[:, 3])
    u = np.linspace(0.0, 1.0, 161)
    a = P[:, None, 0] + u[None, :, None] * (P[:, None, 1] - P[:, None, 0])
    b = P[:, None, 2] + u[None, :, None] * (P[:, None, 3] - P[:, None, 2])
    brute = np.linalg.norm(a[:, :, None] - b[:, None, :], axis=-1).min(axis=(1, 2))
    assert np.all(d <= brute + 1e-12)
    span = np.linalg.norm(P[:, 1] - P[:, 0], axis=1) + np.linalg.norm(P[:, 3] - P[:, 2], axis=1)
    assert np.all(brute - d <= span / 160 + 1e-9)


@pytest.mark.parametrize(
    ("seg", "expected"),
    [
        (([0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, 1, 0]), 1.0),
        (([0.5, 1, 0], [0.5, 1, 0], [0, 0, 0], [1, 0, 0]), 1.0),
        (([0, 0, 0], [1, 0, 0], [0.5, -1, 2], [0.5, 1, 2]), 2.0),
        (([0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]), 1.0),
        (([0, 0, 0], [0, 0, 0], [0, 3, 4], [0, 3, 4]), 5.0),
    ],
)
def test_closed_cases(seg, expected):
    assert segment_distance(*seg) == pytest.approx(expected, abs=1e-15)
