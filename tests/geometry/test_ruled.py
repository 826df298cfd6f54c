"""RuledSurface: striction points (paper 2.4 rules), DH frames and parameters, Sannia frames."""

from __future__ import annotations

import numpy as np
import pytest

import ruledrobot as rr
from ruledrobot.geometry import se3
from ruledrobot.geometry.lines import plucker_transform
from ruledrobot.geometry.ruled import dh_transform

from ..conftest import helical_motion, random_poses


def helicoid(u: np.ndarray, pitch: float) -> rr.Lines:
    pts = np.stack([0 * u, 0 * u, pitch * u], 1)
    return rr.Lines.from_point_direction(pts, np.stack([np.cos(u), np.sin(u), 0 * u], 1))


def test_helicoid_striction_is_axis_and_distribution_parameter_is_pitch():
    u = np.linspace(0, 3, 9)
    surf = rr.RuledSurface(helicoid(u, 0.25))
    s = surf.striction_points()
    np.testing.assert_allclose(s[:, :2], 0, atol=1e-14)
    np.testing.assert_allclose(s[1:-1, 2], 0.25 * u[1:-1], atol=1e-14)
    np.testing.assert_allclose(surf.distribution_parameters(), 0.25, atol=1e-13)
    assert not surf.torsal().any() and not surf.cylindrical().any()


def test_helical_surface_striction_is_a_helix_orbit():
    L0 = rr.Lines.from_point_direction([[1.0, 0.3, 0.0]], [[0.2, 0.7, 0.6]]).plucker[0]
    phi = np.linspace(0, 2, 10)
    surf = rr.RuledSurface(rr.Lines(plucker_transform(helical_motion(phi, 0.3), L0)))
    s = surf.striction_points()[1:-1]
    back = np.einsum(
        "nij,nj->ni",
        se3.inverse(helical_motion(phi[1:-1], 0.3))[:, :3, :3],
        s - helical_motion(phi[1:-1], 0.3)[:, :3, 3],
    )
    np.testing.assert_allclose(back, np.broadcast_to(back[0], back.shape), atol=1e-12)


def test_parallel_pair_uses_outer_pedal_points():
    # rulings 1 and 2 parallel (along y), ruling 0 and 3 skew to them
    pts = [[0, 0, 0], [1, 0, 0], [2, 0, 1], [3, 0, 0]]
    dirs = [[0, 1, 1], [0, 1, 0], [0, 1, 0], [0, 1, -1]]
    surf = rr.RuledSurface(rr.Lines.from_point_direction(pts, dirs))
    cn = surf.common_normals()
    assert cn.parallel.tolist() == [False, True, False]
    left = cn.foot2[0]  # foot on ruling 1 of the normal with ruling 0
    right = cn.foot1[2]  # foot on ruling 2 of the normal with ruling 3
    ref = 0.5 * (left + right)
    np.testing.assert_allclose(cn.foot1[1], [1, ref[1], 0], atol=1e-14)
    np.testing.assert_allclose(cn.foot2[1], [2, ref[1], 1], atol=1e-14)
    s = surf.striction_points()
    np.testing.assert_allclose(s[1], 0.5 * (left + cn.foot1[1]), atol=1e-14)
    assert surf.cylindrical().tolist() == [False, True, False]
    assert np.isinf(surf.distribution_parameters()[1])


def test_cone_rulings_intersect_at_apex():
    u = np.linspace(0, 2, 6)
    apex = np.array([0.5, -1.0, 2.0])
    dirs = np.stack([np.cos(u), np.sin(u), np.ones_like(u)], 1)
    surf = rr.RuledSurface(rr.Lines.from_point_direction(np.broadcast_to(apex, (6, 3)), dirs))
    assert surf.torsal().all()
    for mode in ("average", "intersection"):
        np.testing.assert_allclose(
            surf.striction_points(mode), np.broadcast_to(apex, (6, 3)), atol=1e-12
        )
    np.testing.assert_allclose(surf.distribution_parameters(), 0.0, atol=1e-12)


def test_intersection_mode_takes_the_intersection_point():
    pts = [[0, 0, 0], [0, 0, 0], [1, 0, 3]]
    dirs = [[1, 0, 0], [0, 1, 0], [0, 1, 1]]
    surf = rr.RuledSurface(rr.Lines.from_point_direction(pts, dirs))
    np.testing.assert_allclose(surf.striction_points("intersection")[0], [0, 0, 0], atol=1e-15)
    with pytest.raises(ValueError, match="at_intersection"):
        surf.striction_points("bogus")


def check_dh_frames(surf: rr.RuledSurface) -> np.ndarray:
    T = surf.dh_frames()
    R = T[:, :3, :3]
    np.testing.assert_allclose(
        np.swapaxes(R, 1, 2) @ R, np.broadcast_to(np.eye(3), R.shape), atol=1e-12
    )
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)
    l = surf.lines
    np.testing.assert_allclose(T[:, :3, 2], l.direction, atol=1e-12)
    np.testing.assert_allclose(np.cross(T[:, :3, 3], l.direction), l.moment, atol=1e-12)
    return T


def test_dh_frames_and_parameters_rebuild_the_chain(rng):
    lines = rr.Lines.from_point_direction(rng.normal(size=(7, 3)), rng.normal(size=(7, 3)))
    surf = rr.RuledSurface(lines)
    T = check_dh_frames(surf)
    cn = surf.common_normals()
    # x along the common normal towards the next ruling
    np.testing.assert_allclose(T[:-1, :3, 0], cn.direction, atol=1e-12)
    np.testing.assert_allclose(T[:-1, :3, 3], cn.foot1, atol=1e-12)
    dh = surf.dh_parameters()
    assert dh.shape == (6, 4)
    assert np.all(dh[:, 2] >= 0)
    np.testing.assert_allclose(T[:-1] @ dh_transform(*dh.T), T[1:], atol=1e-12)


def test_dh_closed_with_flip_parameters(rng):
    u = np.arange(9) * np.pi / 9
    pts = np.stack([0 * u, 0 * u, np.sin(2 * u)], 1)  # cylindroid: closes with a flip
    surf = rr.RuledSurface(
        rr.Lines.from_point_direction(pts, np.stack([np.cos(u), np.sin(u), 0 * u], 1)), closed=True
    )
    assert surf.flip
    T = check_dh_frames(surf)
    dh = surf.dh_parameters()
    assert dh.shape == (9, 4)
    nxt = np.roll(T, -1, axis=0)
    nxt[-1] = nxt[-1] @ np.diag([1.0, -1.0, -1.0, 1.0])
    np.testing.assert_allclose(T @ dh_transform(*dh.T), nxt, atol=1e-12)


def test_continuous_frames_share_origins_and_axes(rng):
    u = np.linspace(0, 3, 9)
    pts = np.stack([0 * u, 0 * u, 0.4 * np.sin(2 * u)], 1)  # distribution parameter changes sign
    surf = rr.RuledSurface(
        rr.Lines.from_point_direction(pts, np.stack([np.cos(u), np.sin(u), 0 * u], 1))
    )
    check_dh_frames(surf)
    a, b = surf.dh_frames("towards_next"), surf.dh_frames("continuous")
    np.testing.assert_allclose(a[:, :3, 2:], b[:, :3, 2:], atol=1e-12)
    xs = b[:, :3, 0]
    assert np.all((xs[:-1] * xs[1:]).sum(1) > 0.9)
    np.testing.assert_allclose(np.abs((a[:, :3, 0] * xs).sum(1)), 1.0, atol=1e-12)
    with pytest.raises(ValueError, match="x_axis"):
        surf.dh_frames("sideways")


def test_dh_end_rule_keeps_helical_orbit():
    L0 = rr.Lines.from_point_direction([[1.0, 0.3, 0.0]], [[0.2, 0.7, 0.6]]).plucker[0]
    phi = np.linspace(0, 2, 6)
    H = helical_motion(phi, 0.3)
    surf = rr.RuledSurface(rr.Lines(plucker_transform(H, L0)))
    T = check_dh_frames(surf)
    rel = se3.inverse(H) @ T
    np.testing.assert_allclose(rel, np.broadcast_to(rel[0], rel.shape), atol=1e-12)


def test_two_rulings_use_the_papers_end_rule():
    lines = rr.Lines.from_point_direction([[0, 0, 0], [0, 0, 1]], [[1, 0, 0], [0, 1, 0]])
    T = check_dh_frames(rr.RuledSurface(lines))
    np.testing.assert_allclose(T[1, :3, 3], [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(T[1, :3, 0], [0, 0, 1], atol=1e-15)


def test_sannia_frames(rng):
    u = np.linspace(0, 3, 12)
    surf = rr.RuledSurface(helicoid(u, 0.4))
    S = surf.sannia_frames()
    R = S[:, :3, :3]
    np.testing.assert_allclose(
        np.swapaxes(R, 1, 2) @ R, np.broadcast_to(np.eye(3), R.shape), atol=1e-12
    )
    np.testing.assert_allclose(R[:, :, 0], surf.lines.direction, atol=1e-15)
    # e2 of a helicoid ruling is the tangent of the spherical image: (-sin u, cos u, 0)
    np.testing.assert_allclose(
        R[1:-1, :, 1], np.stack([-np.sin(u), np.cos(u), 0 * u], 1)[1:-1], atol=1e-12
    )
    np.testing.assert_allclose(S[:, :3, 3], surf.striction_points())


def test_frames_are_equivariant(rng):
    lines = rr.Lines.from_point_direction(rng.normal(size=(6, 3)), rng.normal(size=(6, 3)))
    g = random_poses(rng, 1)[0]
    a, b = rr.RuledSurface(lines), rr.RuledSurface(lines.transform(g))
    np.testing.assert_allclose(b.dh_frames(), g @ a.dh_frames(), atol=1e-12)
    np.testing.assert_allclose(b.sannia_frames(), g @ a.sannia_frames(), atol=1e-12)
    np.testing.assert_allclose(b.dh_parameters(), a.dh_parameters(), atol=1e-12)


def test_surface_errors():
    one = rr.Lines.from_point_direction([[0, 0, 0]], [[1, 0, 0]])
    with pytest.raises(ValueError, match="at least 2 rulings"):
        rr.RuledSurface(one)
    two = rr.Lines.from_point_direction([[0, 0, 0], [0, 0, 1]], [[1, 0, 0], [0, 1, 0]])
    with pytest.raises(ValueError, match="closed surface needs at least 3"):
        rr.RuledSurface(two, closed=True)
    with pytest.raises(ValueError, match="flip=True needs closed=True"):
        rr.RuledSurface(two, flip=True)
