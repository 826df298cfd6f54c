"""Oriented boxes: containment, line clipping against hand-computed cases, segments."""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.geometry import se3
from ruledrobot.geometry.box import Box


def test_clip_axis_aligned_hand_computed():
    box = Box([0.0, 0.0, 0.0], [2.0, 2.0, 2.0])
    t0, t1, hit = box.clip_lines(
        [[0.0, 0.5, -3.0], [0.0, 5.0, 0.0], [0.2, 0.2, 0.0]],
        [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]],
    )
    np.testing.assert_allclose(t0[:1], [2.0])
    np.testing.assert_allclose(t1[:1], [4.0])
    assert hit.tolist() == [True, False, True]
    assert np.isnan(t0[1]) and np.isnan(t1[1])
    np.testing.assert_allclose([t0[2], t1[2]], [-1.2, 0.8])


def test_clip_rotated_box_matches_box_coordinates(rng):
    R = se3.rotation_about_axis(np.array([1.0, 2.0, 0.5]) / np.linalg.norm([1, 2, 0.5]), 0.7)
    box = Box([0.3, -0.2, 1.0], [0.5, 1.0, 0.3], R)
    o = rng.normal(size=(500, 3))
    d = rng.normal(size=(500, 3))
    t0, t1, hit = box.clip_lines(o, d)
    assert hit.any() and (~hit).any()
    inside = box.contains(o[hit] + t0[hit, None] * d[hit], margin=1e-9)
    assert inside.all() and box.contains(o[hit] + t1[hit, None] * d[hit], margin=1e-9).all()
    mid = o[hit] + 0.5 * (t0[hit] + t1[hit])[:, None] * d[hit]
    assert box.contains(mid).all()
    assert not box.contains(o[hit] + (t1[hit] + 1e-6)[:, None] * d[hit]).any()


def test_segment_hits_and_errors():
    box = Box([0.0, 0.0, 0.0], [1.0, 1.0, 1.0])
    a = np.array([[-2.0, 0.0, 0.0], [-2.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.6, 0.6, 0.6]])
    b = np.array([[2.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.6, 0.6, 0.6]])
    assert box.segment_hits(a, b).tolist() == [True, False, True, False]
    assert box.segment_hits(a[1], b[1], margin=1.6)
    with pytest.raises(ValueError, match=r"box_size\[2\]"):
        Box([0, 0, 0], [1, 1, 0])
    with pytest.raises(ValueError, match="box_rotation"):
        Box([0, 0, 0], [1, 1, 1], np.diag([1.0, 1.0, -1.0]))
