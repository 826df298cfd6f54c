"""S^2 geodesics (slerp with extrapolation), log and exp."""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.geometry import sphere


def test_geodesic_is_constant_speed_great_circle(rng):
    a = rng.normal(size=(100, 3))
    b = rng.normal(size=(100, 3))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    phi = np.arccos(np.clip((a * b).sum(1), -1, 1))
    for t in (-1.0, 0.0, 0.3, 1.0, 2.5):
        g = sphere.geodesic(a, b, t)
        np.testing.assert_allclose(np.linalg.norm(g, axis=1), 1.0, atol=1e-14)
        # in the plane of a and b
        assert np.abs((g * np.cross(a, b)).sum(1)).max() < 1e-12
        np.testing.assert_allclose((g * a).sum(1), np.cos(t * phi), atol=1e-12)
    np.testing.assert_allclose(sphere.geodesic(a, b, 1.0), b, atol=1e-14)
    # slerp formula (paper Eq. 12) on [0, 1]
    t = 0.37
    slerp = (np.sin((1 - t) * phi)[:, None] * a + np.sin(t * phi)[:, None] * b) / np.sin(phi)[
        :, None
    ]
    np.testing.assert_allclose(sphere.geodesic(a, b, t), slerp, atol=1e-12)


def test_identical_points_and_antipodes():
    a = np.array([0.0, 0.0, 1.0])
    np.testing.assert_allclose(sphere.geodesic(a, a, 3.0), a)
    with pytest.raises(ValueError, match="antipodal"):
        sphere.geodesic(a, -a, 0.5)


def test_log_exp_round_trip(rng):
    a = rng.normal(size=(50, 3))
    x = rng.normal(size=(50, 3))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    v = sphere.log(a, x)
    assert np.abs((v * a).sum(1)).max() < 1e-14
    np.testing.assert_allclose(sphere.exp(a, v), x, atol=1e-12)
    np.testing.assert_allclose(sphere.exp(a, 0 * v), a, atol=1e-15)


def test_validate_unit_names_index():
    with pytest.raises(ValueError, match=r"unit vectors\[1\]"):
        sphere.validate_unit([[1, 0, 0], [2, 0, 0]])
