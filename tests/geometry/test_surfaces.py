"""Built-in ruled surfaces: valid Plücker rows, exact membership, symmetries, registry."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ruledrobot.geometry.lines import Lines, plucker_transform
from ruledrobot.geometry.ruled import RuledSurface
from ruledrobot.geometry.surfaces import (
    SURFACES,
    conoid,
    cylindroid,
    cylindroid_residual,
    helical_developable,
    helical_motion,
    helical_surface,
    helicoid,
    helicoid_residual,
    hyperbolic_paraboloid,
    hyperbolic_paraboloid_residual,
    hyperboloid,
    hyperboloid_residual,
    mobius_band,
    ruling,
    sample_surface,
    surface_point,
)

U = np.linspace(-2.0, 5.0, 23)
V = np.linspace(-1.5, 1.5, 7)


def _assert_plucker(x: np.ndarray) -> None:
    l, m = x[..., :3], x[..., 3:]
    np.testing.assert_allclose(np.linalg.norm(l, axis=-1), 1.0, atol=1e-14)
    np.testing.assert_allclose(np.einsum("...i,...i->...", l, m), 0.0, atol=1e-13)


def _points(lines: Lines, v: np.ndarray = V) -> np.ndarray:
    """Points (N, K, 3) of every line at offsets v from its point nearest the origin."""
    return lines.points_at(np.broadcast_to(v, (len(lines), v.size)))


@pytest.mark.parametrize("name", sorted(SURFACES))
def test_every_surface_gives_valid_plucker_rows(name):
    lines = SURFACES[name](U)
    assert isinstance(lines, Lines)
    assert lines.plucker.shape == (U.size, 6)
    _assert_plucker(lines.plucker)
    # the generic helper agrees and takes any parameter shape
    grid = U.reshape(23, 1) + np.zeros((1, 3))
    rows = ruling(name, grid)
    assert rows.shape == (23, 3, 6)
    np.testing.assert_allclose(rows[:, 1], lines.plucker, atol=1e-15)
    # the base point b(u) and surface points lie on the ruling
    pts = surface_point(name, U[:, None], V[None, :])
    l, m = lines.direction[:, None], lines.moment[:, None]
    np.testing.assert_allclose(
        np.cross(pts, np.broadcast_to(l, pts.shape)), np.broadcast_to(m, pts.shape), atol=1e-12
    )


@given(st.lists(st.floats(-20.0, 20.0), min_size=1, max_size=12))
def test_rulings_are_lines_for_any_parameters(us):
    for name in SURFACES:
        _assert_plucker(ruling(name, np.asarray(us)))


def test_named_samplers_match_the_registry():
    pairs = [
        (cylindroid(U, c=0.3), ruling("cylindroid", U, c=0.3)),
        (hyperbolic_paraboloid(U, c=2.0), ruling("hyperbolic_paraboloid", U, c=2.0)),
        (hyperboloid(U, a=0.5, c=2.0), ruling("hyperboloid", U, a=0.5, c=2.0)),
        (helicoid(U, pitch=0.1), ruling("helicoid", U, pitch=0.1)),
        (
            helical_developable(U, radius=2.0, pitch=0.1),
            ruling("helical_developable", U, radius=2.0, pitch=0.1),
        ),
        (conoid(U, height=0.2, waves=4), ruling("conoid", U, height=0.2, waves=4)),
        (mobius_band(U, radius=3.0), ruling("mobius_band", U, radius=3.0)),
    ]
    for lines, rows in pairs:
        np.testing.assert_array_equal(lines.plucker, rows)
    assert len(cylindroid(0.3)) == 1  # a scalar parameter gives one line


def test_cylindroid_parametrisation_and_implicit_equation():
    c = 0.4
    lines = cylindroid(U, c=c)
    np.testing.assert_allclose(
        lines.direction, np.stack([np.cos(U), np.sin(U), 0 * U], 1), atol=1e-15
    )
    np.testing.assert_allclose(
        lines.point, np.stack([0 * U, 0 * U, c * np.sin(2 * U)], 1), atol=1e-15
    )
    assert np.abs(cylindroid_residual(_points(lines), c=c)).max() < 1e-14
    # ruling u + pi is ruling u reversed
    np.testing.assert_allclose(cylindroid(U + np.pi, c=c).plucker, -lines.plucker, atol=1e-14)
    # the right conoid with two waves is the cylindroid
    np.testing.assert_allclose(conoid(U, height=c, waves=2).plucker, lines.plucker, atol=1e-15)


def test_hyperboloid_rulings_satisfy_the_implicit_equation():
    a, c = 0.7, 1.3
    lines = hyperboloid(U, a=a, c=c)
    pts = _points(lines, np.linspace(-5, 5, 11))
    assert np.abs(hyperboloid_residual(pts, a=a, c=c)).max() < 1e-14 * 25
    # explicit form: through (a cos u, a sin u, 0) along (-a sin u, a cos u, c)
    d = np.stack([-a * np.sin(U), a * np.cos(U), np.full_like(U, c)], 1)
    np.testing.assert_allclose(
        lines.direction, d / np.linalg.norm(d, axis=1, keepdims=True), atol=1e-15
    )
    # first-order distance: a point moved off the surface along the normal by delta
    p = np.array([a, 0.0, 0.0])
    for delta in (1e-3, -2e-4):
        assert hyperboloid_residual(p + np.array([delta, 0.0, 0.0]), a=a, c=c) == pytest.approx(
            delta, rel=2e-3
        )
    # periodic: ruling u + 2 pi is ruling u
    np.testing.assert_allclose(
        hyperboloid(U + 2 * np.pi, a=a, c=c).plucker, lines.plucker, atol=1e-14
    )


def test_paraboloid_and_helicoid_membership():
    lines = hyperbolic_paraboloid(U, c=1.7)
    assert np.abs(hyperbolic_paraboloid_residual(_points(lines), c=1.7)).max() < 1e-13
    assert abs(hyperbolic_paraboloid_residual([0.0, 0.0, 0.01], c=1.7)) == pytest.approx(0.01)
    lines = helicoid(U, pitch=0.25)
    assert np.abs(helicoid_residual(_points(lines), pitch=0.25)).max() < 1e-14
    assert abs(helicoid_residual([0.0, 0.3, 0.0], pitch=0.25)) == pytest.approx(0.3)


def test_mobius_ruling_after_a_full_turn_is_reversed():
    lines = mobius_band(U, radius=1.5)
    np.testing.assert_allclose(
        mobius_band(U + 2 * np.pi, radius=1.5).plucker, -lines.plucker, atol=1e-14
    )
    np.testing.assert_allclose(
        mobius_band(U + 4 * np.pi, radius=1.5).plucker, lines.plucker, atol=1e-13
    )
    # through the centre circle, direction has the documented half-angle form
    b, d = SURFACES["mobius_band"].points_directions(U, radius=1.5)
    np.testing.assert_allclose(np.linalg.norm(b[:, :2], axis=1), 1.5)
    np.testing.assert_allclose(d[:, 2], np.sin(U / 2), atol=1e-15)
    # an even sample over one turn is a sequence closed with a flip
    sample = sample_surface("mobius_band", n=9)
    assert sample.closed and sample.flip
    assert RuledSurface(sample.lines, closed=True).flip


@pytest.mark.parametrize(
    ("name", "params", "pitch"),
    [
        (
            "helical_surface",
            {"point": (0.5, 0.2, -0.1), "direction": (0.3, -0.6, 0.8), "pitch": 0.12},
            0.12,
        ),
        ("helicoid", {"pitch": 0.3}, 0.3),
        ("helical_developable", {"radius": 0.8, "pitch": -0.2}, -0.2),
        ("hyperboloid", {"a": 0.8, "c": 0.5}, 0.0),
    ],
)
def test_helical_surfaces_are_invariant_under_their_helical_motion(name, params, pitch):
    for phi in (0.37, -1.2, 2 * np.pi + 0.1):
        moved = plucker_transform(helical_motion(phi, pitch), ruling(name, U, **params))
        np.testing.assert_allclose(moved, ruling(name, U + phi, **params), atol=1e-13)


def test_helical_surface_is_the_orbit_of_its_first_line():
    p, d, h = np.array([1.0, 0.5, 0.0]), np.array([0.2, 0.4, 0.9]), 0.2
    lines = helical_surface(U, point=p, direction=d, pitch=h)
    first = helical_surface(0.0, point=p, direction=d, pitch=h).plucker[0]
    np.testing.assert_allclose(
        lines.plucker, plucker_transform(helical_motion(U, h), first), atol=1e-14
    )
    T = helical_motion(np.array([0.5, 1.0]), 0.1)
    np.testing.assert_allclose(T[1], T[0] @ T[0], atol=1e-15)  # a one-parameter subgroup


def test_helical_developable_is_tangent_to_the_helix():
    r, h = 1.2, 0.25
    lines = helical_developable(U, radius=r, pitch=h)
    helix = np.stack([r * np.cos(U), r * np.sin(U), h * U], 1)
    tangent = np.stack([-r * np.sin(U), r * np.cos(U), np.full_like(U, h)], 1)
    np.testing.assert_allclose(np.cross(helix, lines.direction), lines.moment, atol=1e-14)
    np.testing.assert_allclose(np.cross(tangent, lines.direction), 0.0, atol=1e-14)
    # consecutive tangents of a dense sample nearly meet on the helix (torsal rulings)
    surf = RuledSurface(helical_developable(np.linspace(0, 1, 200), radius=r, pitch=h))
    s = surf.striction_points()[1:-1]
    u = np.linspace(0, 1, 200)[1:-1]
    ref = np.stack([r * np.cos(u), r * np.sin(u), h * u], 1)
    assert np.abs(s - ref).max() < 1e-4


def test_sample_surface_topology_and_parameters():
    s = sample_surface("cylindroid", n=8, c=0.2)
    assert s.closed and s.flip and len(s.lines) == 8
    np.testing.assert_allclose(s.u, np.arange(8) * np.pi / 8)
    assert s.params == {"c": 0.2}
    s = sample_surface("hyperboloid", n=6)
    assert s.closed and not s.flip
    assert not RuledSurface(s.lines, closed=True).flip
    s = sample_surface("hyperboloid", n=6, start=0.0, stop=1.0)
    assert not s.closed
    np.testing.assert_allclose(s.u, np.linspace(0, 1, 6))
    s = sample_surface("helicoid", n=5)
    assert not s.closed and not s.flip
    s = sample_surface("mobius_band", n=5, start=1.0, closed=True)
    np.testing.assert_allclose(s.u, 1.0 + 2 * np.pi * np.arange(5) / 5)
    s = sample_surface("helical_surface", n=4, point=[0, 1, 0], direction=[1, 0, 1], pitch=0)
    assert s.params["pitch"] == 0.0
    np.testing.assert_array_equal(s.params["point"], [0.0, 1.0, 0.0])


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: sample_surface("torus"), r"unknown surface 'torus'.*cylindroid.*mobius_band"),
        (lambda: ruling("nope", 0.0), r"expected one of .*hyperboloid"),
        (
            lambda: sample_surface("hyperboloid", radius=2),
            r"unknown parameter.*\['radius'\].*a=1.0, c=1.0",
        ),
        (lambda: cylindroid(U, c=0.0), r"parameter c: expected a non-zero"),
        (lambda: hyperboloid(U, a=-1), r"parameter a: expected a positive"),
        (lambda: hyperboloid(U, c=float("nan")), r"parameter c: expected a finite"),
        (lambda: conoid(U, waves=1.5), r"parameter waves: expected a positive integer"),
        (
            lambda: helical_surface(U, direction=(0, 0, 0)),
            r"parameter direction: expected a non-zero",
        ),
        (lambda: helical_surface(U, point=(0, 0)), r"parameter point: expected 3 numbers"),
        (lambda: sample_surface("cylindroid", n=1), r"n: expected an integer"),
        (lambda: sample_surface("cylindroid", n=2), r"closed sample needs at least 3"),
        (lambda: sample_surface("helicoid", closed=True), r"'helicoid' is not periodic"),
        (lambda: sample_surface("cylindroid", closed=True, stop=1.0), r"stop: a closed sample"),
        (lambda: sample_surface("helicoid", start=1.0, stop=1.0), r"stop: equals start"),
        (lambda: cylindroid(np.zeros((2, 2))), r"u: expected a scalar or a 1-D array"),
        (lambda: cylindroid([0.0, np.inf]), r"u\[1\]: contains NaN or infinity"),
        (lambda: hyperboloid_residual(np.zeros((3, 2))), r"points: expected an array of shape"),
    ],
)
def test_bad_input_raises_value_error_naming_the_item(call, match):
    with pytest.raises(ValueError, match=match):
        call()
