"""Corners of a pass (wirecut.corners), anchored frames, the linear scheme."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ruledrobot.algorithms import refine
from ruledrobot.geometry.lines import Lines
from ruledrobot.geometry.ruled import RuledSurface
from ruledrobot.wirecut.cut.wire_geometry import anchored_frames
from ruledrobot.wirecut.motion.corners import corner_nodes, corner_stop_mask, polygon_corners


def _frames(o: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Frames with origins o (M, 3) and z axes z (M, 3) (x any normal to z)."""
    z = z / np.linalg.norm(z, axis=1, keepdims=True)
    x = np.cross(z, [0.3, 0.5, 0.8])
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    F = np.tile(np.eye(4), (len(o), 1, 1))
    F[:, :3, 0], F[:, :3, 1], F[:, :3, 2], F[:, :3, 3] = x, np.cross(z, x), z, o
    return F


def test_the_corners_of_a_square_of_parallel_rulings():
    """Vertical rulings whose foot walks round three sides of a square: two corners."""
    side = np.linspace(0.0, 0.1, 11)
    walk = np.r_[np.c_[side, 0 * side], np.c_[0.1 + 0 * side[1:], side[1:]],
                 np.c_[0.1 - side[1:], 0.1 + 0 * side[1:]]]  # fmt: skip
    o = np.c_[walk, np.zeros(len(walk))]
    F = _frames(o, np.tile([0.0, 0.0, 1.0], (len(o), 1)))
    assert corner_nodes(F, 0.2).tolist() == [10, 20]
    lines = Lines.from_point_direction(o, F[:, :3, 2])
    assert polygon_corners(lines.plucker, np.array([0.05, 0.05, 0.0]), 0.2).tolist() == [10, 20]


def test_a_refined_helicoid_has_no_corners():
    t = np.linspace(0.0, 2.0, 400)
    o = np.c_[0 * t, 0 * t, 0.05 * t]
    z = np.c_[np.cos(t), np.sin(t), 0 * t]
    assert corner_nodes(_frames(o, z), 0.2).size == 0


@settings(max_examples=30, deadline=None)
@given(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.floats(-1.0, 1.0),
       st.floats(-3.0, 3.0), st.floats(-3.0, 3.0))
def test_anchored_origins_are_the_rulings_points_nearest_the_point(px, py, pz, a, b):
    rng = np.random.default_rng(7)
    o = rng.normal(size=(20, 3))
    z = np.c_[np.cos(a + 0.1 * np.arange(20)), np.sin(b + 0.1 * np.arange(20)), np.ones(20)]
    F = _frames(o, z)
    p = np.array([px, py, pz])
    A = anchored_frames(F, p)
    np.testing.assert_array_equal(A[:, :3, :3], F[:, :3, :3])
    d = A[:, :3, 3] - o  # moved along z only
    np.testing.assert_allclose(np.cross(d, F[:, :3, 2]), 0.0, atol=1e-12)
    np.testing.assert_allclose(((p - A[:, :3, 3]) * F[:, :3, 2]).sum(axis=1), 0.0, atol=1e-12)


def test_the_linear_scheme_keeps_a_polygon_of_parallel_rulings():
    """Geodesic midpoints of parallel rulings through a polygon's vertices stay on it,
    corners included (four_point overshoots them)."""
    pts = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0]])
    lines = Lines.from_point_direction(pts, np.tile([0.0, 0.0, 1.0], (4, 1)))
    for scheme, ok in (("linear", True), ("four_point", False)):
        res = refine(RuledSurface(lines), "projection", scheme, 3)
        L = np.asarray(res.lines.plucker)
        foot = np.cross(L[:, :3], L[:, 3:])[:, :2]  # where each ruling meets z = 0
        on_edge = (np.isclose(foot, 0.0, atol=1e-12) | np.isclose(foot, 0.1, atol=1e-12))
        inside = ((foot > -1e-12) & (foot < 0.1 + 1e-12)).all(axis=1)
        assert (on_edge.any(axis=1) & inside).all() == ok, scheme
    assert len(refine(RuledSurface(lines), "projection", "linear", 3).lines) == 25


def test_the_stop_mask_takes_the_slow_runs_that_reach_a_corner():
    class Timed:  # the two fields the mask reads
        feed_limited = np.array([0, 1, 1, 0, 0, 1, 1, 1, 0, 1, 1], dtype=bool)
        s_of_t = np.linspace(0.0, 1.0, 11)

    mask = corner_stop_mask(Timed, np.array([0.6]))  # inside the second slow run
    assert mask.tolist() == [0, 0, 0, 0, 0, 1, 1, 1, 0, 0, 0]
    assert not corner_stop_mask(Timed, np.array([])).any()
    # a slow run a sample before the stop's, joined: one approach (CORNER_JOIN)
    joined = corner_stop_mask(Timed, np.array([0.6]), join=1)
    assert joined.tolist() == [0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1]
    assert corner_stop_mask(Timed, np.array([0.1]), join=1).tolist()[:5] == [0, 1, 1, 0, 0]
    assert corner_stop_mask(Timed, np.array([0.1]), join=2).tolist() == [0] + [1] * 10
