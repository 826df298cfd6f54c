"""Kerf compensation (wirecut.cut.kerf) against closed forms.

Surfaces built here by hand: a plane and a cylinder (developable: the normal is constant
along a ruling, the offset is exactly half the kerf along it, error 0) and the hyperbolic
paraboloid z = x y / c, whose normal along the ruling x = u is (-y/c, -u/c, 1): the angle
Delta between the normals at the chord's ends gives the minimax offset's length
kerf / (1 + cos(Delta/2)) along their bisector and its error kerf/2 tan^2(Delta/4).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ruledrobot.geometry.box import Box
from ruledrobot.wirecut.cut.kerf import (
    KEEP_CLEARANCE,
    kept_surface_error,
    kerf_offsets,
    ruling_normals,
    waste_sign,
)

KERF = 0.0008
R = 0.5 * KERF


def _frames(origins: np.ndarray, z: np.ndarray, x_hint: np.ndarray) -> np.ndarray:
    """Right-handed frames (M, 4, 4): origin, unit z, x the part of x_hint normal to z."""
    z = z / np.linalg.norm(z, axis=1, keepdims=True)
    x = x_hint - np.einsum("mi,mi->m", x_hint, z)[:, None] * z
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    F = np.tile(np.eye(4), (len(z), 1, 1))
    F[:, :3, 0], F[:, :3, 1], F[:, :3, 2], F[:, :3, 3] = x, np.cross(z, x), z, origins
    return F


def _plane(u: np.ndarray) -> np.ndarray:
    """The plane z = 0 ruled by lines along y at x = u."""
    o = np.c_[u, np.zeros_like(u), np.zeros_like(u)]
    return _frames(o, np.tile([0.0, 1.0, 0.0], (len(u), 1)), np.tile([1.0, 0, 0], (len(u), 1)))


def _paraboloid(u: np.ndarray, c: float) -> np.ndarray:
    """z = x y / c ruled by the lines x = u: points (u, y, u y / c)."""
    o = np.c_[u, np.zeros_like(u), np.zeros_like(u)]
    z = np.c_[np.zeros_like(u), np.ones_like(u), u / c]
    return _frames(o, z, np.tile([1.0, 0.0, 0.0], (len(u), 1)))


def _cylinder(radius: float, m: int) -> np.ndarray:
    th = np.linspace(0.0, 2 * np.pi, m, endpoint=False)
    o = np.c_[radius * np.cos(th), radius * np.sin(th), np.zeros(m)]
    return _frames(o, np.tile([0.0, 0.0, 1.0], (m, 1)), o.copy())


def _shifted(F: np.ndarray, offset: np.ndarray) -> np.ndarray:
    G = F.copy()
    G[:, :3, 3] += offset
    return G


def test_plane_offset_is_half_the_kerf_into_the_waste_exactly():
    F = _plane(np.linspace(-0.05, 0.05, 21))
    box = Box([0.0, 0.0, 0.0], [0.2, 0.2, 0.2])
    below = kerf_offsets(F, box, KERF, np.array([0.0, 0.0, -0.05]), closed=False)
    assert below.compensated
    np.testing.assert_allclose(below.offset, np.tile([0.0, 0.0, R], (21, 1)), atol=1e-15)
    np.testing.assert_allclose(below.error, 0.0, atol=1e-15)
    above = kerf_offsets(F, box, KERF, np.array([0.01, 0.02, 0.05]), closed=False)
    np.testing.assert_allclose(above.offset, -below.offset, atol=1e-15)


def test_no_keep_or_no_kerf_is_not_compensated():
    F = _plane(np.linspace(-0.05, 0.05, 5))
    box = Box([0.0, 0.0, 0.0], [0.2, 0.2, 0.2])
    for keep, kerf in ((None, KERF), (np.array([0.0, 0.0, -0.05]), 0.0)):
        k = kerf_offsets(F, box, kerf, keep, closed=False)
        assert not k.compensated
        assert k.offset.shape == (5, 3) and not k.offset.any() and not k.error.any()


def test_rulings_off_the_stock_keep_the_nearest_crossing_rulings_offset():
    u = np.linspace(-0.2, 0.2, 41)  # the box spans |x| <= 0.0525: rulings 15..25 cross it
    F = _paraboloid(u, 0.1)
    box = Box([0.0, 0.0, 0.0], [0.105, 0.2, 0.4])
    k = kerf_offsets(F, box, KERF, np.array([0.0, 0.0, -0.1]), closed=False)
    inside = np.abs(u) < 0.0525
    assert np.flatnonzero(inside).tolist() == list(range(15, 26))
    first, last = np.flatnonzero(inside)[[0, -1]]
    assert (k.offset[:first] == k.offset[first]).all()
    assert (k.offset[last + 1 :] == k.offset[last]).all()
    assert not (k.offset[first] == k.offset[last]).all()
    assert not k.error[~inside].any()
    assert (k.error[inside] > 0).all()


def test_twisted_surface_minimax_offset_and_error_closed_form():
    c = 0.1
    u = np.linspace(-0.1, 0.1, 201)  # 1 mm apart: the central differences are near exact
    F = _paraboloid(u, c)
    box = Box([0.0, 0.0, 0.0], [0.3, 0.2, 0.4])  # chords end at y = +-0.1, |z| <= 0.1
    k = kerf_offsets(F, box, KERF, np.array([0.0, 0.0, -0.1]), closed=False)
    n_plus = np.c_[np.full_like(u, -0.1 / c), -u / c, np.ones_like(u)]
    n_minus = np.c_[np.full_like(u, 0.1 / c), -u / c, np.ones_like(u)]
    n_plus /= np.linalg.norm(n_plus, axis=1, keepdims=True)
    n_minus /= np.linalg.norm(n_minus, axis=1, keepdims=True)
    delta = np.arccos(np.clip(np.einsum("mi,mi->m", n_plus, n_minus), -1, 1))
    assert delta.min() > np.radians(53) and delta.max() > np.radians(70)  # a real twist
    bis = n_plus + n_minus
    bis /= np.linalg.norm(bis, axis=1, keepdims=True)  # +z: the waste side (keep below)
    length = KERF / (1.0 + np.cos(delta / 2))
    # inside (central differences, O(du^2)); the end rulings' one-sided differences are
    # first order
    np.testing.assert_allclose(k.offset[1:-1], (length[:, None] * bis)[1:-1], rtol=0, atol=1e-8)
    np.testing.assert_allclose(k.offset[[0, -1]], (length[:, None] * bis)[[0, -1]], atol=1e-6)
    np.testing.assert_allclose(k.error[1:-1], (R * np.tan(delta / 4) ** 2)[1:-1], rtol=1e-4)
    # the offset lies normal to its ruling
    np.testing.assert_allclose(np.einsum("mi,mi->m", k.offset, F[:, :3, 2]), 0.0, atol=1e-12)
    # the wire on the offsets leaves the kept surface with the predicted error
    measured = kept_surface_error(F, _shifted(F, k.offset), box, KERF,
                                  np.array([0.0, 0.0, -0.1]))  # fmt: skip
    np.testing.assert_allclose(measured, k.error, rtol=1e-9, atol=1e-15)


@settings(max_examples=40, deadline=None)
@given(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.floats(1e-6, 2e-4))
def test_no_other_offset_does_better(a, b, size):
    """Minimax: any other offset normal to the ruling has a larger largest error."""
    c = 0.1
    u = np.linspace(-0.1, 0.1, 41)
    F = _paraboloid(u, c)
    box = Box([0.0, 0.0, 0.0], [0.3, 0.2, 0.4])
    keep = np.array([0.0, 0.0, -0.1])
    k = kerf_offsets(F, box, KERF, keep, closed=False)
    d = a * F[:, :3, 0] + b * F[:, :3, 1]
    norm = np.linalg.norm(d, axis=1, keepdims=True)
    if norm.min() < 1e-6:
        return
    d = size * d / norm
    worse = kept_surface_error(F, _shifted(F, k.offset + d), box, KERF, keep)
    best = kept_surface_error(F, _shifted(F, k.offset), box, KERF, keep)
    assert (worse >= best - 1e-12).all()


def test_a_wire_on_the_part_side_counts_its_full_distance():
    F = _plane(np.linspace(-0.05, 0.05, 11))
    box = Box([0.0, 0.0, 0.0], [0.2, 0.2, 0.2])
    keep = np.array([0.0, 0.0, -0.05])
    err = kept_surface_error(F, _shifted(F, np.array([0.0, 0.0, -R])), box, KERF, keep)
    np.testing.assert_allclose(err, KERF, rtol=1e-12)
    on_target = kept_surface_error(F, F, box, KERF, keep)
    np.testing.assert_allclose(on_target, R, rtol=1e-12)


@pytest.mark.parametrize("keep, outward", [("inside", 1.0), ("outside", -1.0)])
def test_closed_cylinder_keeps_its_inside_or_outside(keep, outward):
    F = _cylinder(0.05, 48)
    box = Box([0.0, 0.0, 0.0], [0.3, 0.3, 0.1])
    k = kerf_offsets(F, box, KERF, keep, closed=True)
    radial = F[:, :3, 3] / 0.05
    np.testing.assert_allclose(k.offset, outward * R * radial, atol=1e-12)
    np.testing.assert_allclose(k.error, 0.0, atol=1e-15)


def test_waste_sign_flips_with_the_keep_point_and_the_frames_order():
    F = _plane(np.linspace(-0.05, 0.05, 11))
    box = Box([0.0, 0.0, 0.0], [0.2, 0.2, 0.2])
    t = np.zeros((len(F), 1))
    n = ruling_normals(F, t)[:, 0]
    np.testing.assert_allclose(np.abs(n[:, 2]), 1.0)  # unit normals of z = 0
    s_below = waste_sign(F, box, np.array([0.0, 0.0, -0.05]))
    # the waste is above (+z): the sign turns the normals to +z
    assert s_below * n[0, 2] == pytest.approx(1.0)
    assert waste_sign(F, box, np.array([0.0, 0.0, 0.05])) == -s_below
    assert waste_sign(F[::-1], box, np.array([0.0, 0.0, -0.05])) == -s_below


def test_a_keep_point_on_the_surface_or_a_surface_off_the_stock_is_refused():
    F = _plane(np.linspace(-0.05, 0.05, 11))
    box = Box([0.0, 0.0, 0.0], [0.2, 0.2, 0.2])
    with pytest.raises(ValueError, match="keep: the point lies on the surface"):
        waste_sign(F, box, np.array([0.0, 0.0, 0.5 * KEEP_CLEARANCE]))
    far = Box([1.0, 1.0, 1.0], [0.1, 0.1, 0.1])
    with pytest.raises(ValueError, match="does not cross the stock"):
        waste_sign(F, far, np.array([0.0, 0.0, -0.05]))


def test_ruling_normals_of_the_paraboloid_match_the_gradient():
    c = 0.2
    u = np.linspace(-0.1, 0.1, 401)
    F = _paraboloid(u, c)
    t = np.linspace(-0.1, 0.1, 5)[None, :].repeat(len(u), 0)
    n = ruling_normals(F, t)
    y = t * F[:, None, 1, 2]  # y coordinate of the points at parameter t
    g = np.stack([-y / c, np.broadcast_to(-u[:, None] / c, y.shape), np.ones_like(y)], -1)
    g /= np.linalg.norm(g, axis=-1, keepdims=True)
    inner = np.abs(np.einsum("mki,mki->mk", n, g))[1:-1]
    np.testing.assert_allclose(inner, 1.0, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(n, axis=-1), 1.0, atol=1e-12)
