"""The compiled SE(3) geodesic kernel: the numpy path to rounding, its branches, dispatch."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from ruledrobot.geometry import se3

from ..conftest import random_poses

#: Agreement of the compiled kernel with the numpy path, in units of the float64 epsilon
#: per unit of ``1 + |t|`` (and per metre of the poses' translations for the translation
#: column).  Both paths evaluate the same formulas in the same order, but they need not
#: round alike on every CPU: numpy may take its own SIMD ``sin``/``cos``/``arctan2``
#: (AVX-512, ARM SVE) where the kernel calls the C library, and LLVM may vectorise or
#: fuse differently.  Measured here (AMD EPYC, AVX-512): at most 2.3 eps on the rotation
#: block and 1.3 eps per metre on the translation; 64 leaves a factor of 28, while a wrong
#: sign, branch or series term gives errors of 1e-7 and more.
KERNEL_EPS = 64


def assert_same(a: np.ndarray, b: np.ndarray, t: np.ndarray | float, A=None, B=None) -> None:
    """``a`` and ``b`` (n, 4, 4) agree to :data:`KERNEL_EPS` (see there); ``A``, ``B`` the
    inputs, whose translations scale the translation column's bound."""
    a, b = np.asarray(a).reshape(-1, 4, 4), np.asarray(b).reshape(-1, 4, 4)
    tt = 1.0 + np.abs(np.broadcast_to(np.asarray(t, dtype=np.float64), (len(a),)))
    size = np.ones(len(a))
    for P in (A, B):
        if P is not None:
            trans = np.abs(np.asarray(P).reshape(-1, 4, 4)[:, :3, 3]).max(axis=1)
            size = size + np.broadcast_to(trans, (len(a),))
    eps = KERNEL_EPS * np.finfo(np.float64).eps
    d = np.abs(a - b)
    assert np.array_equal(a[:, 3], b[:, 3])  # the last row is written, not computed
    rot = d[:, :3, :3].max(axis=(1, 2)) / (eps * tt)
    trans = d[:, :3, 3].max(axis=1) / (eps * tt * size)
    assert rot.max() <= 1.0 and trans.max() <= 1.0, (rot.max(), trans.max())


def numpy_geodesic(A: np.ndarray, B: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The numpy chunk on (n, 4, 4) pairs, per-pair t (n,): the reference."""
    out = np.empty((len(A), 4, 4))
    se3._geodesic_matrix_chunk(A, B, t, out)
    return out


def kernel_geodesic(A: np.ndarray, B: np.ndarray, t: np.ndarray) -> np.ndarray:
    return se3._geodesic_kernel(A, B, np.asarray(t, dtype=np.float64))


def pose(axis, angle: float, p=(0.3, -0.2, 0.5)) -> np.ndarray:
    T = np.eye(4)
    axis = np.asarray(axis, dtype=np.float64)
    T[:3, :3] = se3.rotation_about_axis(axis / np.linalg.norm(axis), angle)
    T[:3, 3] = p
    return T


def edge_pairs(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Relative motions on every branch: identity, pure translations, tiny rotations
    (the series of sin(t phi)/sin(phi)), rotations near and at pi about each axis and
    about skew axes (each row of Shepperd's method, both signs of w)."""
    rel = [np.eye(4), pose((1, 0, 0), 0.0, (0, 0, 0)), pose((0, 0, 1), 0.0, (1.0, -2.0, 3.0))]
    axes = [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, -2, 0.5), (-0.3, 0.1, 1.0), (1, 1, 1)]
    for ax in axes:
        for angle in (1e-15, 1e-9, 3e-7, 9.99e-7 * 2, 2e-6, 0.3, 2.0):
            rel.append(pose(ax, angle))
            rel.append(pose(ax, -angle))
        for eps in (0.0, 1e-15, 1e-12, 1e-8, 1e-4):
            rel.append(pose(ax, np.pi - eps))
            rel.append(pose(ax, -(np.pi - eps)))
            rel.append(pose(ax, np.pi + eps))
    rel = np.array(rel)
    A = random_poses(rng, len(rel))
    A[:3] = np.eye(4)  # identity bases too
    return A, A @ rel


@pytest.mark.parametrize("t", [0.0, 0.5, 1.0, -0.7, 1.9, 1e-9])
def test_kernel_is_the_numpy_path(rng, t):
    A, B = random_poses(rng, 3000), random_poses(rng, 3000, scale=5.0)
    tt = np.full(len(A), t)
    assert_same(kernel_geodesic(A, B, tt), numpy_geodesic(A, B, tt), tt, A, B)


def test_start_is_the_first_pose_bit_for_bit_on_both_paths(rng):
    """At t = 0 both paths return ``A`` exactly on any CPU: sin(0) = 0 and cos(0) = 1 in
    every libm and SIMD library, so the relative motion is the identity rotation and a zero
    translation exactly, and ``A``'s entries pass through products by 1 and sums with 0."""
    A, B = random_poses(rng, 500), random_poses(rng, 500, scale=5.0)
    EA, EB = edge_pairs(rng)
    for a, b in ((A, B), (EA, EB)):
        zero = np.zeros(len(a))
        assert np.array_equal(kernel_geodesic(a, b, zero), a)
        assert np.array_equal(numpy_geodesic(a, b, zero), a)


def test_kernel_edge_cases_are_the_numpy_path(rng):
    A, B = edge_pairs(rng)
    for t in (0.0, 0.25, 0.5, 1.0, -1.3, 2.0):
        tt = np.full(len(A), t)
        got = kernel_geodesic(A, B, tt)
        assert_same(got, numpy_geodesic(A, B, tt), tt, A, B)
        assert np.all(np.isfinite(got))
    tt = rng.uniform(-2, 3, len(A))
    assert_same(kernel_geodesic(A, B, tt), numpy_geodesic(A, B, tt), tt, A, B)


def test_kernel_edge_cases_are_geodesics(rng):
    """Endpoints, the midpoint's doubled logarithm and the rotation angle <= pi on the
    edge cases (small angles, near and at pi)."""
    A, B = edge_pairs(rng)
    n = len(A)
    np.testing.assert_allclose(kernel_geodesic(A, B, np.zeros(n)), A, atol=1e-12)
    np.testing.assert_allclose(kernel_geodesic(A, B, np.ones(n)), B, atol=1e-12)
    mid = kernel_geodesic(A, B, np.full(n, 0.5))
    full = se3.log(se3.inverse(A) @ B)
    half = se3.log(se3.inverse(A) @ mid)
    angle = np.linalg.norm(full[:, :3], axis=1)
    assert np.all(angle <= np.pi + 1e-12)
    ok = angle < np.pi - 1e-6  # at pi the screw's sense is the quaternion sign's choice
    np.testing.assert_allclose(2 * half[ok], full[ok], atol=1e-9)
    # near pi: exp of the doubled half step is B whichever sense was taken
    np.testing.assert_allclose(A @ se3.exp(2 * half), B, atol=1e-9)


def test_kernel_matches_pytransform3d_near_pi_and_small(rng):
    ptr = pytest.importorskip("pytransform3d.trajectories")
    A, B = edge_pairs(rng)
    angle = np.linalg.norm(se3.log(se3.inverse(A) @ B)[:, :3], axis=1)
    keep = angle < np.pi - 1e-9  # at pi both senses are shortest
    A, B = A[keep], B[keep]
    t = rng.uniform(-0.5, 1.5, len(A))
    dqa = ptr.dual_quaternions_from_transforms(A)
    dqb = ptr.dual_quaternions_from_transforms(B)
    ref = ptr.transforms_from_dual_quaternions(ptr.dual_quaternions_sclerp(dqa, dqb, t))
    np.testing.assert_allclose(kernel_geodesic(A, B, t), ref, atol=1e-9)


unit = arrays(np.float64, 3, elements=st.floats(-1, 1)).filter(lambda v: np.linalg.norm(v) > 0.1)


@settings(max_examples=200, deadline=None)
@given(
    axis=unit,
    angle=st.one_of(st.floats(0.0, 1e-5), st.floats(0.0, np.pi), st.floats(np.pi - 1e-6, np.pi)),
    p=arrays(np.float64, 3, elements=st.floats(-5, 5)),
    t=st.floats(-3, 3),
    seed=st.integers(0, 2**31),
)
def test_kernel_is_the_numpy_path_property(axis, angle, p, t, seed):
    A = random_poses(np.random.default_rng(seed), 1)
    B = A @ pose(axis, angle, p)
    tt = np.array([t])
    assert_same(kernel_geodesic(A, B, tt), numpy_geodesic(A, B, tt), tt, A, B)


def test_public_api_dispatch_gives_the_same_bytes(rng, monkeypatch):
    """geodesic / geodesic_many (broadcasting, scalar and per-pair t) through the kernel
    agree with the numpy path (to :data:`KERNEL_EPS`)."""
    A, B = random_poses(rng, 50), random_poses(rng, 1)[0]
    t = rng.uniform(-1, 2, 50)
    se3.load_kernel()
    assert se3.kernel_loaded() and se3.uses_kernel(1)
    fast = (se3.geodesic(A, B, t), se3.geodesic(A, B, 0.3), se3.geodesic_many(A, B, [0.2, 1.5]))
    fast_one = se3.geodesic(A[0], B, 0.7)
    monkeypatch.setattr(se3, "_kernel", None)
    monkeypatch.setattr(se3, "NUMPY_PAIRS", 10**9)
    assert not se3.uses_kernel(10**6)
    slow = (se3.geodesic(A, B, t), se3.geodesic(A, B, 0.3), se3.geodesic_many(A, B, [0.2, 1.5]))
    assert_same(fast[0], slow[0], t, A, B)
    assert_same(fast[1], slow[1], 0.3, A, B)
    for f, s, tk in zip(fast[2], slow[2], (0.2, 1.5), strict=True):
        assert_same(f, s, tk, A, B)
    assert fast_one.shape == (4, 4)
    assert_same(fast_one, se3.geodesic(A[0], B, 0.7), 0.7, A[:1], B)


def test_small_geodesics_do_not_load_numba():
    """NUMPY_PAIRS pairs run in numpy without importing numba; one more loads the kernel;
    ``import ruledrobot`` loads neither."""
    code = """
import sys
import numpy as np
import ruledrobot
from ruledrobot.geometry import se3
assert "numba" not in sys.modules
A = np.broadcast_to(np.eye(4), (se3.NUMPY_PAIRS + 1, 4, 4))
se3.geodesic(A[:-1], A[:-1], 0.5)
assert "numba" not in sys.modules and not se3.kernel_loaded()
se3.geodesic(A, A, 0.5)
assert se3.kernel_loaded()
print("ok")
"""
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0 and res.stdout.strip() == "ok", res.stderr[-2000:]
