"""The one model of the wire against the block, against closed forms and an independent
measure written here (points of the wire tested inside the box, speeds across the wire by
dense sampling), over random motions (hypothesis)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ruledrobot.geometry import se3
from ruledrobot.geometry.box import Box
from ruledrobot.robot.tool import BowTool
from ruledrobot.robot.wire.cut import FeedWindow, WireCut, feed_checks, feed_measures
from ruledrobot.robot.wire.in_stock import (
    TOUCH,
    feed_chord,
    flange_wire_ends,
    largest_line_distance,
    wire_ends,
    wire_in_stock,
)

STOCK = Box(centre=[0.0, 0.0, 0.0], size=[0.2, 0.2, 0.2])


def test_translating_wire_closed_form():
    t = np.linspace(0.0, 2.0, 201)
    x = -0.3 + 0.3 * t  # the wire along y moves along x at 0.3 m/s
    ends = np.stack([np.stack([x, -0.5 + 0 * t, 0 * t], 1), np.stack([x, 0.5 + 0 * t, 0 * t], 1)],
                    axis=1)  # fmt: skip
    w = wire_in_stock(t, ends, STOCK)
    inside = np.abs(x) <= 0.1
    np.testing.assert_array_equal(w.inside, inside)
    np.testing.assert_allclose(w.feed[inside], 0.3, rtol=1e-9)
    assert np.isnan(w.feed[~inside]).all()
    np.testing.assert_allclose(w.lo[inside], 0.4)
    np.testing.assert_allclose(w.hi[inside], 0.6)
    np.testing.assert_allclose(w.depth[inside], 0.1 - np.abs(x[inside]), atol=1e-12)
    assert w.runs() == ((int(np.argmax(inside)), int(np.flatnonzero(inside)[-1]) + 1),)


def test_turning_wire_and_sliding_wire():
    t = np.linspace(0.0, 2.0, 2001)
    d = np.stack([np.cos(t), np.sin(t), 0 * t], 1)  # turning about its middle at 1 rad/s
    w = wire_in_stock(t, np.stack([-0.5 * d, 0.5 * d], axis=1), STOCK)
    half = 0.5 * w.chord_length  # the chord ends are fastest: omega * r
    np.testing.assert_allclose(w.feed[5:-5], half[5:-5], rtol=1e-5)
    # sliding along itself cuts nothing
    z = 0.2 * t
    ends = np.stack([np.stack([0 * t, 0 * t, z - 0.5], 1), np.stack([0 * t, 0 * t, z + 0.5], 1)],
                    axis=1)  # fmt: skip
    w = wire_in_stock(t, ends, STOCK)
    assert w.inside.all()
    np.testing.assert_allclose(w.feed, 0.0, atol=1e-12)


def test_touching_is_not_inside_and_depth_of_a_diagonal():
    # a wire along an edge of the block only touches it ... (chord on the boundary has
    # length; a wire crossing a corner point has a chord shorter than TOUCH)
    a = np.array([[[0.1 + 1e-7, -1.0, 0.0], [0.1 - 1e-7, 1.0, 0.0]]])  # 2e-7 inside at x
    w = wire_in_stock([0.0], a, STOCK)
    assert w.chord_length[0] > TOUCH and w.inside[0]
    corner = np.array([[[0.2, 0.0, 0.0], [0.0, 0.2, 0.0]]])  # touches the edge x=y=0.1
    assert not wire_in_stock([0.0], corner, STOCK).inside[0]
    diag = np.array([[[-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]]])  # through the centre
    np.testing.assert_allclose(wire_in_stock([0.0], diag, STOCK).depth, 0.1, atol=1e-12)


def test_feed_chord_meets_the_chord_without_a_jump():
    t = np.linspace(0.0, 1.0, 1001)
    x = -0.2 + 0.2 * t  # enters the block's face x = -0.1 at t = 0.5
    ends = np.stack([np.stack([x, -0.5 + 0 * t, 0.05 + 0 * t], 1),
                     np.stack([x, 0.5 + 0 * t, 0.05 + 0 * t], 1)], axis=1)  # fmt: skip
    f = feed_chord(ends, STOCK, near=0.05)
    far = x < -0.15 - 1e-9
    assert np.isnan(f[far]).all()
    near = (x > -0.15 + 1e-9) & (x < -0.1)
    assert np.isfinite(f[near]).all()
    # the part nearest the block (parallel to its face: a stretch) becomes the chord the
    # wire gets on entering, [0.4, 0.6], continuously
    gap = -0.1 - x[near]
    np.testing.assert_allclose(f[near, 0], 0.4 - gap, atol=1e-6)
    np.testing.assert_allclose(f[near, 1], 0.6 + gap, atol=1e-6)
    w = wire_in_stock(t, ends, STOCK)
    k = np.flatnonzero(w.inside)[0]
    np.testing.assert_allclose([w.lo[k], w.hi[k]], [0.4, 0.6], atol=1e-9)


def _independent(t: np.ndarray, ends: np.ndarray, box: Box, n: int = 2001):
    """Points of the wire tested inside the box; speeds across the wire of every point.

    The wire's ``n`` points at fractions ``lam`` of it, ``a + lam (b - a)``, are linear in
    ``lam``, and so are their box coordinates and their velocities (np.gradient over ``t``
    is linear): both are interpolated between the ends' ((T, 3) -> (T, n)), the squared
    speed across the wire as the quadratic in ``lam`` it is."""
    lam = np.linspace(0.0, 1.0, n)[None, :]
    a, b = ends[:, 0], ends[:, 1]
    pa, pb = box.to_box(a), box.to_box(b)
    inbox = np.ones((len(t), n), dtype=bool)
    for i in range(3):  # each box axis: (T, n)
        inbox &= np.abs(pa[:, i, None] + lam * (pb - pa)[:, i, None]) <= 0.5 * box.size[i]
    d = (b - a) / np.linalg.norm(b - a, axis=1, keepdims=True)
    va, vb = np.gradient(a, t, axis=0), np.gradient(b, t, axis=0)
    ca = va - (va * d).sum(-1, keepdims=True) * d  # across the wire, at its ends
    dc = vb - (vb * d).sum(-1, keepdims=True) * d - ca
    sq = (ca * ca).sum(-1)[:, None] + lam * (2 * (ca * dc).sum(-1)[:, None]
                                             + lam * (dc * dc).sum(-1)[:, None])
    speed = np.where(inbox, np.sqrt(np.maximum(sq, 0.0)), -np.inf).max(axis=1)
    length = inbox.sum(axis=1) / (n - 1) * np.linalg.norm(b - a, axis=1)
    return inbox.sum(axis=1) >= 3, speed, length


@settings(max_examples=40, deadline=None)
@given(
    st.floats(-0.2, 0.2), st.floats(-0.2, 0.2), st.floats(-0.2, 0.2),  # start offset
    st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.floats(-1.0, 1.0),  # rotation vector rate
    st.floats(-0.3, 0.3), st.floats(-0.3, 0.3), st.floats(-0.3, 0.3),  # velocity
    st.floats(0.3, 0.8),  # wire length
    st.floats(0.05, 0.3), st.floats(0.05, 0.3), st.floats(0.05, 0.3),  # block size
)
def test_model_equals_an_independent_measure(x0, y0, z0, wx, wy, wz, vx, vy, vz, L, a, b, c):
    """A rigid wire moving on a screw motion through a block: inside, chord length and
    cutting speed agree with dense sampling of the wire's points."""
    box = Box([0.01, -0.02, 0.03], [a, b, c], se3.pose_from_rotvec([0.3, -0.2, 0.5])[:3, :3])
    t = np.linspace(0.0, 1.0, 401)
    T = se3.pose_from_rotvec(np.outer(t, [wx, wy, wz]))
    T[:, :3, 3] = np.array([x0, y0, z0]) + np.outer(t, [vx, vy, vz]) - 0.15 * np.array([vx, vy, vz])
    ends = wire_ends(T, L)
    w = wire_in_stock(t, ends, box)
    inside, speed, length = _independent(t, ends, box)
    step = L / 2000
    clear = (w.chord_length > 4 * step) | ~w.inside  # away from grazing touches
    k = np.arange(2, t.size - 2)
    k = k[clear[k]]
    np.testing.assert_array_equal(w.inside[k], inside[k])
    np.testing.assert_allclose(w.chord_length[k], length[k], atol=2 * step)
    m = k[w.inside[k]]
    # the dense measure's points lie within one step inside the chord's ends, and two
    # material points one step apart differ in velocity by at most |omega| * step (a rigid
    # wire; the part across the wire by no more): the dense measure is short of the
    # chord end's speed by up to that (a wire turning near its middle, whose chord end
    # moves at 32 mm/s, was 0.36 mm/s short: 1.1 %, beyond a bare 5e-3 + 0.2 mm/s)
    spin = np.linalg.norm([wx, wy, wz]) * step
    np.testing.assert_allclose(w.feed[m], speed[m], rtol=5e-3, atol=2e-4 + spin)


def test_feed_of_a_wire_turning_about_a_point_is_the_chord_ends_distance_times_the_rate():
    """The closed form behind the tolerance above: a wire turning at omega about an axis
    through its middle, normal to it, cuts at omega times the distance of the chord's
    farther end from the middle (the material points move on circles)."""
    box = Box([0.01, -0.02, 0.03], [0.25, 0.0625, 0.0625],
              se3.pose_from_rotvec([0.3, -0.2, 0.5])[:3, :3])  # fmt: skip
    t = np.linspace(0.0, 1.0, 401)
    ends = wire_ends(se3.pose_from_rotvec(np.outer(t, [0.0, -1.0, 0.0])), 0.75)
    w = wire_in_stock(t, ends, box)
    m = np.flatnonzero(w.inside)[2:-2]
    far = np.maximum(np.abs(w.lo[m] - 0.5), np.abs(w.hi[m] - 0.5)) * 0.75
    np.testing.assert_allclose(w.feed[m], 1.0 * far, rtol=2e-5)


def test_feed_measures_of_windows():
    t = np.linspace(0.0, 2.0, 201)
    x = -0.3 + 0.3 * t
    ends = np.stack([np.stack([x, -0.5 + 0 * t, 0 * t], 1), np.stack([x, 0.5 + 0 * t, 0 * t], 1)],
                    axis=1)  # fmt: skip
    w = wire_in_stock(t, ends, STOCK)
    cut = WireCut(STOCK, 1.0, (FeedWindow("a", 0, 201, 0.3, 0.05, ((80, 120),)),))
    (fm,) = feed_measures(w, cut)
    assert fm.max_ok and fm.min_ok and abs(fm.highest - 0.3) < 1e-9
    (fm,) = feed_measures(w, WireCut(STOCK, 1.0, (FeedWindow("a", 0, 201, 0.25, 0.05),)))
    assert not fm.max_ok and 67 <= fm.at_highest <= 133
    sliced = cut.sliced(100, 201)
    assert sliced.feeds[0].start == 0 and sliced.feeds[0].held == ((0, 20),)


def test_a_cut_the_wire_never_made_fails_every_feed_check():
    """The one feed rule (feed_checks): a window or held range the wire never enters in
    the stock fails (before, an exported program's check passed it while the run's and
    the plan's verdicts failed it)."""
    t = np.linspace(0.0, 2.0, 201)
    x = -0.3 + 0.3 * t  # in the stock (|x| < 0.1) at samples 67-133
    ends = np.stack([np.stack([x, -0.5 + 0 * t, 0 * t], 1), np.stack([x, 0.5 + 0 * t, 0 * t], 1)],
                    axis=1)  # fmt: skip
    w = wire_in_stock(t, ends, STOCK)
    missed = WireCut(STOCK, 1.0, (FeedWindow("a", 0, 201, 0.3, 0.05, ((150, 190),)),))
    (fm,) = feed_measures(w, missed)
    assert np.isnan(fm.lowest) and not fm.min_ok and fm.max_ok
    hi, lo = fm.checks(":a")
    assert (hi.name, lo.name) == ("feed_max:a", "feed_min:a") and hi.ok and not lo.ok
    (fm,) = feed_measures(w, WireCut(STOCK, 1.0, (FeedWindow("a", 0, 40, 0.3, 0.05),)))
    assert np.isnan(fm.highest) and not fm.max_ok and not fm.min_ok
    # the plan's verdict words the same rule in mm/s: at the limit passes, beyond fails
    assert all(c.ok for c in feed_checks("", 10.5, 9.5, 10.0, 0.05))
    assert [c.ok for c in feed_checks("", 10.51, 9.49, 10.0, 0.05)] == [False, False]


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_largest_line_distance_is_the_projection_residual(seed):
    """The one deviation measure (plan, program, run) against the projection form."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(5, 3, 3))
    o = rng.normal(size=(5, 3))
    u = rng.normal(size=(5, 3)) * rng.uniform(0.1, 10.0, size=(5, 1))  # any length
    x[0, 1] = np.nan  # a point left out
    x[1] = np.nan  # no point: 0
    n = u / np.linalg.norm(u, axis=1, keepdims=True)
    w = x - o[:, None]
    r = np.linalg.norm(w - np.einsum("kpi,ki->kp", w, n)[..., None] * n[:, None], axis=2)
    np.testing.assert_allclose(largest_line_distance(x, o, u), np.nanmax(
        np.where(np.isnan(r), -np.inf, r), axis=1).clip(0.0), rtol=1e-12, atol=1e-12)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(-0.4, 0.4), min_size=6, max_size=6), st.integers(0, 2**32 - 1))
def test_flange_wire_ends_carry_the_bows_wire_start_and_end(xyz, seed):
    """The wire from flange poses is the bow's ``wire_start`` / ``wire_end`` (flange frame)
    carried by each pose: ``T [p, 1]`` written out here, not through the wire frame."""
    start, end = np.asarray(xyz[:3]), np.asarray(xyz[3:])
    if np.linalg.norm(end - start) < 0.05:
        end = start + np.array([0.0, 0.0, 0.3])
    bow = BowTool(wire_start=start, wire_end=end)
    rng = np.random.default_rng(seed)
    T = se3.pose_from_rotvec(rng.normal(size=(7, 3)), rng.normal(size=(7, 3)))
    ends = flange_wire_ends(T, bow)
    want = np.einsum("mij,kj->mki", T[:, :3, :3], np.stack([start, end])) + T[:, None, :3, 3]
    np.testing.assert_allclose(ends, want, atol=1e-14)
