"""Subdivision schemes in R^n, S^2 and SE(3): reproduction, interpolation, orders, errors."""

from __future__ import annotations

import numpy as np
import pytest

import ruledrobot as rr
from ruledrobot.geometry import se3, sphere
from ruledrobot.subdivision import get_scheme

from ..conftest import helical_motion, random_poses

INTERPOLATORY = ("four_point", "six_point", "ternary_four_point")
ARITY = {"chaikin": 2, "bspline3": 2, "four_point": 2, "six_point": 2, "ternary_four_point": 3}


def smooth_pose(s: np.ndarray) -> np.ndarray:
    """A smooth SE(3) curve that is no one-parameter subgroup."""
    rv = np.stack([0.9 * np.sin(s), 0.5 * s * s - 0.3, 0.7 * np.cos(1.3 * s)], axis=-1)
    p = np.stack([np.cos(s), np.sin(2 * s), 0.3 * s**3], axis=-1)
    return se3.pose_from_rotvec(rv, p)


def smooth_sphere(s: np.ndarray) -> np.ndarray:
    v = np.stack(
        [np.cos(s) * np.cos(0.6 * s * s), np.sin(s) * np.cos(0.6 * s * s), np.sin(0.6 * s * s)],
        axis=-1,
    )
    return v


def smooth_points(s: np.ndarray) -> np.ndarray:
    return np.stack([np.cos(2 * s), np.sin(s) * s, np.exp(0.5 * s)], axis=-1)


def error(space: str, a: np.ndarray, b: np.ndarray) -> float:
    if space == "se3":
        return float(np.linalg.norm(se3.log(se3.inverse(a) @ b), axis=-1).max())
    if space == "sphere":
        return float(np.linalg.norm(sphere.log(a, b), axis=-1).max())
    return float(np.linalg.norm(a - b, axis=-1).max())


def measured_orders(scheme: str, space: str, steps: int = 2) -> list[float]:
    curve = {"se3": smooth_pose, "sphere": smooth_sphere, "euclidean": smooth_points}[space]
    errs = []
    for h in (0.2, 0.1, 0.05, 0.025):
        s = np.arange(0.0, 2.4 + 1e-9, h)
        out = rr.subdivide(curve(s), scheme, steps, space=space)
        fine = np.linspace(0.0, s[-1], len(out))
        errs.append(error(space, curve(fine), out))
    return [float(np.log2(errs[i] / errs[i + 1])) for i in range(len(errs) - 1)]


def fitted_order(rates: list[float]) -> float:
    """Least-squares slope of log2(error) against log2(1/h) = mean of the halving rates."""
    return float(np.mean(rates))


@pytest.mark.parametrize("space", ["euclidean", "sphere", "se3"])
@pytest.mark.parametrize(
    ("scheme", "order"),
    [("four_point", 4), ("six_point", 6), ("ternary_four_point", 3), ("bspline3", 2)],
)
def test_approximation_order(scheme, order, space):
    rates = measured_orders(scheme, space)
    assert fitted_order(rates) > order - 0.3, rates


@pytest.mark.parametrize("scheme", INTERPOLATORY)
def test_polynomial_reproduction_in_rn(scheme, rng):
    degree = {"four_point": 3, "six_point": 5, "ternary_four_point": 2}[scheme]
    coef = rng.normal(size=(degree + 1, 4))
    s = np.arange(9.0)
    poly = lambda u: np.polynomial.polynomial.polyval(u, coef).T  # noqa: E731
    out = rr.subdivide(poly(s), scheme, steps=3)
    fine = np.linspace(0, 8, len(out))
    np.testing.assert_allclose(out, poly(fine), atol=1e-8 * np.abs(poly(fine)).max())


def test_four_point_dlg_mask_and_w():
    p = np.array([[0.0], [1.0], [4.0], [2.0], [3.0], [-1.0]])
    w = 0.1
    out = rr.subdivide(p, "four_point", steps=1, closed=True, w=w)
    n = len(p)
    for i in range(n):
        expected = (0.5 + w) * (p[i] + p[(i + 1) % n]) - w * (p[i - 1] + p[(i + 2) % n])
        np.testing.assert_allclose(out[2 * i + 1], expected, atol=1e-14)
        np.testing.assert_allclose(out[2 * i], p[i], atol=0)


def test_chaikin_and_bspline3_masks():
    p = np.array([[0.0], [1.0], [4.0], [2.0], [3.0]])
    n = len(p)
    out = rr.subdivide(p, "chaikin", steps=1, closed=True)
    for i in range(n):
        np.testing.assert_allclose(out[2 * i], 0.75 * p[i] + 0.25 * p[(i + 1) % n], atol=1e-14)
        np.testing.assert_allclose(out[2 * i + 1], 0.25 * p[i] + 0.75 * p[(i + 1) % n], atol=1e-14)
    out = rr.subdivide(p, "bspline3", steps=1, closed=True)
    for i in range(n):
        v = (p[i - 1] + 6 * p[i] + p[(i + 1) % n]) / 8
        np.testing.assert_allclose(out[2 * i], v, atol=1e-14)
        np.testing.assert_allclose(out[2 * i + 1], (p[i] + p[(i + 1) % n]) / 2, atol=1e-14)
    # open clamped Chaikin: ends kept, end edges give their midpoints
    out = rr.subdivide(p, "chaikin", steps=1)
    np.testing.assert_allclose(
        out[[0, 1, -2, -1]], [p[0], (p[0] + p[1]) / 2, (p[3] + p[4]) / 2, p[4]], atol=1e-14
    )
    assert len(out) == 2 * n - 2


@pytest.mark.parametrize("scheme", rr.SCHEME_NAMES)
@pytest.mark.parametrize("closed", [False, True])
def test_lengths_and_kept_ends(scheme, closed, rng):
    p = rng.normal(size=(7, 2))
    out = rr.subdivide(p, scheme, steps=2, closed=closed)
    sch = get_scheme(scheme)
    n = len(p)
    for _ in range(2):
        n = sch.refined_length(n, closed)
    assert len(out) == n
    if not closed:
        np.testing.assert_allclose(out[[0, -1]], p[[0, -1]], atol=1e-15)
    if scheme in INTERPOLATORY:
        step = ARITY[scheme] ** 2
        np.testing.assert_allclose(out[::step][: len(p)], p, atol=1e-15)


@pytest.mark.parametrize("scheme", rr.SCHEME_NAMES)
def test_se3_reproduces_screw_motions(scheme):
    """Uniform samples of a helical motion are refined onto the same helical motion."""
    g = random_poses(np.random.default_rng(7), 1)[0]
    phi = np.linspace(0.0, 2.0, 7)
    frames = g @ helical_motion(phi, 0.4)
    out = rr.subdivide(frames, scheme, steps=3)
    # each refined frame is g H(psi) for some psi: recover psi from the rotation
    rel = se3.inverse(g) @ out
    psi = np.arctan2(rel[:, 1, 0], rel[:, 0, 0])
    np.testing.assert_allclose(rel, helical_motion(psi, 0.4), atol=1e-10)
    if scheme != "chaikin":  # chaikin's clamped ends are not uniform in the parameter
        np.testing.assert_allclose(psi, np.linspace(0.0, 2.0, len(out)), atol=1e-10)


def test_sphere_closed_with_flip_stays_on_great_circle():
    u = np.arange(6) * np.pi / 6  # half a great circle; p_6 = -p_0
    tilt = se3.rotation_about_axis(np.array([1.0, 0.0, 0.0]), 0.4)
    v = np.stack([np.cos(u), np.sin(u), 0 * u], 1) @ tilt.T
    out = rr.subdivide(v, "four_point", 3, closed=True, space="sphere", flip=True)
    assert len(out) == 48
    normal = tilt[:, 2]
    assert np.abs(out @ normal).max() < 1e-12
    ang = np.unwrap(np.arctan2(out @ tilt[:, 1], out @ tilt[:, 0]))
    np.testing.assert_allclose(ang, np.arange(48) * np.pi / 48, atol=1e-12)


def moebius_frames(u: np.ndarray) -> np.ndarray:
    """F(u) = Rz(u) Tx(1) Rx(u/2): F(u + 2 pi) = F(u) Rx(pi), F(u + 4 pi) = F(u)."""
    F = helical_motion(u, 0.0) @ se3.pose_from_rotvec([0.0, 0.0, 0.0], [1.0, 0.0, 0.0])
    return F @ se3.pose_from_rotvec(np.stack([u / 2, 0 * u, 0 * u], axis=-1))


@pytest.mark.parametrize("scheme", rr.SCHEME_NAMES)
def test_se3_closed_with_flip_equals_periodic_double_cover(scheme):
    n = 8
    half = moebius_frames(np.arange(n) * 2 * np.pi / n)
    double = moebius_frames(np.arange(2 * n) * 2 * np.pi / n)
    out = rr.subdivide(half, scheme, 2, closed=True, flip=True)
    ref = rr.subdivide(double, scheme, 2, closed=True)
    m = len(out)
    assert len(ref) == 2 * m
    np.testing.assert_allclose(out, ref[:m], atol=1e-12)
    np.testing.assert_allclose(ref[m:], out @ np.diag([1.0, -1.0, -1.0, 1.0]), atol=1e-12)


def test_subdivide_lines_is_projection_algorithm(rng):
    lines = rr.Lines.from_point_direction(rng.normal(size=(6, 3)), rng.normal(size=(6, 3)))
    a = rr.subdivide(lines, "bspline3", 2)
    b = rr.refine(lines, "projection", "bspline3", 2).lines
    np.testing.assert_array_equal(a.plucker, b.plucker)
    assert isinstance(a, rr.Lines)


def test_bad_input_errors():
    pts = np.zeros((3, 3))
    with pytest.raises(ValueError, match="'six_point' needs at least 6 elements, got 3"):
        rr.subdivide(pts, "six_point", 1)
    with pytest.raises(ValueError, match="unknown scheme 'foo'"):
        rr.subdivide(pts, "foo", 1)
    with pytest.raises(ValueError, match=r"w = 0\.3"):
        rr.subdivide(np.zeros((5, 3)), "four_point", 1, w=0.3)
    with pytest.raises(ValueError, match=r"unknown parameter\(s\) \['w'\]"):
        rr.subdivide(pts, "chaikin", 1, w=0.1)
    with pytest.raises(ValueError, match="steps"):
        rr.subdivide(pts, "chaikin", -1)
    bad = np.zeros((5, 3))
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match=r"points\[3\]"):
        rr.subdivide(bad, "chaikin", 1)
    with pytest.raises(ValueError, match="flip=True needs closed=True"):
        rr.subdivide(np.zeros((5, 3)), "chaikin", 1, flip=True)
    with pytest.raises(ValueError, match=r"unit vectors\[0\]"):
        rr.subdivide(np.ones((5, 3)), "chaikin", 1, space="sphere")
    with pytest.raises(ValueError, match=r"poses\[0\]"):
        rr.subdivide(np.ones((5, 4, 4)), "chaikin", 1)
    v = np.array([[1.0, 0, 0], [0, 1, 0], [-1, 0, 0], [0, 1, 0]])
    with pytest.raises(ValueError, match="antipodal"):
        rr.subdivide(v[[0, 2, 1]], "chaikin", 1, space="sphere")
