"""The three refinement algorithms: closed forms, invariants, equivariance."""

from __future__ import annotations

import numpy as np
import pytest

import ruledrobot as rr
from ruledrobot.geometry.lines import plucker_transform

from ..conftest import helical_motion, random_poses

ALGORITHMS = ("projection", "combined", "dh")


def manifold_residual(lines: rr.Lines) -> float:
    l, m = lines.direction, lines.moment
    return float(max(np.abs(np.linalg.norm(l, axis=1) - 1).max(), np.abs((l * m).sum(1)).max()))


@pytest.fixture
def random_lines(rng):
    return rr.Lines.from_point_direction(
        rng.normal(size=(7, 3)), rng.normal(size=(7, 3)) + np.array([0, 0, 3])
    )


@pytest.mark.parametrize("algorithm", ALGORITHMS)
@pytest.mark.parametrize("scheme", rr.SCHEME_NAMES)
@pytest.mark.parametrize("closed", [False, True])
def test_equivariance_and_manifold(algorithm, scheme, closed, random_lines, rng):
    g = random_poses(rng, 1, scale=3.0)[0]
    a = rr.refine(random_lines.transform(g), algorithm, scheme, 2, closed=closed)
    b = rr.refine(random_lines, algorithm, scheme, 2, closed=closed)
    np.testing.assert_allclose(a.lines.plucker, b.lines.transform(g).plucker, atol=1e-10)
    if b.frames is not None:
        np.testing.assert_allclose(a.frames, g @ b.frames, atol=1e-10)
    assert manifold_residual(a.lines) < 1e-12 * max(1, np.abs(a.lines.moment).max())


@pytest.mark.parametrize("algorithm", ALGORITHMS)
@pytest.mark.parametrize("scheme", ["four_point", "six_point", "ternary_four_point"])
def test_interpolatory_schemes_keep_the_input(algorithm, scheme, random_lines):
    step = 3 if scheme == "ternary_four_point" else 2
    for k in (1, 2):
        res = rr.refine(random_lines, algorithm, scheme, k)
        np.testing.assert_allclose(res.lines.plucker[:: step**k], random_lines.plucker, atol=1e-12)


@pytest.mark.parametrize("algorithm", ALGORITHMS)
@pytest.mark.parametrize("scheme", ["chaikin", "bspline3"])
def test_open_sequences_keep_their_ends(algorithm, scheme, random_lines):
    res = rr.refine(random_lines, algorithm, scheme, 3)
    np.testing.assert_allclose(
        res.lines.plucker[[0, -1]], random_lines.plucker[[0, -1]], atol=1e-12
    )


@pytest.mark.parametrize("scheme", rr.SCHEME_NAMES)
def test_dh_reproduces_helical_surfaces(scheme):
    L0 = rr.Lines.from_point_direction([[1.0, 0.2, 0.1]], [[0.1, 0.6, 0.8]]).plucker[0]
    lines = rr.Lines(plucker_transform(helical_motion(np.linspace(0, 1.5, 6), 0.3), L0))
    res = rr.refine(lines, "dh", scheme, 3)
    d = res.lines.direction
    # recover each refined line's helical parameter from its direction, then compare
    psi = np.unwrap(np.arctan2(d[:, 1], d[:, 0]) - np.arctan2(L0[1], L0[0]))
    expected = plucker_transform(helical_motion(psi, 0.3), L0)
    np.testing.assert_allclose(res.lines.plucker, expected, atol=1e-9)
    rel = np.linalg.inv(helical_motion(psi, 0.3)) @ res.frames
    np.testing.assert_allclose(rel, np.broadcast_to(rel[0], rel.shape), atol=1e-9)


def test_projection_keeps_cylindroid_striction_on_the_double_line():
    phi = np.arange(8) * np.pi / 8
    pts = np.stack([0 * phi, 0 * phi, np.sin(2 * phi)], 1)
    lines = rr.Lines.from_point_direction(pts, np.stack([np.cos(phi), np.sin(phi), 0 * phi], 1))
    res = rr.refine(lines, "projection", "four_point", 5, closed=True)
    assert res.flip and len(res.lines) == 8 * 32
    s = res.surface().striction_points()
    assert np.hypot(s[:, 0], s[:, 1]).max() < 1e-9


@pytest.mark.parametrize("scheme", ["four_point", "chaikin", "bspline3"])
def test_dh_keeps_cylindroid_on_its_double_line(scheme):
    """The DH x axis of the cylindroid flips at its turning rulings; the dh refinement
    uses sign-continuous frames, so the refined rulings still cross the z axis at
    right angles (the frames' screw axes are the z axis itself)."""
    phi = np.arange(8) * np.pi / 8
    pts = np.stack([0 * phi, 0 * phi, 0.5 * np.sin(2 * phi)], 1)
    lines = rr.Lines.from_point_direction(pts, np.stack([np.cos(phi), np.sin(phi), 0 * phi], 1))
    towards = rr.RuledSurface(lines, closed=True).dh_frames("towards_next")[:, :3, 0]
    assert np.any((towards * np.roll(towards, -1, axis=0)).sum(1) < 0)  # the flip is real
    res = rr.refine(lines, "dh", scheme, 4, closed=True)
    assert np.abs(res.lines.direction[:, 2]).max() < 1e-12
    assert np.hypot(*res.lines.point[:, :2].T).max() < 1e-12
    assert np.hypot(*res.striction[:, :2].T).max() < 1e-12


def test_dh_keeps_equally_spaced_hyperboloid_rulings_on_the_quadric():
    a, c = 1.0, 1.5
    u = np.linspace(0, 4, 8)
    pts = np.stack([a * np.cos(u), a * np.sin(u), 0 * u], 1)
    dirs = np.stack([-a * np.sin(u), a * np.cos(u), c + 0 * u], 1)
    for scheme in ("four_point", "chaikin", "six_point"):
        res = rr.refine(rr.Lines.from_point_direction(pts, dirs), "dh", scheme, 4)
        p = res.lines.points_at(np.tile([-2.0, 0.0, 2.0], (len(res.lines), 1)))
        residual = p[..., 0] ** 2 + p[..., 1] ** 2 - (a / c) ** 2 * p[..., 2] ** 2 - a**2
        assert np.abs(residual).max() < 1e-9


def test_combined_moebius_band_closes_with_a_flip():
    u = np.arange(12) * 2 * np.pi / 12
    centre = np.stack([np.cos(u), np.sin(u), 0 * u], 1)
    d = np.stack([np.cos(u / 2) * np.cos(u), np.cos(u / 2) * np.sin(u), np.sin(u / 2)], 1)
    res = rr.refine(rr.Lines.from_point_direction(centre, d), "combined", "chaikin", 3, closed=True)
    assert res.flip and res.closed and len(res.lines) == 96
    assert res.lines.direction[-1] @ res.lines.direction[0] < 0
    # consecutive refined rulings turn smoothly, including across the seam
    l = res.lines.direction
    nxt = np.roll(l, -1, axis=0)
    nxt[-1] *= -1
    assert np.all((l * nxt).sum(1) > np.cos(0.2))


def test_combined_striction_is_computed_once_and_refined():
    u = np.linspace(0, 3, 8)
    lines = rr.Lines.from_point_direction(
        np.stack([0 * u, 0 * u, 0.3 * u], 1), np.stack([np.cos(u), np.sin(u), 0 * u], 1)
    )
    res = rr.refine(lines, "combined", "four_point", 2)
    s0 = rr.RuledSurface(lines).striction_points()
    np.testing.assert_allclose(res.striction, rr.subdivide(s0, "four_point", 2), atol=1e-15)


def test_refine_errors(random_lines):
    with pytest.raises(ValueError, match="algorithm: expected one of"):
        rr.refine(random_lines, "magic")
    with pytest.raises(ValueError, match=r"expected ruledrobot\.Lines"):
        rr.refine(np.zeros((4, 6)))
    with pytest.raises(ValueError, match="needs at least 6"):
        rr.refine(random_lines[:4], "dh", "six_point")
    surf = rr.RuledSurface(random_lines)
    with pytest.raises(ValueError, match="contradicts"):
        rr.refine(surf, closed=True)
