"""Wire/tool geometry: wire frame, chords, slide bounds, the wire covering its chord."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from ruledrobot.geometry import se3
from ruledrobot.geometry.box import Box
from ruledrobot.wirecut.cut import wire_geometry as tp
from ruledrobot.wirecut.job.load import ToolSpec

TOOL = ToolSpec(np.array([-0.2, 0.05, 0.25]), np.array([0.2, 0.05, 0.25]), clearance=0.03)


def test_wire_frame():
    W = tp.wire_frame(TOOL)
    np.testing.assert_allclose(W[:3, 3], [0.0, 0.05, 0.25])
    np.testing.assert_allclose(W[:3, 2], [1.0, 0.0, 0.0])
    np.testing.assert_allclose(W[:3, :3].T @ W[:3, :3], np.eye(3), atol=1e-15)
    assert np.linalg.det(W[:3, :3]) > 0
    ends = W @ np.array([[0, 0, -0.2, 1], [0, 0, 0.2, 1]]).T
    np.testing.assert_allclose(ends[:3].T, [TOOL.wire_start, TOOL.wire_end], atol=1e-15)
    np.testing.assert_allclose(W[:3, 0], np.array([0, 0.05, 0.25]) / np.hypot(0.05, 0.25))


def test_chords_and_slide_bounds_hand_computed():
    F = np.broadcast_to(np.eye(4), (2, 4, 4)).copy()
    F[0, :3, 3] = [0.0, 0.05, -1.0]  # along z, enters the box at z = -0.1
    F[1, :3, 3] = [0.0, 2.0, 0.0]  # misses
    box = Box([0.0, 0.0, 0.0], [0.2, 0.2, 0.2])
    c0, c1, hit = tp.chords(F, box)
    np.testing.assert_allclose([c0[0], c1[0]], [0.9, 1.1])
    assert hit.tolist() == [True, False]
    lo, hi, ok = tp.slide_bounds(c0, c1, hit, TOOL)
    half = 0.2 - 0.03
    np.testing.assert_allclose([lo[0], hi[0]], [1.1 - half, 0.9 + half])
    assert ok.all() and np.isinf(lo[1]) and np.isinf(hi[1])
    long_box = Box([0.0, 0.0, 0.0], [0.2, 0.2, 0.5])
    assert not tp.slide_bounds(*tp.chords(F, long_box), TOOL)[2][0]


@given(
    psi=st.floats(-np.pi, np.pi),
    frac=st.floats(0.0, 1.0),
    reverse=st.booleans(),
    seed=st.integers(0, 2**16),
)
def test_wire_covers_its_chord(psi, frac, reverse, seed):
    rng = np.random.default_rng(seed)
    F = se3.exp(np.r_[rng.normal(size=3), 0.05 * rng.normal(size=3)])[None]
    box = Box(
        [0.0, 0.0, 0.0],
        [0.1, 0.15, 0.12],
        se3.rotation_about_axis(np.array([0.0, 0.0, 1.0]), rng.uniform(-1, 1)),
    )
    c0, c1, hit = tp.chords(F, box)
    if not hit[0]:
        return
    lo, hi, ok = tp.slide_bounds(c0, c1, hit, TOOL)
    if not ok[0]:
        return
    s = lo + frac * (hi - lo)
    P = tp.flange_poses(tp.wire_poses(F, psi, s, reverse), tp.wire_frame(TOOL))[0]
    a = P[:3, :3] @ TOOL.wire_start + P[:3, 3]
    b = P[:3, :3] @ TOOL.wire_end + P[:3, 3]
    # the wire lies on the ruling ...
    z, o = F[0, :3, 2], F[0, :3, 3]
    for w in (a, b):
        assert np.linalg.norm(np.cross(w - o, z)) < 1e-12
    # ... and covers the chord with the clearance at both ends
    ta, tb = sorted([(a - o) @ z, (b - o) @ z])
    assert ta <= c0[0] - TOOL.clearance + 1e-12 and tb >= c1[0] + TOOL.clearance - 1e-12
    assert not box.contains(a) and not box.contains(b)


def test_speed_factor_known_motions():
    """The time law's bound: speed across the wire per unit of s, from the one model."""
    s = np.linspace(0.0, 1.0, 11)
    big = Box([0.0, 0.05, 0.25], [1.0, 1.0, 1.0])
    P = np.broadcast_to(np.eye(4), (11, 4, 4)).copy()
    P[:, 1, 3] = 0.3 * s  # translation across the wire (along flange y): 0.3 m per unit s
    np.testing.assert_allclose(tp.speed_factor(P, s, TOOL, big, 0.0), 0.3, rtol=1e-12)
    P = np.broadcast_to(np.eye(4), (11, 4, 4)).copy()
    P[:, 0, 3] = 0.3 * s  # sliding along the wire cuts nothing
    np.testing.assert_allclose(tp.speed_factor(P, s, TOOL, big, 0.0), 0.0, atol=1e-12)
    # far from a small block: 0; within `near` of it: the speed of the nearest point
    far = Box([0.0, 2.0, 0.25], [0.1, 0.1, 0.1])
    P[:, 1, 3] = 0.3 * s
    P[:, 0, 3] = 0.0
    assert (tp.speed_factor(P, s, TOOL, far, 0.5) == 0.0).all()
    np.testing.assert_allclose(tp.speed_factor(P, s, TOOL, far, 2.0), 0.3, rtol=1e-12)
    # rotation about the flange z axis by 2 rad per unit of s: the wire (at y = 0.05,
    # z = 0.25, along x) sweeps; its chord ends at x = +-0.2 are fastest across it
    P = se3.pose_from_rotvec(np.c_[0 * s, 0 * s, 2.0 * s])
    f = tp.speed_factor(P, s, TOOL, big, 0.0)
    r = 0.2  # across-wire part of the velocity of the end at radius hypot(0.2, 0.05)
    np.testing.assert_allclose(f[1:-1], 2.0 * r * np.sinc(2 * 0.1 / np.pi), rtol=1e-9)
