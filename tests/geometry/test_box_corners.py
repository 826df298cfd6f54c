"""Box.corners and Box.edges: the one home of a block's corners (plots, transits,
placement, scene); Box.moved and Box.grown: a block placed elsewhere, grown by a margin;
Box.signed_distance: the part mesh's distance to the block."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ruledrobot.geometry.box import Box
from ruledrobot.geometry.se3 import pose_from_rotvec

coords = st.floats(-1.0, 1.0, allow_nan=False)
sizes = st.floats(0.01, 2.0, allow_nan=False)


@settings(max_examples=50, deadline=None)
@given(st.tuples(coords, coords, coords), st.tuples(sizes, sizes, sizes),
       st.tuples(coords, coords, coords))
def test_corners_are_on_the_box_and_edges_have_its_lengths(c, s, rv):
    box = Box(np.array(c), np.array(s), pose_from_rotvec(np.array(rv))[:3, :3])
    local = box.to_box(box.corners)
    np.testing.assert_allclose(np.abs(local), np.broadcast_to(0.5 * box.size, (8, 3)),
                               atol=1e-12)
    assert len({tuple(np.sign(p)) for p in local}) == 8  # all eight, once each
    np.testing.assert_allclose(box.corners.mean(axis=0), box.centre, atol=1e-12)
    lengths = np.linalg.norm(box.edges[:, 1] - box.edges[:, 0], axis=1)
    assert box.edges.shape == (12, 2, 3)
    np.testing.assert_allclose(np.sort(lengths), np.sort(np.repeat(box.size, 4)), rtol=1e-12)


def test_corner_order_is_low_high_per_axis():
    box = Box(np.zeros(3), np.array([2.0, 4.0, 6.0]))
    np.testing.assert_allclose(box.corners[0], [-1, -2, -3])
    np.testing.assert_allclose(box.corners[7], [1, 2, 3])
    np.testing.assert_allclose(box.corners[4 + 2], [1, 2, -3])


@settings(max_examples=50, deadline=None)
@given(st.tuples(coords, coords, coords), st.tuples(sizes, sizes, sizes),
       st.tuples(coords, coords, coords), st.tuples(coords, coords, coords),
       st.tuples(coords, coords, coords))
def test_a_moved_box_has_the_moved_corners(c, s, rv, turn, shift):
    """``Box.moved(T)``: its corners are ``T`` applied to the corners (order kept)."""
    box = Box(np.array(c), np.array(s), pose_from_rotvec(np.array(rv))[:3, :3])
    T = pose_from_rotvec(np.array(turn), np.array(shift))
    moved = box.moved(T)
    want = box.corners @ T[:3, :3].T + T[:3, 3]
    np.testing.assert_allclose(moved.corners, want, atol=1e-12)
    np.testing.assert_array_equal(moved.size, box.size)


@settings(max_examples=50, deadline=None)
@given(st.tuples(coords, coords, coords), st.tuples(sizes, sizes, sizes),
       st.tuples(coords, coords, coords), st.floats(0.0, 0.5), st.integers(0, 2**32 - 1))
def test_a_grown_box_holds_what_the_margin_tests_hold(c, s, rv, margin, seed):
    """``Box.grown(m)`` is the box ``contains(.., m)`` and ``clip_lines(.., m)`` test."""
    box = Box(np.array(c), np.array(s), pose_from_rotvec(np.array(rv))[:3, :3])
    grown = box.grown(margin)
    rng = np.random.default_rng(seed)
    p = box.centre + rng.uniform(-1.5, 1.5, size=(400, 3))
    np.testing.assert_array_equal(grown.contains(p), box.contains(p, margin))
    np.testing.assert_allclose(grown.size - box.size, 2.0 * margin, atol=1e-15)


def test_a_box_shrunk_away_or_moved_by_a_non_pose_is_refused():
    box = Box(np.zeros(3), np.array([0.2, 0.4, 0.6]))
    with pytest.raises(ValueError, match=r"box_size\[0\]"):
        box.grown(-0.1)
    with pytest.raises(ValueError, match=r"T: expected a pose"):
        box.moved(np.eye(3))


@settings(max_examples=60, deadline=None)
@given(c=st.tuples(*[st.floats(-1.0, 1.0)] * 3), s=st.tuples(*[st.floats(0.01, 0.5)] * 3),
       rv=st.tuples(*[st.floats(-3.0, 3.0)] * 3), seed=st.integers(0, 2**31))  # fmt: skip
def test_the_signed_distance_is_the_nearest_point_of_the_box(c, s, rv, seed):
    """Outside: the distance to the nearest point of the solid box (box coordinates clipped
    to its half sizes); inside: minus the distance to the nearest face.  Points near the
    faces, edges and corners as well as far ones."""
    box = Box(np.array(c), np.array(s), pose_from_rotvec(np.array(rv), np.zeros(3))[:3, :3])
    rng = np.random.default_rng(seed)
    local = rng.uniform(-1.0, 1.0, (400, 3)) * box.size
    local[:100] = np.clip(local[:100], -0.5 * box.size, 0.5 * box.size)  # on the surface
    local[100:200] *= 0.5  # near it
    world = local @ box.rotation.T + box.centre
    half = 0.5 * box.size
    nearest = np.clip(local, -half, half)
    outside = np.linalg.norm(local - nearest, axis=1)
    inside = (half - np.abs(local)).min(axis=1)
    truth = np.where(outside > 0.0, outside, -inside)
    np.testing.assert_allclose(box.signed_distance(world), truth, atol=1e-12)
