"""face_error on a twisted surface where the wire's chord ends lie mid-way along the
target rulings (the block narrower than the rulings): the wire built from the closed-form
normal half a kerf off the surface at its ends is judged as the closed form says, at
chord ends 170 mm from the rulings' ends (a first version looked at those only)."""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.geometry.box import Box
from ruledrobot.robot.wire.face import FaceTarget, face_error
from ruledrobot.robot.wire.in_stock import wire_in_stock

C, KERF = 0.4, 0.0008  # z = x y / C; the cut's kerf


def _point(u, y):
    u, y = np.broadcast_arrays(u, y)
    return np.stack([u, y, u * y / C], axis=-1)


def _normal(u, y):  # closed form: grad(z - x y / C), the waste above the saddle
    u, y = np.broadcast_arrays(u, y)
    n = np.stack([-y / C, -u / C, np.ones_like(y)], axis=-1)
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


def _target(us: np.ndarray, samples: int) -> FaceTarget:
    d = np.stack([np.zeros_like(us), np.ones_like(us), us / C], axis=1)
    norm = np.linalg.norm(d, axis=1)
    # n(t) ∝ (0, -u/C, 1) + y (-1/C, 0, 0), y = t / |d| along the unit direction
    a = np.stack([np.zeros_like(us), -us / C, np.ones_like(us)], axis=1)
    b = np.stack([-1.0 / (C * norm), np.zeros_like(us), np.zeros_like(us)], axis=1)
    chord = np.stack([-0.15 * norm, 0.15 * norm], axis=1)  # the rulings run past the block
    return FaceTarget("saddle", _point(us, 0 * us), d / norm[:, None], a, b, chord,
                      ranges=((0, samples),), kerf=KERF)  # fmt: skip


@pytest.mark.parametrize("extra", [0.0, 0.0002])
def test_chord_ends_mid_ruling_are_judged_on_their_ruling(extra):
    u = np.linspace(-0.05, 0.05, 201)  # the wire sweeps across the rulings
    y = np.array([-0.2, 0.2])
    off = 0.5 * KERF + extra
    ends = _point(u[:, None], y[None, :]) + off * _normal(u[:, None], y[None, :])
    # a wire through the surface's points half a kerf off at y = -0.2, 0.2 is a line, but
    # the surface twists: measure where it crosses a block 60 mm deep in y, mid-ruling
    stock = Box(np.array([0.0, 0.0, 0.0]), np.array([0.2, 0.06, 0.2]))
    wis = wire_in_stock(np.arange(u.size) * 0.01, ends, stock)
    target = _target(np.linspace(-0.06, 0.06, 121), u.size)
    e = face_error(wis, None, None, target)
    # independent truth at the chord ends: the distance along the closed-form normal of
    # the surface point below the wire's chord end, less half the kerf
    x = wis.chord_points()
    yy = x[..., 1]
    uu = x[..., 0] + 0 * yy
    for _ in range(20):  # the foot: the surface point whose normal line passes through x
        p = _point(uu, yy)
        n = _normal(uu, yy)
        d = np.einsum("...i,...i->...", x - p, n)
        q = x - d[..., None] * n
        uu, yy = q[..., 0], q[..., 1]
    truth = np.abs(d - 0.5 * KERF).max(axis=1)
    ok = ~np.isnan(e.error)
    assert ok.all()
    np.testing.assert_allclose(e.error[ok], truth[ok], atol=2e-6)
    assert e.worst == pytest.approx(truth.max(), abs=2e-6)
    assert (e.worst > 1e-4) == (extra > 0)  # the wire 0.2 mm further off fails 0.1 mm


def test_a_wire_at_a_thin_trailing_edge_is_judged_on_its_own_face():
    # a wedge 0.3 mm thick at most: face A (z = 0, waste above) and face B (z = -x / 300,
    # waste below), rulings along y, dense as a refined profile; the wire cuts A half a
    # kerf above it, nearer B's rulings than most of A's
    xa, xb = np.linspace(0.0, 0.09, 181), np.linspace(0.0, 0.09, 9001)  # B the denser
    o = np.concatenate([np.stack([xa, -0.15 + 0 * xa, 0 * xa], 1),
                        np.stack([xb, -0.15 + 0 * xb, -xb / 300], 1)])  # fmt: skip
    d = np.tile([0.0, 1.0, 0.0], (len(o), 1))
    a = np.concatenate([np.tile([0.0, 0.0, 1.0], (xa.size, 1)),
                        np.tile([-1 / 300, 0.0, -1.0], (xb.size, 1))])  # fmt: skip
    target = FaceTarget("wedge", o, d, a, 0 * a, np.tile([0.0, 0.3], (len(o), 1)),
                        ranges=((0, 50),), kerf=KERF)  # fmt: skip
    x = np.linspace(0.0005, 0.003, 50)  # along face A near the edge
    ends = np.stack([np.stack([x, -0.2 + 0 * x, 0.5 * KERF + 0 * x], 1),
                     np.stack([x, 0.2 + 0 * x, 0.5 * KERF + 0 * x], 1)], 1)  # fmt: skip
    stock = Box(np.array([0.05, 0.0, 0.0]), np.array([0.2, 0.15, 0.1]))  # chord ends on sample rows
    e = face_error(wire_in_stock(np.arange(50) * 0.01, ends, stock), None, None, target)
    assert e.worst < 1e-9


@pytest.mark.parametrize(("excess", "burns"), [(0.01, False), (20.0, True)])
def test_a_standing_wire_burns_only_when_its_melt_moves_the_face_past_the_tolerance(
    excess, burns
):
    from ruledrobot.robot.wire.kerf import Material

    # plane z = 0, waste above, rulings along y; the wire cuts at 10 mm/s, then stands
    # with the power at the threshold plus ``excess`` W/m
    mat = Material(kerf_base=0.0003, kerf_gain=1e-7, power_threshold=10.0)
    x = np.concatenate([np.linspace(0.0, 0.01, 101), np.full(50, 0.01)])
    t = np.arange(x.size) * 0.01
    v = np.gradient(x, t)  # the power holds the kerf while the wire moves (constant_kerf)
    power = np.where(v > 0.0, mat.power_for_kerf(KERF, v), 10.0 + excess)
    ends = np.stack([np.stack([x, -0.2 + 0 * x, 0.5 * KERF + 0 * x], 1),
                     np.stack([x, 0.2 + 0 * x, 0.5 * KERF + 0 * x], 1)], 1)  # fmt: skip
    xs = np.linspace(-0.01, 0.03, 401)
    o = np.stack([xs, -0.15 + 0 * xs, 0 * xs], 1)
    target = FaceTarget("plane", o, np.tile([0.0, 1.0, 0.0], (xs.size, 1)),
                        np.tile([0.0, 0.0, 1.0], (xs.size, 1)), np.zeros((xs.size, 3)),
                        np.tile([0.0, 0.3], (xs.size, 1)), ranges=((0, x.size),),
                        kerf=KERF)  # fmt: skip
    stock = Box(np.array([0.0, 0.0, 0.0]), np.array([0.1, 0.2, 0.1]))
    e = face_error(wire_in_stock(t, ends, stock), power, mat, target)
    standing = e.error[102:]  # sample 101 on: still (the stop itself is a step in speed)
    assert bool(np.isinf(standing).any()) == burns == e.burn
    if not burns:  # 0.01 W/m at 1 mm/s melts 1 um more: a hair, not a hole
        assert standing.max() < 2e-6
